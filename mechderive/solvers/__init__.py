"""Reusable numerical pieces: quaternion kinematics, symmetric compositions, the Lie–Poisson splitting.

* :mod:`.quaternion` — q̇ = ½ q ⊗ (0, ω) for the quaternion of A = Rᵀ (derived from Ṙ = hat(ω) R, 3.11);
* :mod:`.composition` — triple-jump, Suzuki and Yoshida weights raising a symmetric order-2 step to 4 and 6;
* :mod:`.lie_poisson` — exact axis sub-flows of the free rigid body and their composition (one body or M).

The one integration driver for every system is :mod:`.driver` (a :class:`~.driver.Term`, DOP853 compiled to C
or SciPy, the splittings, the tolerance controller, one :class:`~.driver.Trajectory`); the systems' entry
points (:func:`mechderive.systems.free_top.integrate.integrate_free_top`, ...) run through it.
"""

from __future__ import annotations

from .composition import suzuki_fractal, triple_jump, yoshida6
from .quaternion import quaternion_multiply, quaternion_rate

__all__ = ["quaternion_multiply", "quaternion_rate", "triple_jump", "suzuki_fractal", "yoshida6"]
