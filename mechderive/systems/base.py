"""The ``System`` protocol: what a physical system tells the scenes, ``derive``, ``check`` and plots.

A system is one object.  The generic layers (scene schema, planner, units, ``derive``, ``check``,
``interop``, plots, the CLI) ask it — through :mod:`mechderive.systems.registry` — and never name a
system.  A system carries:

* its scene schema: the ``[parameters]`` and ``[initial]`` keys (:class:`Key`: name, unit, meaning,
  required or default) and the checks of their values (:meth:`System.check_parameters`,
  :meth:`System.check_initial`), plus any further top-level keys or tables it reads
  (:attr:`System.extra_keys`, e.g. a ``lagrangian`` system's ``coordinates`` and ``lagrangian``);
* the quantities it can output (:class:`Quantity`: name, unit, meaning) and, in
  :meth:`System.solve`, the laziness of each (a solve derives, compiles and evaluates only what the
  requested quantities need);
* its solvers: ``methods`` lists ``"exact"`` first where a closed form exists, ``"integrate"``
  always; :meth:`System.solve` returns the columns, a report and the solved object, raising
  :class:`OutOfReach` where a closed form cannot follow a motion (``method = "auto"`` then
  integrates);
* the conserved quantities' drift along a solution (:meth:`System.drift`);
* its derived formulas for ``derive`` (:meth:`System.derivations`), its symbols for ``check``
  (:meth:`System.check_system`), optionally a plot (:meth:`System.plot`) and a default scene
  (:meth:`System.example_scene`).

A *family* of systems — ``rigid_body``, ``lagrangian`` — is one registered object whose
:meth:`System.configure` builds the concrete system from the scene's own definition (its
``extra_keys``); a built-in system returns itself.

Adding a system is one package under ``mechderive/systems/`` defining a subclass of
:class:`System`, and one registration (:func:`mechderive.systems.registry.register`, or one line in
the registry's built-in table for a system shipped with the package).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, ClassVar, Mapping, NamedTuple

from ..errors import InvalidInputError

if TYPE_CHECKING:  # pragma: no cover
    import numpy as np

    from ..core.drift import Drift
    from ..scenes.schema import Scene
    from .scaling import Scaled

__all__ = ["BatchSummary", "Key", "Quantity", "Solved", "OutOfReach", "System", "Derivation", "Derivations"]


@dataclass(frozen=True)
class Key:
    """One scene key of ``[parameters]`` or ``[initial]``.

    ``size`` is 0 for a number, n for a list of n numbers (``omega = [w1, w2, w3]``); ``default``
    is used when the key is absent and ``required`` is False (None: absent stays absent).
    ``scales_as`` says how the key changes when a scene is solved in units of its own motion
    (:mod:`mechderive.systems.scaling`): ``"angle"``, ``"rate"``, ``"moment"``, ``"time"``, or ``""``
    (not scaled).
    """

    name: str
    unit: str
    meaning: str
    required: bool = True
    size: int = 0
    default: Any = None
    scales_as: str = ""


@dataclass(frozen=True)
class Quantity:
    """One output column: its name, unit (SI; ``"rad"``, ``"rad/s"``, ``"1"``) and a one-line meaning."""

    name: str
    unit: str
    meaning: str
    scales_as: str = ""


class Solved(NamedTuple):
    """What :meth:`System.solve` returns: the requested columns (in the scene's order), the report's
    ``details`` (must hold ``error_estimate``: a float measured on the run, or None; may hold ``note``: which
    method was used and why, moved to the report's note) and the solved object (a closed-form solution or a
    trajectory)."""

    columns: dict
    info: dict
    solution: Any


class BatchSummary(NamedTuple):
    """What :meth:`System.summarize_batch` returns for N points (a sweep's chunk).

    ``values[name]``: a float64 array (numeric quantities) or an object array of str (a class), N
    long; ``errors[name]``: each point's measured estimate (float64); ``fallback``: a bool array,
    True where the batch did not answer (a point refused, ill-conditioned, a quantity that does not
    apply or is not a plain number): the sweep computes those points one by one through the planner,
    which gives the value, the estimate or the reason.  Values at fallback points are ignored.
    ``reasons[name]`` (optional): an object array, a string where the quantity does not apply to an
    answered point (its value is then None, as :meth:`System.summarize` says it), None elsewhere.
    """

    values: dict
    errors: dict
    fallback: Any
    reasons: dict = {}


class OutOfReach(InvalidInputError):
    """A closed form cannot follow this motion (the message says why); ``method = "auto"`` integrates instead."""


@dataclass(frozen=True)
class Derivation:
    """One quantity ``derive`` can print: its name, a one-line meaning, the chapter's equation (or ""),
    and ``build(options)`` returning the SymPy expression, matrix or equation list.

    ``options`` is :class:`mechderive.derive.options.Options` (``sequence``, ``frame``, ``shape``,
    ``pivot``, ``moments``, ``values``, ``label(option)``, ``body_parameters(default_pivot=)``); a
    build that takes none ignores it.  The optional fields:

    * ``lhs`` — the left-hand side printed before the value: a callable returning a SymPy object,
      the string ``"= 0"`` for "value = 0", or None (the value alone);
    * ``default`` — printed when no quantity is named (if none of a system's is, all are);
    * ``options`` — the options besides ``values`` that ``build`` reads (``"sequence"``,
      ``"shape"``, ``"moments"``; a pivot goes with a shape); others given are refused;
    * ``substitute(options)`` — {symbol: value} the options put into every value of the system
      (a shape's derived moments of inertia), or None.
    """

    name: str
    meaning: str
    equation: str
    build: Callable[[Any], Any]
    lhs: Any = None
    default: bool = False
    options: frozenset = frozenset()
    substitute: Callable[[Any], Mapping] | None = None


class Derivations(tuple):
    """A system's derivations (a tuple of :class:`Derivation`) with the title ``derive`` prints above
    them, ``summary`` (the system's own :attr:`System.summary` where empty)."""

    summary: str

    def __new__(cls, items: Any = (), summary: str = "") -> "Derivations":
        self = super().__new__(cls, items)
        self.summary = summary
        return self


class System:
    """Base class of every system; a subclass sets the class attributes and overrides the methods.

    The defaults describe a system with no parameters, no initial values and no quantities; the
    methods a system must provide raise :class:`NotImplementedError`-like :class:`InvalidInputError`
    naming the system, so a half-built system fails loudly, never silently.
    """

    #: the scene's ``system = "..."`` value
    name: ClassVar[str] = ""
    #: one line: what the system is (``mechderive scenes --systems``)
    summary: ClassVar[str] = ""
    #: the chapter's section(s), e.g. "3.6"; "" for a user system
    section: ClassVar[str] = ""
    parameters: tuple[Key, ...] = ()
    initial: tuple[Key, ...] = ()
    #: True where ``[parameters]`` takes names the system checks itself (the falling cat's)
    open_parameters: bool = False
    #: further top-level scene keys and tables the system reads (``configure`` gets them)
    extra_keys: ClassVar[tuple[str, ...]] = ()
    quantities: tuple[Quantity, ...] = ()
    #: solvers, ``"exact"`` first where a closed form exists
    methods: tuple[str, ...] = ("integrate",)
    #: peak bytes a solve needs per output sample (the schema's memory guard)
    bytes_per_sample: int = 600
    #: whether :meth:`solve` takes any increasing output times ``t`` (False: only ``samples`` equally spaced on
    #: [0, t_end], a motion defined over its own duration such as the falling cat's; ``[time] t_start`` and
    #: ``times`` are then refused)
    free_times: ClassVar[bool] = True
    #: the quantities :meth:`plot` draws from (``mechderive run --plot`` solves them too)
    plot_quantities: tuple[str, ...] = ()
    #: the quantities :meth:`motion_geometry` draws from (``mechderive run --animate`` solves them too)
    animation_quantities: tuple[str, ...] = ()
    #: the per-motion quantities a scene may ask for in ``[output] summary = [...]`` (turning angles,
    #: periods, invariants' values), each with its unit and meaning; :meth:`summarize` computes them
    summaries: tuple[Quantity, ...] = ()
    #: a sweep's points per chunk where :meth:`summarize_batch` answers (a closed form's NumPy batch: 10⁴, a
    #: few ms for the chunk; a system that integrates, each point milliseconds of C, sets fewer)
    batch_chunk: ClassVar[int] = 10_000

    # --- the scene schema -------------------------------------------------------------------------

    def configure(self, definition: Mapping[str, Any]) -> "System":
        """The concrete system a scene defines with the keys of :attr:`extra_keys` (``definition``);
        a built-in system has none and returns itself."""
        if definition:
            raise InvalidInputError(f"system {self.name!r} takes no keys {', '.join(sorted(definition))}")
        return self

    def quantity_names(self) -> tuple[str, ...]:
        return tuple(q.name for q in self.quantities)

    def check_parameters(self, given: Mapping[str, Any], *, strict: bool = True) -> dict[str, Any]:
        """The ``[parameters]`` values, checked (numbers finite, bodies physical unless ``strict`` is
        False); raises :class:`InvalidInputError` naming the key, what it is and what is allowed."""
        return dict(given)

    def check_initial(self, given: Mapping[str, Any], parameters: Mapping[str, Any]) -> dict[str, Any]:
        """The ``[initial]`` values, checked, with defaults filled in."""
        return dict(given)

    def waived(self, parameters: Mapping[str, Any]) -> list[str]:
        """The physical conditions a ``strict = false`` scene's parameters break (empty if none)."""
        return []

    # --- solving --------------------------------------------------------------------------------

    def scale(self, scene: "Scene") -> "Scaled":
        """The scene in units of its own motion (exact powers of two); the default keeps the scene's units."""
        from .scaling import Scaled

        return Scaled(scene, scene)

    def solve(self, scene: "Scene", method: str, t: "np.ndarray") -> Solved:
        """Solve ``scene`` by ``method`` (one of :attr:`methods`) at the times ``t``, computing only
        what ``scene.quantities`` need."""
        raise InvalidInputError(f"system {self.name!r} has no solver")

    def drift(self, scene: "Scene", solved: Solved, t: "np.ndarray") -> dict[str, "Drift"]:
        """The drift of each conserved quantity along the solution, each against a scale of the motion."""
        return {}

    # --- per-motion quantities ------------------------------------------------------------------

    def summary_names(self) -> tuple[str, ...]:
        return tuple(q.name for q in self.summaries)

    def summarize(self, scene: "Scene", solved: Solved, t: "np.ndarray",
                  names: tuple[str, ...]) -> dict[str, tuple[Any, float | None]]:
        """The per-motion quantities ``names`` (each one of :attr:`summaries`) of the solved motion.

        Returns {name: (value, error estimate)}, in the order of ``names``.  A value is a float, a
        string (a motion's class), a bool, or a dict of those (``steady``: its kind and rates; a free
        top's ``stability`` per axis); None where the quantity does not apply to this motion (a
        ``minimum_spin`` of a top that is not sleeping), with the reason as a string in its place
        of the estimate.  The estimate is measured (the closed form's own residual or conditioning,
        the spread of the trajectory's measurements), never a constant; None where none can be
        measured.  Computed from the closed form where the system has one, else measured on the
        trajectory (``solved.solution``); ``scene``, ``solved`` and ``t`` are in the solver's units
        (the planner converts each value back by its :attr:`Quantity.scales_as`).
        """
        if names:
            raise InvalidInputError(f"system {self.name!r} has no per-motion quantities "
                                    f"(asked for {', '.join(names)})")
        return {}

    def summarize_batch(self, parameters: Mapping[str, "np.ndarray"], initial: Mapping[str, "np.ndarray"],
                        names: tuple[str, ...], *, strict: bool = True, scene: Any = None) -> BatchSummary | None:
        """The per-motion quantities ``names`` of N motions at once (a sweep's chunk), or None.

        ``parameters`` and ``initial`` map the scene's keys (SI, as :class:`~mechderive.scenes.schema.Scene`
        holds them after checking) to arrays of N values (a vector key such as the free top's ``omega``
        to an (N, 3) array).  A system with a closed form vectorises its setup here; every value it
        answers must equal :meth:`summarize`'s for the same point to 1e-12 relative, and each point it
        cannot answer so is marked ``fallback``.  ``scene``: the sweep's checked scene (its ``[time]``,
        ``rtol``, ``method``, quantities), which a system that integrates needs
        (:mod:`mechderive.systems.batch_points`: its points integrated together, each point's summaries
        those of its single run); a system written without this keyword is called without it.  None (the
        default): the sweep runs every point through the planner.
        """
        return None

    def period(self, scene: "Scene") -> float | None:
        """The period (s) of the scene's motion, known before solving — the heavy top's nutation period,
        the free top's polhode period — for ``[time] samples_per_period``; None where the system cannot
        know it in advance."""
        return None

    # --- derive, check, plot ----------------------------------------------------------------------

    def derivations(self) -> tuple[Derivation, ...]:
        """What ``mechderive derive`` can print for this system (a tuple, or :class:`Derivations`)."""
        return ()

    def check_system(self) -> Any:
        """The :class:`mechderive.formulas.systems.System` that ``mechderive check`` uses, or None.

        By default, that of :meth:`lagrangian_model` where the system offers one
        (:func:`mechderive.core.check_system.from_lagrangian_model`): q, q_dot, q_ddot on a motion,
        the parameters, ``Lagrangian``, ``energy`` and ``p_<q>``.
        """
        model = self.lagrangian_model()
        if model is None:
            return None
        from ..core.check_system import from_lagrangian_model

        return from_lagrangian_model(self.name, self.summary, *model)

    def parameter_values(self, parameters: Mapping[str, Any]) -> dict[str, float]:
        """A scene's checked ``[parameters]`` as {symbol name: number} for the derived equations: the
        numbers as they are; a system whose scene keys are lists (``center_of_mass``) names their entries."""
        return {k: v for k, v in parameters.items() if isinstance(v, (int, float)) and not isinstance(v, bool)}

    def lagrangian_model(self) -> tuple | None:
        """(L, coordinates, velocities, parameter symbols) for :mod:`mechderive.core.linearize`, or None.

        L is a SymPy expression in the plain symbols ``coordinates`` (q) and ``velocities`` (q̇, same
        order) and the parameter symbols; a system given by a Lagrangian returns it, so that
        ``derive … linearization --at …`` can linearize it about an equilibrium or a steady motion.
        """
        return None

    def first_order_model(self) -> tuple | None:
        """(rhs, state, parameter symbols) of ẋ = rhs(x) for :mod:`mechderive.core.linearize`, or None.

        Used when :meth:`lagrangian_model` is None (Euler's equations (3.33) of the free top: the
        state ω, the linearization about a steady rotation).
        """
        return None

    def plot(self, result: Any, figure: Any) -> bool:
        """Draw ``result`` (a :class:`~mechderive.scenes.planner.RunResult`) on ``figure``; False where the
        system has no picture of its own (the generic plot of the columns against t is used)."""
        return False

    def motion_geometry(self, result: Any) -> Any:
        """What ``mechderive run --animate`` draws of ``result`` (a
        :class:`~mechderive.scenes.planner.RunResult`): a
        :class:`mechderive.systems.figures.MotionGeometry` (the body's orientation, shape and
        moments, L and ω, the traces), or None where the system has no body to draw."""
        return None

    def example_scene(self) -> str:
        """A complete scene file (TOML) of this system: the default of ``mechderive run``'s built-ins."""
        return ""

    # --- systems from a program -----------------------------------------------------------------

    @classmethod
    def from_lagrangian(cls, lagrangian: Any, coordinates: Any, parameters: Any = (),
                        name: str | None = None) -> "System":
        """The system of a Lagrangian given by a program (SymPy expressions, or text read by the whitelist
        parser): see :func:`mechderive.systems.lagrangian.system.from_lagrangian`."""
        from .lagrangian.system import from_lagrangian

        return from_lagrangian(lagrangian, coordinates, parameters, name)

    def builtin_scenes(self) -> tuple[tuple[str, str, str], ...]:
        """The named ready-made scenes of this system, ``(name, one-line description, TOML text)``, that
        ``mechderive scenes`` lists and ``mechderive run NAME`` runs; none by default."""
        return ()

    def __repr__(self) -> str:
        return f"<system {self.name!r}>"
