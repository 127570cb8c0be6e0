"""No module of the package imports upward, and no import cycle at module level.

The layers, bottom first (a module may import its own layer and those below, never above):

0. ``errors``;
1. the foundations: ``core`` (symbols, simplify, compile, code caches, C builds, code generation,
   the Lagrangian machinery, the check-side symbol table), ``special`` (elliptic functions) and
   ``formulas.parse`` (the whitelist parser) — ``core`` and ``special`` use each other's leaves
   (``core.phase`` the double-double π, ``special`` ``core.validate``), so they share a layer;
2. ``kinematics`` and ``inertia``, derived with the foundations;
3. ``solvers`` (integrators; the generated C comes from ``core.codegen``);
4. ``systems`` (each system, its registry and protocol);
5. the generic layers that ask the registry: ``scenes``, ``derive``, ``formulas``, ``catalog``,
   ``interop``, ``bench``, ``stress``, ``sweeps``;
6. ``cli``; 7. ``__main__`` (and the package's lazily loaded public names).

Issue 13 gives the same order except that it puts ``kinematics`` and ``inertia`` below ``core``
and ``formulas.parse``; they are built on ``core.symbols``, ``core.model``, ``core.validate`` and
the parser (and nothing of ``core`` needs them), so here they sit above.

Every ``import`` and ``from … import`` is scanned, at module level and inside functions (an
import in a function body runs too, only later); those under ``if TYPE_CHECKING:`` are skipped
(never executed).  The scan reads the source (AST) and imports nothing, so it takes ~0.3 s.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

import pytest

from ._package_sources import syntax_tree

PACKAGE = Path(__file__).resolve().parent.parent / "mechderive"
#: the package itself: loaded before any of its modules and importing none at load (its public names
#: are loaded on first use), so ``from .. import __version__`` reaches nothing above
ROOT = "mechderive"

#: module prefix -> layer (the longest matching prefix decides)
LAYERS: dict[str, int] = {
    "mechderive.errors": 0,
    "mechderive.core": 1,
    "mechderive.special": 1,
    "mechderive.formulas.parse": 1,
    "mechderive.kinematics": 2,
    "mechderive.inertia": 2,
    "mechderive.solvers": 3,
    "mechderive.systems": 4,
    "mechderive.scenes": 5,
    "mechderive.sweeps": 5,
    "mechderive.derive": 5,
    "mechderive.formulas": 5,
    "mechderive.catalog": 5,
    "mechderive.interop": 5,
    "mechderive.bench": 5,
    "mechderive.stress": 5,
    "mechderive.cli": 6,
    "mechderive.__main__": 7,
    "mechderive": 7,
}

#: (importing module prefix, imported module) -> why it is allowed for now.  Each is inside a
#: function body (checked below): the import runs only when that function is called.
EXCEPTIONS: dict[tuple[str, str], str] = {}


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _layer(module: str) -> int:
    best = max((p for p in LAYERS if module == p or module.startswith(p + ".")), key=len)
    return LAYERS[best]


def _is_type_checking(node: ast.If) -> bool:
    return "TYPE_CHECKING" in ast.unparse(node.test)


def _imports(path: Path) -> list[tuple[str, int, bool]]:
    """(imported module, line, inside a function) of every executed import of the package in ``path``."""
    module = _module_name(path)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    out: list[tuple[str, int, bool]] = []

    def visit(node: ast.AST, in_function: bool) -> None:
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and _is_type_checking(child):
                for sub in child.orelse:
                    visit(sub, in_function)
                continue
            inner = in_function or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.ImportFrom):
                if child.level:
                    base = package.split(".")
                    base = base[: len(base) - (child.level - 1)]
                    target = ".".join(base + ([child.module] if child.module else []))
                else:
                    target = child.module or ""
                if target == "mechderive" or target.startswith("mechderive."):
                    # "from . import euler": the names may be modules; take the deepest that exists
                    for alias in child.names:
                        sub = f"{target}.{alias.name}"
                        as_module = PACKAGE.parent / Path(*sub.split("."))
                        known = as_module.with_suffix(".py").exists() or (as_module / "__init__.py").exists()
                        out.append((sub if known else target, child.lineno, inner))
            elif isinstance(child, ast.Import):
                out.extend((a.name, child.lineno, inner) for a in child.names
                           if a.name == "mechderive" or a.name.startswith("mechderive."))
            visit(child, inner)

    visit(syntax_tree(path), False)
    return out


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


@functools.cache
def _all_imports() -> dict[str, list[tuple[str, int, bool]]]:
    # parsed on first use, not at collection: every xdist worker collects this file, one runs its tests
    return {name: _imports(path) for name, path in MODULES.items()}


def _allowed(importer: str, imported: str, in_function: bool) -> bool:
    return in_function and any((importer == a or importer.startswith(a + ".")) and imported == b
                               for a, b in EXCEPTIONS)


def test_every_module_has_a_layer():
    assert all(_layer(m) is not None for m in MODULES)
    assert len(MODULES) > 100   # the scan sees the package


def test_no_import_goes_upward():
    upward = [f"{m} (line {line}{', in a function' if f else ''}) imports {target}: layer {_layer(m)} -> "
              f"{_layer(target)}"
              for m, found in _all_imports().items() for target, line, f in found
              if target != ROOT and _layer(target) > _layer(m) and not _allowed(m, target, f)]
    assert not upward, "upward imports:\n" + "\n".join(upward)


def test_the_exceptions_name_modules_that_exist():
    """Each exception is about modules of the package, the imported one in a higher layer."""
    for (a, b), reason in EXCEPTIONS.items():
        assert a in MODULES and b in MODULES and _layer(b) > _layer(a) and reason


def _module_level_graph() -> dict[str, set[str]]:
    graph: dict[str, set[str]] = {m: set() for m in MODULES}
    for m, found in _all_imports().items():
        for target, _, in_function in found:
            if in_function:
                continue
            # importing a.b.c runs a/__init__ and a/b/__init__ first
            parts = target.split(".")
            for k in range(1, len(parts) + 1):
                t = ".".join(parts[:k])
                if t in MODULES and t != m:
                    graph[m].add(t)
    return graph


def test_no_import_cycle_at_module_level():
    graph = _module_level_graph()
    # a package's __init__ importing its own submodules, which import the package back, is how
    # every package works (the __init__ is already in sys.modules): only cycles through two
    # or more modules of which none is an ancestor package of the others count
    def ancestor(a: str, b: str) -> bool:
        return b.startswith(a + ".")

    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    cycles: list[list[str]] = []
    counter = [0]

    def connect(v: str) -> None:  # Tarjan's strongly connected components (iterative depth is small here)
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph[v]:
            if ancestor(w, v):
                continue
            if w not in index:
                connect(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                cycles.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            connect(v)
    assert not cycles, "module-level import cycles: " + "; ".join(" <-> ".join(c) for c in cycles)


@pytest.mark.parametrize("path", ["mechderive/solvers/dop853_c.py", "mechderive/solvers/kick_drift_c.py"])
def test_the_solvers_generate_code_from_below(path):
    """The loop solvers -> derive.formats -> derive.catalog -> systems -> solvers is gone."""
    found = _all_imports()[_module_name(PACKAGE.parent / path)]
    assert ("mechderive.core.codegen", ) in {(t,) for t, _, _ in found}
    assert not any(t.startswith("mechderive.derive") for t, _, _ in found)
