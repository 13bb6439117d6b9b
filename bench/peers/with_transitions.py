"""The shared rules with the phase held by a ``transitions`` machine (one ``Machine`` per robot).

The phase checks of the rules read the machine's state, and every phase change
fires a trigger, as an application written on ``transitions`` would.
"""

from __future__ import annotations

from transitions import Machine

from .rules import INACTIVE, RUNNING, WAITING, Rules

__all__ = ["TransitionsServer"]

_STATES = ["inactive", "waiting", "running"]
_PHASE = {"inactive": INACTIVE, "waiting": WAITING, "running": RUNNING}
_TRANSITIONS = [
    {"trigger": "ev_begin", "source": "inactive", "dest": "waiting"},
    {"trigger": "ev_start", "source": "waiting", "dest": "running"},
    {"trigger": "ev_child_end", "source": "running", "dest": "waiting"},
    {"trigger": "ev_finish", "source": "waiting", "dest": "inactive"},
]


class TransitionsServer(Rules):
    """One robot's server; ``self.state`` is the ``transitions`` state name."""

    state: str

    def start_machine(self, initial: str | None) -> None:
        if initial is not None and initial not in _PHASE:
            raise ValueError(f"snapshot.phase = {initial!r}: expected one of {_STATES}")
        self.machine = Machine(
            model=self,
            states=_STATES,
            transitions=_TRANSITIONS,
            initial=initial or "inactive",
            auto_transitions=False,
        )

    def phase(self) -> int:
        return _PHASE[self.state]

    def saved_phase(self) -> str:
        return self.state
