"""The inertia tensor (section 3.2) and the kinetic energy of a free body (3.29)–(3.30).

Modules, one job each:

- :mod:`.tensor` — point masses: T, I (3.17)–(3.19), L (3.27)–(3.28), derived;
- :mod:`.regions`, :mod:`.density` — continuous bodies by symbolic integration (3.20);
- :mod:`.bodies` — the uniform standard bodies (rod, disc, ring, spheres, cylinder, cuboid, ellipsoid, cone);
- :mod:`.parallel_axis` — (3.25)–(3.26), derived for general point masses;
- :mod:`.principal` — principal moments and axes (3.21);
- :mod:`.validate` — symmetric, positive (3.22), triangle inequalities;
- :mod:`.free_body` — separation of centre-of-mass and rotational energy (3.30).

Vectors and tensors are in body components; any consistent units.
"""

from .bodies import BODIES, body_inertia, body_inertia_symbolic
from .body_inertia import BodyInertia
from .density import inertia_from_density
from .parallel_axis import parallel_axis, parallel_axis_symbolic
from .principal import principal_axes, principal_axes_symbolic
from .regions import Region, box, solid_of_revolution
from .tensor import angular_momentum, inertia_tensor, inertia_tensor_symbolic, kinetic_energy, point_mass_tensor
from .validate import check_inertia_tensor, check_principal_moments

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
