"""dynevent: the sans-IO reference implementation of the Open-RMF Dynamic Event protocol.

The names a user needs most are importable from here (``from dynevent import
Goal, ServerConfig, State, step``); each lives in the module that defines it
(the wire in :mod:`dynevent.wire.messages`, :mod:`dynevent.wire.vocab` and
:mod:`dynevent.wire.names`; the robot's side in :mod:`dynevent.server.machine`,
:mod:`dynevent.server.inputs`, :mod:`dynevent.server.outputs`, :mod:`dynevent.server.holder`,
:mod:`dynevent.server.fleet`, :mod:`dynevent.server.snapshot` and :mod:`dynevent.server.store`;
the client's side in :mod:`dynevent.client`; every error in
:mod:`dynevent.errors`).  They are imported on first use, so ``import
dynevent`` itself stays quick.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0"

#: Where the project lives; the documentation is under ``docs/`` there.
HOME = "https://github.com/dynevent/dynevent"
#: The documentation, as the command line's help points at it.
DOCS = HOME + "/blob/main/docs"

#: Each public name, and the module that defines it.
_HOMES: dict[str, str] = {
    **dict.fromkeys(
        (
            "DescriptionRequest",
            "DescriptionResponse",
            "DynamicEventDescription",
            "DynamicEventStatus",
            "Feedback",
            "Goal",
            "LogEntry",
            "Result",
            "Time",
        ),
        "wire.messages",
    ),
    **dict.fromkeys(
        (
            "Compatibility",
            "DynamicState",
            "EventType",
            "Failure",
            "GoalStatus",
            "IdPolicy",
            "RejectReason",
            "Status",
            "Tier",
        ),
        "wire.vocab",
    ),
    **dict.fromkeys(("action_name", "begin_topic", "description_service", "status_topic"), "wire.names"),
    "EventDescription": "wire.description",
    **dict.fromkeys(("MAX_DURATION", "MILLISECOND", "SECOND"), "wire.units"),
    **dict.fromkeys(
        ("ServerConfig", "State", "Transition", "accept", "any_description", "status_message", "step"),
        "server.machine",
    ),
    **dict.fromkeys(("LockedRobotServer", "RobotServer"), "server.holder"),
    "Fleet": "server.fleet",
    "StateStore": "server.store",
    **dict.fromkeys(
        (
            "DuplicateRobot",
            "DyneventError",
            "ImplementationError",
            "InvalidConfig",
            "InvalidDescription",
            "InvalidMessage",
            "InvalidName",
            "InvalidRecord",
            "InvalidSnapshot",
            "InvalidStore",
            "InvalidValue",
            "InvalidVector",
            "LocalError",
            "MalformedMessage",
            "RemoteError",
            "TraceError",
            "UnknownRobot",
            "WrongInput",
        ),
        "errors",
    ),
}
#: The modules importable as attributes (``dynevent.inputs.Tick``) once ``dynevent`` is imported,
#: and where each lives.
_MODULES: dict[str, str] = {
    "client": "client",
    "errors": "errors",
    "inputs": "server.inputs",
    "machine": "server.machine",
    "messages": "wire.messages",
    "names": "wire.names",
    "outputs": "server.outputs",
    "snapshot": "server.snapshot",
    "vocab": "wire.vocab",
}

#: The public face; a test keeps it equal to the names above.
__all__ = [
    "DOCS",
    "HOME",
    "MAX_DURATION",
    "MILLISECOND",
    "SECOND",
    "Compatibility",
    "DescriptionRequest",
    "DescriptionResponse",
    "DuplicateRobot",
    "DynamicEventDescription",
    "DynamicEventStatus",
    "DynamicState",
    "DyneventError",
    "EventDescription",
    "EventType",
    "Failure",
    "Feedback",
    "Fleet",
    "Goal",
    "GoalStatus",
    "IdPolicy",
    "ImplementationError",
    "InvalidConfig",
    "InvalidDescription",
    "InvalidMessage",
    "InvalidName",
    "InvalidRecord",
    "InvalidSnapshot",
    "InvalidStore",
    "InvalidValue",
    "InvalidVector",
    "LocalError",
    "LockedRobotServer",
    "LogEntry",
    "MalformedMessage",
    "RejectReason",
    "RemoteError",
    "Result",
    "RobotServer",
    "ServerConfig",
    "State",
    "StateStore",
    "Status",
    "Tier",
    "Time",
    "TraceError",
    "Transition",
    "UnknownRobot",
    "WrongInput",
    "__version__",
    "accept",
    "action_name",
    "any_description",
    "begin_topic",
    "client",
    "description_service",
    "errors",
    "inputs",
    "machine",
    "messages",
    "names",
    "outputs",
    "snapshot",
    "status_message",
    "status_topic",
    "step",
    "vocab",
]


def __getattr__(name: str) -> Any:
    """Import a public name's module on first use (PEP 562)."""
    if name in _MODULES:
        value = importlib.import_module(f"{__name__}.{_MODULES[name]}")
    elif name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # what type checkers and editors see, without importing anything at run time
    from dynevent import client, errors
    from dynevent.errors import (
        DuplicateRobot,
        DyneventError,
        ImplementationError,
        InvalidConfig,
        InvalidDescription,
        InvalidMessage,
        InvalidName,
        InvalidRecord,
        InvalidSnapshot,
        InvalidStore,
        InvalidValue,
        InvalidVector,
        LocalError,
        MalformedMessage,
        RemoteError,
        TraceError,
        UnknownRobot,
        WrongInput,
    )
    from dynevent.server import inputs, machine, outputs, snapshot
    from dynevent.server.fleet import Fleet
    from dynevent.server.holder import LockedRobotServer, RobotServer
    from dynevent.server.machine import (
        ServerConfig,
        State,
        Transition,
        accept,
        any_description,
        status_message,
        step,
    )
    from dynevent.server.store import StateStore
    from dynevent.wire import messages, names, vocab
    from dynevent.wire.description import EventDescription
    from dynevent.wire.messages import (
        DescriptionRequest,
        DescriptionResponse,
        DynamicEventDescription,
        DynamicEventStatus,
        Feedback,
        Goal,
        LogEntry,
        Result,
        Time,
    )
    from dynevent.wire.names import action_name, begin_topic, description_service, status_topic
    from dynevent.wire.units import MAX_DURATION, MILLISECOND, SECOND
    from dynevent.wire.vocab import (
        Compatibility,
        DynamicState,
        EventType,
        Failure,
        GoalStatus,
        IdPolicy,
        RejectReason,
        Status,
        Tier,
    )
