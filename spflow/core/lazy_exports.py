"""Package attributes imported on first use (PEP 562), so that importing a package does not import what it exports.

``import spflow`` and the CLI's cheap verbs (``spflow list``, ``spflow status``) must not pay for numba, SciPy's
optimisers, pymoo, GPy, chaospy, SALib, ArviZ or matplotlib; a package whose ``__init__`` re-exports names from such
modules declares them here instead::

    __getattr__, __dir__ = lazy_exports(__name__, {"make_coreflood": ".twin", ...})
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping
from typing import Any

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: Mapping[str, str]) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """Module ``__getattr__`` and ``__dir__`` for ``package`` serving ``exports`` (public name -> the module defining
    it, absolute or relative to ``package``; a name mapped to ``""`` is the sub-module ``package.name`` itself). Each
    name is imported once, on first access, and then kept in the package's namespace."""

    def __getattr__(name: str) -> Any:
        if name not in exports:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        where = exports[name]
        if where:
            value = getattr(importlib.import_module(where, package), name)
        else:
            value = importlib.import_module(f"{package}.{name}")
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__
