"""The shared rules with the phase held by a ``python-statemachine`` machine.

The phase checks of the rules read the machine's current state, and every
phase change sends an event, as an application written on
``python-statemachine`` would.
"""

from __future__ import annotations

from statemachine import State, StateMachine

from .rules import INACTIVE, RUNNING, WAITING, Rules

__all__ = ["StatemachineServer"]

_PHASE = {"inactive": INACTIVE, "waiting": WAITING, "running": RUNNING}


class _Phases(StateMachine):
    inactive = State(initial=True)
    waiting = State()
    running = State()

    ev_begin = inactive.to(waiting)
    ev_start = waiting.to(running)
    ev_child_end = running.to(waiting)
    ev_finish = waiting.to(inactive)


class StatemachineServer(Rules):
    """One robot's server; ``self.machine`` holds the phase."""

    def start_machine(self, initial: str | None) -> None:
        if initial is not None and initial not in _PHASE:
            raise ValueError(f"snapshot.phase = {initial!r}: expected one of {sorted(_PHASE)}")
        self.machine = _Phases(start_value=initial)

    def phase(self) -> int:
        return _PHASE[self.machine.current_state_value]

    def ev_begin(self) -> None:
        self.machine.ev_begin()

    def ev_start(self) -> None:
        self.machine.ev_start()

    def ev_child_end(self) -> None:
        self.machine.ev_child_end()

    def ev_finish(self) -> None:
        self.machine.ev_finish()

    def saved_phase(self) -> str:
        return str(self.machine.current_state_value)
