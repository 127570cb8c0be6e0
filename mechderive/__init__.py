"""mechderive — derive, verify and simulate the motion of rigid bodies.

The chapter this toolkit covers is "The Motion of Rigid Bodies" (equations
(3.1)–(3.103)); docstrings cite its equation numbers.  Conventions: the body
frame is e_a = R_ab ẽ_b with R(φ, θ, ψ) = R3(ψ) R1(θ) R3(φ) (3.54); SI units or
any consistent set; angles in radians.

``import mechderive`` is light: it imports neither SymPy nor matplotlib, and
derives nothing.  The public names below are loaded on first use.
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

# public name -> module that defines it
_PUBLIC = {
    "MechDeriveError": "mechderive.errors",
    "rotation_matrix": "mechderive.kinematics.euler",
    "euler_rotation": "mechderive.kinematics.euler",
    "angular_velocity_body": "mechderive.kinematics.euler",
    "angular_velocity_space": "mechderive.kinematics.euler",
    "euler_angles_from_matrix": "mechderive.kinematics.euler",
    "to_scipy_rotation": "mechderive.kinematics.conversions",
    "from_scipy_rotation": "mechderive.kinematics.conversions",
    "matrix_to_quaternion": "mechderive.kinematics.conversions",
    "quaternion_to_matrix": "mechderive.kinematics.conversions",
    "path_ordered_exponential": "mechderive.kinematics.path_ordered",
    "naive_exponential": "mechderive.kinematics.path_ordered",
    "inertia_tensor": "mechderive.inertia.tensor",
    "kinetic_energy": "mechderive.inertia.tensor",
    "angular_momentum": "mechderive.inertia.tensor",
    "body_inertia": "mechderive.inertia.bodies",
    "inertia_from_density": "mechderive.inertia.density",
    "parallel_axis": "mechderive.inertia.parallel_axis_theorem",
    "principal_axes": "mechderive.inertia.principal",
    "check_inertia_tensor": "mechderive.inertia.validate",
    "check_principal_moments": "mechderive.inertia.validate",
    "exact_free_top": "mechderive.systems.free_top.exact",
    "integrate_free_top": "mechderive.systems.free_top.integrate",
    "principal_axis_stability": "mechderive.systems.free_top.stability",
    "linearised_eigenvalues": "mechderive.systems.free_top.stability",
    "instability_growth_rate": "mechderive.systems.free_top.stability",
    "exact_heavy_top": "mechderive.systems.heavy_top.exact",
    "integrate_heavy_top": "mechderive.systems.heavy_top.integrate",
    "falling_cat": "mechderive.systems.deformable.cat",
    "DeformableBody": "mechderive.systems.deformable",
    "net_rotation": "mechderive.systems.deformable",
    "run_claims": "mechderive.catalog.registry",
    "System": "mechderive.systems.base",
    "register_system": "mechderive.systems.registry",
    "rigid_body": "mechderive.systems.rigid_body.system",
    "from_lagrangian": "mechderive.systems.lagrangian",
    "load_sweep": "mechderive.sweeps.spec",
    "run_sweep": "mechderive.sweeps.run",
}

__all__ = sorted(_PUBLIC) + ["__version__"]


def __getattr__(name: str) -> Any:
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'mechderive' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return __all__
