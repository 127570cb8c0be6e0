"""The inertia tensor (section 3.2) and the kinetic energy of a free body (3.29)–(3.30).

Modules, one job each:

- :mod:`.tensor` — point masses: T, I (3.17)–(3.19), L (3.27)–(3.28), derived;
- :mod:`.regions`, :mod:`.density` — continuous bodies by symbolic integration (3.20);
- :mod:`.body` — the BodyInertia record (mass, centre of mass, inertia);
- :mod:`.bodies` — the uniform standard bodies (rod, disc, ring, spheres, cylinder, cuboid, ellipsoid, cone);
- :mod:`.parallel_axis_theorem` — (3.25)–(3.26), derived for general point masses;
- :mod:`.principal` — principal moments and axes (3.21);
- :mod:`.validate` — symmetric, positive (3.22), triangle inequalities;
- :mod:`.free_body` — separation of centre-of-mass and rotational energy (3.30).

Vectors and tensors are in body components; any consistent units.
"""

import importlib
from typing import Any

# name -> submodule; resolved on first use so that importing one light module (e.g. .validate)
# does not import SymPy through the symbolic ones.
_NAMES = {
    "BODIES": "bodies", "body_inertia": "bodies", "body_inertia_symbolic": "bodies",
    "BodyInertia": "body", "inertia_from_density": "density",
    "parallel_axis": "parallel_axis_theorem", "parallel_axis_symbolic": "parallel_axis_theorem",
    "principal_axes": "principal", "principal_axes_symbolic": "principal",
    "Region": "regions", "box": "regions", "solid_of_revolution": "regions",
    "angular_momentum": "tensor", "inertia_tensor": "tensor", "inertia_tensor_symbolic": "tensor",
    "kinetic_energy": "tensor", "point_mass_tensor": "tensor",
    "check_inertia_tensor": "validate", "check_principal_moments": "validate",
}


def __getattr__(name: str) -> Any:
    module = _NAMES.get(name)
    if module is None:
        raise AttributeError(f"module 'mechderive.inertia' has no attribute {name!r}")
    value = getattr(importlib.import_module(f".{module}", __name__), name)
    globals()[name] = value
    return value


__all__ = [
    "BODIES",
    "BodyInertia",
    "Region",
    "angular_momentum",
    "body_inertia",
    "body_inertia_symbolic",
    "box",
    "check_inertia_tensor",
    "check_principal_moments",
    "inertia_from_density",
    "inertia_tensor",
    "inertia_tensor_symbolic",
    "kinetic_energy",
    "parallel_axis",
    "parallel_axis_symbolic",
    "point_mass_tensor",
    "principal_axes",
    "principal_axes_symbolic",
    "solid_of_revolution",
]
