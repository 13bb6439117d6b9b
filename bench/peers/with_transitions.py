"""The shared rules with the phase held by a ``transitions`` machine (one ``Machine`` per robot).

The phase checks of the rules read the machine's state, and every phase change
fires a trigger, as an application written on ``transitions`` would.
"""

from __future__ import annotations

import json
from typing import Any

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

    def __init__(
        self,
        fleet: str,
        robot: str,
        categories: frozenset[str],
        stubborn_minimum: float = 2.0,
        initial: str = "inactive",
    ) -> None:
        self.setup(fleet, robot, categories, stubborn_minimum)
        self.machine = Machine(
            model=self, states=_STATES, transitions=_TRANSITIONS, initial=initial, auto_transitions=False
        )

    def phase(self) -> int:
        return _PHASE[self.state]

    def data(self) -> dict[str, Any]:
        """The robot's data and machine state as plain JSON values."""
        data = self.dump()
        data["phase"] = self.state
        return data

    @classmethod
    def from_data(
        cls, data: dict[str, Any], categories: frozenset[str], stubborn_minimum: float = 2.0
    ) -> TransitionsServer:
        """A server holding the data of :meth:`data`, its machine started in the saved state."""
        server = cls(data["fleet"], data["robot"], categories, stubborn_minimum, initial=data["phase"])
        server.load(data)
        return server

    def dumps(self) -> str:
        """The robot's data and machine state as JSON text."""
        return json.dumps(self.data())

    @classmethod
    def loads(cls, text: str, categories: frozenset[str], stubborn_minimum: float = 2.0) -> TransitionsServer:
        """A server holding the data of :meth:`dumps`."""
        return cls.from_data(json.loads(text), categories, stubborn_minimum)
