"""The same-outputs floor: dynevent's work in plain tuples and dicts, no library.

The rules of :mod:`bench.peers.rules` with nothing more: the phase is read from
the data tuple (as dynevent reads it from its state), and the phase moves do
nothing.  It checks every input, builds every output whole and replaces its
state at every step, as dynevent does, so the ratio dynevent/tuples is the cost
of dynevent's frozen, checked classes over the same work in builtins.
"""

from __future__ import annotations

from .rules import ACTIVE, INACTIVE, RUNNING, RUNNING_GOAL, WAITING, Rules

__all__ = ["TupleServer"]


class TupleServer(Rules):
    """One robot's server: a data tuple, and the phase read from it."""

    __slots__ = ("categories", "data", "stubborn_minimum")

    def phase(self) -> int:
        data = self.data
        if not data[ACTIVE]:
            return INACTIVE
        return WAITING if data[RUNNING_GOAL] is None else RUNNING

    def ev_begin(self) -> None:
        pass

    def ev_start(self) -> None:
        pass

    def ev_child_end(self) -> None:
        pass

    def ev_finish(self) -> None:
        pass
