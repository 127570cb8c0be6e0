"""Lazily derived symbolic quantities, each derived once and logged.

A *model* is the symbolic side of a physical system: a set of quantities derived
by SymPy from first principles.  Each quantity is a method decorated with
:func:`derived`; it is computed on first access, cached on the instance, and its
name appended to :attr:`SymbolicModel.derived`.  Quantities that need others
simply access them, so the log lists exactly the derivations a request caused,
in the order they ran — the lazy-evaluation tests read it.

Models hold no numbers: parameters stay symbols, so one model instance per
system serves every numeric case in the process (see ``model()`` functions in the
system modules).  Compiled NumPy functions are obtained through
:meth:`SymbolicModel.compile`, which goes through :mod:`mechderive.core.compile`'s
cache and logs the name in :attr:`SymbolicModel.compiled`.
"""

from __future__ import annotations

import contextlib
import time
from typing import Any, Callable, Sequence, TypeVar

from . import compile as _compile

__all__ = ["SymbolicModel", "derived", "deriving", "derivation_log", "derivation_seconds"]

#: ("Model.quantity", seconds) for every derivation in this process, in completion order.
_DERIVATION_LOG: list[tuple[str, float]] = []
_DEPTH = [0]  # nesting of derivations in progress
_TOP_LEVEL_SECONDS = [0.0]  # wall time spent in outermost derivations (no double counting)


def derivation_seconds() -> float:
    """Total wall time spent deriving in this process (nested derivations counted once)."""
    return _TOP_LEVEL_SECONDS[0]


@contextlib.contextmanager
def deriving() -> Any:
    """Count the block's wall time as deriving, as an outermost derivation's (nested ones inside count once): the
    work that builds what is then compiled — the imports it needs among it, SymPy's own on a cold start (0.4-1 s),
    which was reported as the stage (solving, compiling) that happened to import it first."""
    if _DEPTH[0]:
        yield
        return
    start = time.perf_counter()
    _DEPTH[0] += 1
    try:
        yield
    finally:
        _DEPTH[0] -= 1
        _TOP_LEVEL_SECONDS[0] += time.perf_counter() - start


def derivation_log() -> list[tuple[str, float]]:
    """("Model.quantity", seconds) for every derivation performed in this process, in order.

    Seconds are inclusive of the quantities a derivation needed first (each logged too).
    """
    return list(_DERIVATION_LOG)

T = TypeVar("T")


class derived:  # noqa: N801 - used as a decorator, like functools.cached_property
    """Mark a method of a :class:`SymbolicModel` as a lazily derived quantity.

    The method runs once per model instance, on first attribute access; the result
    is cached and the quantity's name logged in ``model.derived``.
    """

    def __init__(self, func: Callable[[Any], T]):
        self.func = func
        self.name = func.__name__
        self.__doc__ = func.__doc__

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name

    def __get__(self, instance: "SymbolicModel | None", owner: type | None = None) -> Any:
        if instance is None:
            return self
        cache = instance._derived_cache
        if self.name not in cache:
            start = time.perf_counter()
            _DEPTH[0] += 1
            try:
                value = self.func(instance)
            finally:
                _DEPTH[0] -= 1
            cache[self.name] = value
            elapsed = time.perf_counter() - start
            if _DEPTH[0] == 0:
                _TOP_LEVEL_SECONDS[0] += elapsed
            instance.derived.append(self.name)
            instance.timings[self.name] = elapsed
            _DERIVATION_LOG.append((f"{type(instance).__name__}.{self.name}", elapsed))
        return cache[self.name]


class SymbolicModel:
    """Base class of the symbolic models: a log of derivations and compilations.

    Attributes
    ----------
    derived : list[str]
        Names of the quantities derived by this instance, in order.
    compiled : list[str]
        Names of the functions this instance obtained from the compile layer.
    timings : dict[str, float]
        Seconds spent in each derivation (excluding the ones it triggered first? no:
        inclusive of quantities it needed, which are logged separately as well).
    """

    def __init__(self) -> None:
        self._derived_cache: dict[str, Any] = {}
        self._compiled_cache: dict[str, Callable[..., Any]] = {}
        self.derived: list[str] = []
        self.compiled: list[str] = []
        self.timings: dict[str, float] = {}

    @classmethod
    def quantities(cls) -> list[str]:
        """Names of every quantity this model can derive."""
        return [name for name in dir(cls) if isinstance(getattr(cls, name, None), derived)]

    def is_derived(self, name: str) -> bool:
        """Whether ``name`` has been derived by this instance."""
        return name in self._derived_cache

    def compile(self, name: str, exprs: Any, args: Sequence[Any]) -> Callable[..., Any]:
        """Compile ``exprs`` as a function of ``args`` (once per model and name).

        See :func:`mechderive.core.compile.compile_expressions` for the calling
        convention of the result.
        """
        if name not in self._compiled_cache:
            self._compiled_cache[name] = _compile.compile_expressions(exprs, args, name=name)
            self.compiled.append(name)
        return self._compiled_cache[name]

    def report(self) -> dict[str, Any]:
        """What this model has done so far: derivations, compilations and their times."""
        return {"derived": list(self.derived), "compiled": list(self.compiled), "timings": dict(self.timings)}
