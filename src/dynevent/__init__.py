"""dynevent: the sans-IO reference implementation of the Open-RMF Dynamic Event protocol.

The names a user needs most are importable from here (``from dynevent import
Goal, ServerConfig, State, step``); each lives in the module that defines it
(the wire in :mod:`dynevent.messages`, :mod:`dynevent.vocab` and
:mod:`dynevent.names`; the robot's side in :mod:`dynevent.machine`,
:mod:`dynevent.inputs`, :mod:`dynevent.outputs`, :mod:`dynevent.server`,
:mod:`dynevent.fleet`, :mod:`dynevent.snapshot` and :mod:`dynevent.store`;
the client's side in :mod:`dynevent.client`; every error in
:mod:`dynevent.errors`).  They are imported on first use, so ``import
dynevent`` itself stays quick.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

__version__ = "0.1.0.dev0"

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
        "messages",
    ),
    **dict.fromkeys(
        (
            "Compatibility",
            "DynamicState",
            "EventType",
            "GoalStatus",
            "IdPolicy",
            "RejectReason",
            "Status",
            "Tier",
        ),
        "vocab",
    ),
    **dict.fromkeys(("action_name", "begin_topic", "description_service", "status_topic"), "names"),
    "EventDescription": "description",
    **dict.fromkeys(
        ("ServerConfig", "State", "Transition", "accept", "accept_any", "status_message", "step"), "machine"
    ),
    **dict.fromkeys(("LockedRobotServer", "RobotServer"), "server"),
    "Fleet": "fleet",
    "StateStore": "store",
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
            "InvalidVector",
            "TraceError",
            "UnknownRobot",
        ),
        "errors",
    ),
}
#: The modules importable as attributes (``dynevent.inputs.Tick``) once ``dynevent`` is imported.
_MODULES = ("client", "errors", "inputs", "machine", "messages", "names", "outputs", "snapshot", "vocab")

#: The public face; a test keeps it equal to the names above.
__all__ = [
    "DOCS",
    "HOME",
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
    "InvalidVector",
    "LockedRobotServer",
    "LogEntry",
    "RejectReason",
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
    "__version__",
    "accept",
    "accept_any",
    "action_name",
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
        value = importlib.import_module(f"{__name__}.{name}")
    elif name in _HOMES:
        value = getattr(importlib.import_module(f"{__name__}.{_HOMES[name]}"), name)
    else:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))


if TYPE_CHECKING:  # what type checkers and editors see, without importing anything at run time
    from . import client, errors, inputs, machine, messages, names, outputs, snapshot, vocab
    from .description import EventDescription
    from .errors import (
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
        InvalidVector,
        TraceError,
        UnknownRobot,
    )
    from .fleet import Fleet
    from .machine import ServerConfig, State, Transition, accept, accept_any, status_message, step
    from .messages import (
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
    from .names import action_name, begin_topic, description_service, status_topic
    from .server import LockedRobotServer, RobotServer
    from .store import StateStore
    from .vocab import (
        Compatibility,
        DynamicState,
        EventType,
        GoalStatus,
        IdPolicy,
        RejectReason,
        Status,
        Tier,
    )
