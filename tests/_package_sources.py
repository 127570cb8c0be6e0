"""The package's syntax trees, parsed once per test process.

The layering scan (test_layers), the no-built-in-raise scan (test_package) and the no-eval scan (security/test_injection)
each walk every module of the package; parsing its ~50,000 lines takes ~1 s, so they share the trees (and one xdist
group, tests/conftest.py).  The trees are read, never changed, by the scans.
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path


@functools.cache
def syntax_tree(path: Path) -> ast.Module:
    """``path`` parsed, with its name in the tree's error messages (cached per path for the process)."""
    return ast.parse(path.read_text(encoding="utf-8"), str(path))
