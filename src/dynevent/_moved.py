"""Names that moved: the old import path keeps working for one release, with a DeprecationWarning.

Judging moved below the command line (``dynevent.tools.check.*`` to :mod:`dynevent.conformance.judge`
and :mod:`dynevent.bags`, ``dynevent.tools.explain`` and ``probe_cases`` to
:mod:`dynevent.conformance`, ``dynevent.tools.serve_config`` to :mod:`dynevent.sim`); CHANGELOG.md
says when the old paths go.
"""

from __future__ import annotations

import importlib
import sys
import warnings
from collections.abc import Callable, Mapping
from types import ModuleType
from typing import Any

__all__ = ["MODULES", "moved_attribute", "moved_module"]

#: Each module that moved, at its old path, and where it is now.
MODULES = {
    "dynevent.tools.check.trace": "dynevent.conformance.judge.trace",
    "dynevent.tools.check.observer": "dynevent.conformance.judge.observer",
    "dynevent.tools.check.abduction": "dynevent.conformance.judge.abduction",
    "dynevent.tools.check.partial": "dynevent.conformance.judge.partial",
    "dynevent.tools.check.bags": "dynevent.bags.reader",
    "dynevent.tools.explain": "dynevent.conformance.explain",
    "dynevent.tools.probe_cases": "dynevent.conformance.probe_cases",
    "dynevent.tools.serve_config": "dynevent.sim.config",
}


def _warn(old: str, new: str) -> None:
    warnings.warn(
        f"{old} has moved to {new}; the old name goes in the next release", DeprecationWarning, stacklevel=3
    )


def moved_module(old: str) -> None:
    """Make the module ``old`` (being imported) the module it moved to, saying so."""
    new = MODULES[old]
    _warn(old, new)
    sys.modules[old] = importlib.import_module(new)


def moved_attribute(module: str, moved: Mapping[str, ModuleType]) -> Callable[[str], Any]:
    """A module ``__getattr__`` that finds each name of ``moved`` in its new module, saying so."""

    def __getattr__(name: str) -> Any:
        home = moved.get(name)
        if home is None:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        _warn(f"{module}.{name}", f"{home.__name__}.{name}")
        return getattr(home, name)

    return __getattr__
