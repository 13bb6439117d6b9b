"""The adapter interface the kit drives (:class:`ServerUnderTest`), and the two adapters it ships:
:class:`DyneventServer` (dynevent's own machine) and :class:`ImplementationServer` (any program or
object speaking the conformance driver protocol).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any, Protocol

import attrs

from dynevent.conformance.records import config_from_json, input_to_json, output_from_json
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.wire.vocab import (
    DynamicState,
)

__all__ = ["DyneventServer", "ImplementationServer", "ServerUnderTest", "ServerView"]


@attrs.frozen
class ServerView:
    """What an implementation may expose of its state: the phase, the seq and the current id (R2.2)."""

    phase: DynamicState
    seq: int
    current_id: int


class ServerUnderTest(Protocol):
    """The adapter an implementation is wrapped in to be driven by the kit.

    ``reset`` starts a fresh server for one robot, configured by a
    configuration record (the JSON form of :func:`dynevent.conformance.records.config_from_json`).
    ``apply`` feeds one input and returns the outputs, in order, as dynevent's
    output classes (:mod:`dynevent.server.outputs`); it must not raise.  ``view``
    returns the phase, seq and current id, or ``None`` when the implementation
    does not expose them (the kit then checks the outputs alone).
    """

    def reset(self, fleet: str, robot: str, config: Mapping[str, Any]) -> None:
        """Start a fresh server for ``fleet``/``robot`` with this configuration record."""

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """Apply one input; return its outputs in order."""

    def view(self) -> ServerView | None:
        """The phase, seq and current id, or ``None``."""


class DyneventServer:
    """dynevent's own machine behind :class:`ServerUnderTest`: :func:`~dynevent.server.machine.step`.

    ``state`` and ``config`` are public so that a test can wrap or perturb the
    server (e.g. to build a deliberately broken one).
    """

    def __init__(self) -> None:
        self.config = ServerConfig()
        self.state: State | None = None

    def reset(self, fleet: str, robot: str, config: Mapping[str, Any]) -> None:
        """A fresh state and the configuration the record describes."""
        self.config = config_from_json(dict(config))
        self.state = State.new(fleet, robot)

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """One step of the machine."""
        if self.state is None:
            raise RuntimeError("apply before reset")
        transition = machine.step(self.state, event, self.config)
        self.state = transition.state
        return list(transition.outputs)

    def view(self) -> ServerView | None:
        """The machine's phase, seq and current id."""
        if self.state is None:
            return None
        return ServerView(self.state.phase, self.state.seq, self.state.current_id)


class _Implementation(Protocol):
    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None: ...

    def apply(self, event: Any) -> tuple[list[Any], Any]: ...


class ImplementationServer:
    """Any implementation of the conformance driver protocol behind :class:`ServerUnderTest`.

    ``implementation`` is a :class:`dynevent.conformance.vectors.Implementation` (for
    instance :class:`~dynevent.conformance.vectors.ExternalImplementation` running another
    program); inputs and outputs cross as the JSON records of
    :mod:`dynevent.conformance.records`.  Closing the implementation is the caller's job.
    """

    def __init__(self, implementation: _Implementation) -> None:
        self._implementation = implementation
        self._view: ServerView | None = None

    def reset(self, fleet: str, robot: str, config: Mapping[str, Any]) -> None:
        """Reset the implementation to a fresh server."""
        self._implementation.reset(fleet, robot, dict(config), None)
        self._view = None

    def apply(self, event: ins.Input) -> Sequence[outs.Output]:
        """Send the input record; decode the output records and keep the view."""
        records, view = self._implementation.apply(input_to_json(event))
        self._view = _decode_view(view)
        return [output_from_json(record, f"$.outputs[{index}]") for index, record in enumerate(records)]

    def view(self) -> ServerView | None:
        """The view of the last answer, when the implementation sent one."""
        return self._view


def _decode_view(view: Any) -> ServerView | None:
    if not isinstance(view, dict):
        return None
    try:
        return ServerView(DynamicState[view["phase"]], int(view["seq"]), int(view["current_id"]))
    except (KeyError, TypeError, ValueError):
        return None
