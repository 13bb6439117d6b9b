"""Hypothesis strategies and a reusable stateful test for Dynamic Event implementations.

Requires the ``testing`` extra (``pip install 'dynevent[testing]'``), which
pulls in hypothesis.  Nothing in the core imports this package.
"""

from __future__ import annotations

try:
    import hypothesis  # noqa: F401
except ModuleNotFoundError as exc:  # the extra is not installed: say which one
    raise ModuleNotFoundError(
        "dynevent.testing needs hypothesis, which the 'testing' extra installs: "
        "pip install 'dynevent[testing]'",
        name=exc.name,
    ) from exc

from dynevent.testing.stateful import (
    DEFAULT_CONFIG,
    DyneventServer,
    ImplementationServer,
    Observer,
    ProtocolViolation,
    ServerStateMachine,
    ServerUnderTest,
    ServerView,
    input_sequences,
    server_inputs,
    server_state_machine,
)
from dynevent.testing.strategies import (
    hostile_json_values,
    json_values,
    messages,
    wire_dicts,
)

__all__ = [
    "DEFAULT_CONFIG",
    "DyneventServer",
    "ImplementationServer",
    "Observer",
    "ProtocolViolation",
    "ServerStateMachine",
    "ServerUnderTest",
    "ServerView",
    "hostile_json_values",
    "input_sequences",
    "json_values",
    "messages",
    "server_inputs",
    "server_state_machine",
    "wire_dicts",
]
