"""The floor: the shared rules over plain attributes, no validation, no library.

What a hand-written server costs when it does nothing but decide; dynevent's
frozen, validated values and pure steps are measured against it.
"""

from __future__ import annotations

import json
from typing import Any

from .rules import INACTIVE, RUNNING, WAITING, Rules

__all__ = ["FloorServer"]


class FloorServer(Rules):
    """One robot's server: plain attributes, the phase in one of them."""

    __slots__ = (
        "_phase",
        "active",
        "cancels",
        "categories",
        "event_id",
        "fleet",
        "last_id",
        "log_seq",
        "queued",
        "robot",
        "running",
        "seq",
        "status",
        "stubborn",
        "stubborn_minimum",
    )

    def __init__(
        self, fleet: str, robot: str, categories: frozenset[str], stubborn_minimum: float = 2.0
    ) -> None:
        self.setup(fleet, robot, categories, stubborn_minimum)
        self._phase = INACTIVE

    def phase(self) -> int:
        return self._phase

    def ev_begin(self) -> None:
        self._phase = WAITING

    def ev_start(self) -> None:
        self._phase = RUNNING

    def ev_child_end(self) -> None:
        self._phase = WAITING

    def ev_finish(self) -> None:
        self._phase = INACTIVE

    def data(self) -> dict[str, Any]:
        """The robot's data as plain JSON values (the phase follows from them)."""
        return self.dump()

    @classmethod
    def from_data(
        cls, data: dict[str, Any], categories: frozenset[str], stubborn_minimum: float = 2.0
    ) -> FloorServer:
        """A server holding the data of :meth:`data`."""
        server = cls(data["fleet"], data["robot"], categories, stubborn_minimum)
        server.load(data)
        server._phase = server.dumped_phase()
        return server

    def dumps(self) -> str:
        """The robot's data as JSON text."""
        return json.dumps(self.data())

    @classmethod
    def loads(cls, text: str, categories: frozenset[str], stubborn_minimum: float = 2.0) -> FloorServer:
        """A server holding the data of :meth:`dumps`."""
        return cls.from_data(json.loads(text), categories, stubborn_minimum)
