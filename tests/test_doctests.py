"""The examples in docstrings and in the README run and print what they claim."""

from __future__ import annotations

import doctest
import importlib
import pkgutil

import pytest

import mechderive

from .conftest import ROOT

MODULES = sorted(
    m.name for m in pkgutil.walk_packages(mechderive.__path__, "mechderive.")
    if not m.name.endswith("__main__")
)


@pytest.mark.parametrize("name", MODULES)
def test_module_doctests(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.NORMALIZE_WHITESPACE | doctest.ELLIPSIS)
    assert result.failed == 0


def test_readme_examples():
    result = doctest.testfile(str(ROOT / "README.md"), module_relative=False,
                              optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0
