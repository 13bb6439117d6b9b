"""The common form every implementation is driven and judged in, and the scripted workloads.

A *script* is a list of raw events::

    ("begin", event_id, description)
    ("request", uuid, goal)          goal = (seq, event_type, category, description, id, stubborn_period)
    ("start", uuid)
    ("progress", status, log_text or None, tier)
    ("finished", status)

A *driver* has one method per event kind (``begin``, ``request``, ``start``,
``progress``, ``finished``, each taking the event's raw values and ``now``)
plus ``accept(goal)``, and ``common(outputs)`` writing its outputs in the
common form: the whole output in builtins, as :func:`plain` writes dynevent's,
e.g. ``("publish_feedback", uuid, ("Feedback", "underway", 11, (("LogEntry",
0, "info", 1700000000000, "left the lobby"),)))``.  The peers write that form
natively; :class:`DyneventDriver` drives dynevent's
:class:`~dynevent.server.holder.RobotServer` with inputs built from the raw
values and converts its outputs with :func:`plain`.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Iterable, Sequence
from typing import Any

import attrs

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.holder import RobotServer
from dynevent.server.machine import ServerConfig, any_description
from dynevent.wire._fields import ANNOTATION
from dynevent.wire.messages import Goal

from .rules import CANCEL, FINISHED, NEXT

__all__ = [
    "CATEGORIES",
    "DESCRIPTION",
    "EVENT_DESCRIPTION",
    "DyneventDriver",
    "child_cycle",
    "common_outputs",
    "plain",
    "play",
    "shared_script",
    "uuid",
    "whole_event",
]

#: The categories every robot of the workloads supports, each with dynevent's accept-everything validator.
CATEGORIES = {"go_to_place": any_description, "perform_action": any_description}
#: A small JSON description of a NEXT goal.
DESCRIPTION = '{"place": "pantry", "orientation": 1.57}'
#: The ``dynamic_event`` description the begin events carry.
EVENT_DESCRIPTION = '{"category": "patrol", "detail": "lobby rounds"}'

Event = tuple[Any, ...]


def uuid(number: int) -> str:
    """The goal UUID numbered ``number``."""
    return f"{number:032x}"


# --------------------------------------------------------------------------- the dynevent driver


class DyneventDriver:
    """dynevent's :class:`RobotServer`, fed with inputs built from the raw events."""

    def __init__(self, fleet: str = "fleet", robot: str = "robot", stubborn_minimum: float = 2.0) -> None:
        config = ServerConfig(categories=CATEGORIES, stubborn_minimum=stubborn_minimum)
        self.server = RobotServer(fleet, robot, config)

    @staticmethod
    def goal(raw: Sequence[Any]) -> Goal:
        """The dynevent goal of a raw goal."""
        seq, event_type, category, description, goal_id, period = raw
        return Goal(
            dynamic_event_seq=seq,
            event_type=event_type,
            category=category,
            description=description,
            id=goal_id,
            stubborn_period=period,
        )

    def accept(self, raw: Sequence[Any]) -> tuple[str, ...]:
        """The decision on a raw goal, in the common form."""
        decision = self.server.accept(self.goal(raw))
        if isinstance(decision, outs.Rejected):
            return ("reject", decision.reason.value)
        return ("accept",)

    def begin(self, event_id: int, description: str, now: int) -> tuple[outs.Output, ...]:
        return self.server.step(ins.Begin(description=description, event_id=event_id, now=now))

    def request(self, goal_uuid: str, raw: Sequence[Any], now: int) -> tuple[outs.Output, ...]:
        return self.server.step(ins.GoalRequested(goal_uuid=goal_uuid, goal=self.goal(raw), now=now))

    def start(self, goal_uuid: str, now: int) -> tuple[outs.Output, ...]:
        return self.server.step(ins.GoalStarted(goal_uuid=goal_uuid, now=now))

    def progress(self, status: str, text: str | None, tier: str, now: int) -> tuple[outs.Output, ...]:
        return self.server.step(ins.ChildProgress(status=status, log_text=text, tier=tier, now=now))

    def finished(self, status: str, now: int) -> tuple[outs.Output, ...]:
        return self.server.step(ins.ChildFinished(status=status, now=now))

    @staticmethod
    def common(outputs: Iterable[outs.Output]) -> list[tuple[Any, ...]]:
        """dynevent's outputs in the common form."""
        return common_outputs(outputs)


def plain(value: Any) -> Any:
    """A dynevent output (or any value in one) as the peers write it: the whole value in builtins.

    An output becomes ``(KIND, *fields)``, a nested message ``(class name, *fields)``, both with
    every field that takes part in equality (the ``rule`` annotation does not), in declaration order;
    an enum member becomes its value; a tuple is converted item by item.
    """
    cls = type(value)
    if attrs.has(cls):
        fields = _FIELDS.get(cls)
        if fields is None:
            fields = _FIELDS[cls] = tuple(
                field.name for field in attrs.fields(cls) if field.eq and not field.metadata.get(ANNOTATION)
            )
        name = getattr(value, "KIND", "") or cls.__name__
        return (name, *(plain(getattr(value, field)) for field in fields))
    if isinstance(value, enum.Enum):
        return value.value
    if cls is tuple:
        return tuple(plain(item) for item in value)
    return value


_FIELDS: dict[type, tuple[str, ...]] = {}


def common_outputs(outputs: Iterable[outs.Output]) -> list[Any]:
    """dynevent's outputs as the peers write theirs."""
    return [plain(output) for output in outputs]


# --------------------------------------------------------------------------- playing scripts


def play(driver: Any, script: Sequence[Event], now: int = 0) -> list[Any]:
    """Feed ``script`` to ``driver``; the outputs of each event (in the driver's own form)."""
    results: list[Any] = []
    for index, event in enumerate(script):
        kind, *values = event
        method: Callable[..., Any] = getattr(driver, kind)
        results.append(method(*values, now + index * 1_000_000))
    return results


# --------------------------------------------------------------------------- scripts


def child_cycle(
    seq: int, child_id: int, goal_uuid: str, stubborn_period: float = 0.0, final: str = "completed"
) -> list[Event]:
    """One full child: request, start, three progress updates with a log line, finish."""
    goal = (seq, NEXT, "go_to_place", DESCRIPTION, child_id, stubborn_period)
    return [
        ("request", goal_uuid, goal),
        ("start", goal_uuid),
        ("progress", "underway", "left the lobby", "info"),
        ("progress", "underway", "in the corridor", "info"),
        ("progress", "underway", "at the pantry door", "info"),
        ("finished", final),
    ]


def whole_event(children: int = 100, seq: int = 1, first_id: int = 1000) -> list[Event]:
    """A whole dynamic event: begin, ``children`` children, one of them stubborn and one cancelled, FINISHED.

    The child at 40% of the run asks for a stubborn period of 0.5 s (clamped to
    2 s; its stubbornness ends when the next child starts); the child at 70% is
    cancelled by a CANCEL goal while it runs.
    """
    script: list[Event] = [("begin", first_id - 1, EVENT_DESCRIPTION)]
    stubborn_at, cancel_at = children * 2 // 5, children * 7 // 10
    for index in range(children):
        child = first_id + index
        goal_uuid = uuid(child)
        if index == cancel_at:
            cancel_uuid = uuid(10**9 + child)
            cancel_goal = (seq, CANCEL, "", "", child, 0.0)
            cycle = child_cycle(seq, child, goal_uuid, final="canceled")
            script += cycle[:3]
            script += [("request", cancel_uuid, cancel_goal), ("start", cancel_uuid), cycle[-1]]
        else:
            period = 0.5 if index == stubborn_at else 0.0
            script += child_cycle(seq, child, goal_uuid, stubborn_period=period)
    finished_uuid = uuid(2 * 10**9)
    script += [("request", finished_uuid, (seq, FINISHED, "", "", 0, 0.0)), ("start", finished_uuid)]
    return script


def shared_script() -> list[Event]:
    """The workloads' rules, including every refusal the peers implement, in one scripted run."""
    next_goal = (1, NEXT, "go_to_place", DESCRIPTION, 11, 0.0)
    script: list[Event] = [
        ("progress", "underway", "nobody listens", "info"),  # no child: ignored
        ("request", uuid(1), next_goal),  # seq 0 expected: seq mismatch
        ("begin", 10, EVENT_DESCRIPTION),
        ("begin", 10, EVENT_DESCRIPTION),  # already active: ignored
        ("request", uuid(1), (1, 0, "go_to_place", DESCRIPTION, 11, 0.0)),  # uninitialized event type
        ("request", uuid(1), (1, 9, "go_to_place", DESCRIPTION, 11, 0.0)),  # unknown event type
        ("request", uuid(1), (1, NEXT, "dance", DESCRIPTION, 11, 0.0)),  # unsupported category
        ("request", uuid(1), (1, NEXT, "go_to_place", "{not json", 11, 0.0)),  # not JSON
        ("request", uuid(1), (1, NEXT, "go_to_place", DESCRIPTION, 11, float("nan"))),  # non-finite
        ("request", uuid(1), (1, NEXT, "go_to_place", DESCRIPTION, 10, 0.0)),  # stale id
        ("request", uuid(1), (1, CANCEL, "", "", 11, 0.0)),  # cancel when idle
        ("request", uuid(1), next_goal),
        ("request", uuid(1), next_goal),  # same uuid: ignored
        ("request", uuid(2), (1, NEXT, "go_to_place", DESCRIPTION, 12, 0.0)),  # accepted too: will race
        ("start", uuid(1)),
        ("start", uuid(2)),  # race condition
        ("start", uuid(3)),  # unknown: ignored
        ("request", uuid(3), (1, NEXT, "go_to_place", DESCRIPTION, 13, 0.0)),  # busy
        ("request", uuid(3), (1, CANCEL, "", "", 99, 0.0)),  # cancel id mismatch
        ("progress", "delayed", "waiting for the lift", "warning"),
        ("progress", "delayed", None, "info"),
        ("progress", "underway", "in the lift", "info"),
        ("finished", "failed"),  # a failed child still succeeds
        ("request", uuid(4), (1, NEXT, "perform_action", '"wave"', 20, 0.5)),  # clamped
        ("start", uuid(4)),
        ("finished", "completed"),  # stubbornness begins
        ("request", uuid(5), (1, NEXT, "go_to_place", DESCRIPTION, 21, 3.0)),
        ("start", uuid(5)),  # stubbornness ends
        ("request", uuid(6), (1, CANCEL, "", "", 21, 0.0)),
        ("request", uuid(7), (1, CANCEL, "", "", 21, 0.0)),
        ("start", uuid(6)),  # the child is told to cancel
        ("start", uuid(7)),  # already cancelling: waits too
        ("progress", "underway", "winding down", "info"),
        ("finished", "canceled"),  # the goal aborted, both CANCEL goals succeed
        ("request", uuid(8), (1, FINISHED, "", "", 0, 0.0)),
        ("start", uuid(8)),  # ends stubbornness and the dynamic event
        ("request", uuid(9), next_goal),  # inactive
        ("begin", 30, EVENT_DESCRIPTION),
        *child_cycle(2, 31, uuid(10)),
    ]
    return script
