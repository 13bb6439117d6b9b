"""The shared rules with the phase held by a ``python-statemachine`` machine.

The phase checks of the rules read the machine's current state, and every
phase change sends an event, as an application written on
``python-statemachine`` would.
"""

from __future__ import annotations

import json
from typing import Any

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

    def __init__(
        self,
        fleet: str,
        robot: str,
        categories: frozenset[str],
        stubborn_minimum: float = 2.0,
        initial: str | None = None,
    ) -> None:
        self.setup(fleet, robot, categories, stubborn_minimum)
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

    def data(self) -> dict[str, Any]:
        """The robot's data and machine state as plain JSON values."""
        data = self.dump()
        data["phase"] = self.machine.current_state_value
        return data

    @classmethod
    def from_data(
        cls, data: dict[str, Any], categories: frozenset[str], stubborn_minimum: float = 2.0
    ) -> StatemachineServer:
        """A server holding the data of :meth:`data`, its machine started in the saved state."""
        server = cls(data["fleet"], data["robot"], categories, stubborn_minimum, initial=data["phase"])
        server.load(data)
        return server

    def dumps(self) -> str:
        """The robot's data and machine state as JSON text."""
        return json.dumps(self.data())

    @classmethod
    def loads(
        cls, text: str, categories: frozenset[str], stubborn_minimum: float = 2.0
    ) -> StatemachineServer:
        """A server holding the data of :meth:`dumps`."""
        return cls.from_data(json.loads(text), categories, stubborn_minimum)
