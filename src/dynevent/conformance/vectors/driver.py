"""The conformance driver protocol: one implementation under test, over JSON lines.

``python -m dynevent.conformance.vectors.driver`` serves dynevent's own machine on standard input
and output; ``dynevent vectors --impl COMMAND`` talks to any program that
speaks the same protocol (docs/conformance.md specifies it):

- each request is one JSON object on one line; each answer is one JSON object
  on one line, in order;
- ``{"op": "hello"}`` → ``{"ok": true, "implementation": "...", "protocol": 1}``;
- ``{"op": "reset", "fleet": F, "robot": R, "config": {...}, "state": null | {...}}``
  → ``{"ok": true}``: a new server for this robot, fresh or in the given state;
- ``{"op": "apply", "input": {...}}`` → ``{"ok": true, "outputs": [...],
  "view": {"phase": "WAITING", "seq": 1, "current_id": 7}}``;
- any fault → ``{"ok": false, "error": "..."}``; the driver keeps serving.

Records (inputs, outputs, configurations) are those of :mod:`dynevent.conformance.records`.
"""

from __future__ import annotations

import os
import sys
from typing import IO, Any

from dynevent import __version__
from dynevent.conformance.records import InvalidRecord, config_from_json, input_from_json, output_to_json
from dynevent.errors import DyneventError, InvalidSnapshot, short_repr
from dynevent.server import machine
from dynevent.server.machine import ServerConfig, State
from dynevent.server.snapshot import check_state
from dynevent.wire import _json
from dynevent.wire._codec import CodecError, decode, encode
from dynevent.wire.names import validate_token

__all__ = ["PROTOCOL_VERSION", "Driver", "main", "state_from_json", "view"]

#: The version of the driver protocol this module speaks.
PROTOCOL_VERSION = 1


def state_from_json(fleet: str, robot: str, data: object) -> State:
    """A state from the JSON object of docs/spec.md's state table (missing fields: initial values)."""
    if data is None:
        return State.new(fleet, robot)
    if not isinstance(data, dict):
        raise InvalidRecord("$.state", "expected null or a state object")
    fields = dict(data)
    fields.setdefault("fleet", fleet)
    fields.setdefault("robot", robot)
    try:
        state: State = decode(State, fields, "$.state")
    except CodecError as exc:
        raise InvalidRecord(exc.path, exc.problem) from None
    try:
        return check_state(state)  # R19.8, as a snapshot's restore checks it
    except InvalidSnapshot as exc:
        raise InvalidRecord(exc.path, exc.problem) from None


def view(state: State) -> dict[str, Any]:
    """What a vector may check of the state: phase name, seq, current id."""
    return {"phase": state.phase.name, "seq": state.seq, "current_id": state.current_id}


class Driver:
    """dynevent's own implementation behind the driver protocol, one request at a time."""

    def __init__(self) -> None:
        self._state: State | None = None
        self._config = ServerConfig()

    def handle(self, request: object) -> dict[str, Any]:
        """Answer one decoded request."""
        try:
            return self._handle(request)
        except DyneventError as exc:
            return {"ok": False, "error": str(exc)}

    def _handle(self, request: object) -> dict[str, Any]:
        if not isinstance(request, dict):
            raise InvalidRecord("$", "expected a request object")
        op = request.get("op")
        if op == "hello":
            return {"ok": True, "implementation": f"dynevent {__version__}", "protocol": PROTOCOL_VERSION}
        if op == "reset":
            fleet, robot = request.get("fleet"), request.get("robot")
            config = config_from_json(request.get("config", {}), "$.config")
            self._state = state_from_json(
                validate_token("fleet", fleet), validate_token("robot", robot), request.get("state")
            )
            self._config = config
            return {"ok": True}
        if op == "apply":
            if self._state is None:
                raise InvalidRecord("$.op", "apply before reset")
            event = input_from_json(request.get("input"), "$.input")
            transition = machine.step(self._state, event, self._config)
            self._state = transition.state
            return {
                "ok": True,
                "outputs": [output_to_json(output) for output in transition.outputs],
                "view": view(self._state),
            }
        raise InvalidRecord("$.op", f"expected 'hello', 'reset' or 'apply', got {short_repr(op)}")

    def snapshot(self) -> Any:
        """The current state as JSON values (for debugging)."""
        return encode(self._state)


def serve(reader: IO[str], writer: IO[str]) -> None:
    """Serve the driver protocol until ``reader`` ends."""
    driver = Driver()
    for line in reader:
        if not line.strip():
            continue
        try:
            request = _json.parse(line)
        except _json.JsonProblem as exc:
            answer: dict[str, Any] = {"ok": False, "error": f"request is {exc}"}
        else:
            answer = driver.handle(request)
        writer.write(_json.dumps(answer) + "\n")
        writer.flush()


def main() -> int:
    """Entry point of ``python -m dynevent.conformance.vectors.driver``."""
    try:
        serve(sys.stdin, sys.stdout)
    except KeyboardInterrupt:
        return 130
    except BrokenPipeError:  # the runner went away
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    return 0


if __name__ == "__main__":
    sys.exit(main())
