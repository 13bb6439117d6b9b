"""``dynevent demo``: one robot's scripted session, client machine to server machine, over the loopback.

The session walks through the protocol's main paths, in order:

1. a task begins a dynamic event;
2. a NEXT ``go_to_place`` runs, reports progress with logs, and completes;
3. a NEXT with a 0.5 s stubborn period: the period is clamped to 2.0 s
   (R12.2) and, once the child completes, the robot holds its place over a
   few ticks (R12.1, R12.3, R12.4);
4. a CANCEL naming the wrong event, sent as a raw goal so that the *server*
   rejects it with its reason (the client machine would refuse it locally);
5. a CANCEL naming the running event: the child is cancelled and both goals
   are answered (R9.3, R8.2, R8.3);
6. two NEXT goals race: both are accepted, one wins, the other is aborted
   with ``race condition`` (R5.2);
7. FINISHED ends the dynamic event (R11.1);
8. a goal after the end is rejected as ``inactive`` (R4.3).

Every random draw (message delays, which goal of the race starts first) comes
from the seed, so the same seed prints byte-identical output.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from typing import Any

import attrs

from . import _json, machine
from . import client as cl
from . import inputs as ins
from .loopback import Adapter, ChildScript, Loopback, Options, TimelineEvent, format_timeline
from .messages import Goal
from .records import rule_validator
from .vocab import EventType, Status

__all__ = ["STEPS", "add_command", "run_demo", "session_events"]

_MS = 1_000_000
_SECOND = cl.SECOND

#: The captions of the demo's steps, in order.
STEPS = (
    "begin a dynamic event",
    "NEXT go_to_place: progress, logs, completion",
    "NEXT with a 0.5 s stubborn period: clamped to 2 s, held over a few ticks",
    "CANCEL naming the wrong event, sent raw: the server rejects it",
    "CANCEL naming the running event: both goals are answered",
    "two NEXT goals race: one wins, the other loses",
    "FINISHED ends the dynamic event",
    "a goal after the end",
)


def _config() -> machine.ServerConfig:
    place = rule_validator([{"accept": "string"}, {"accept": "object", "required": ["place"]}])
    return machine.ServerConfig(categories={"go_to_place": place})


def _adapter() -> Adapter:
    progress = ChildScript(
        reports=((300 * _MS, Status.UNDERWAY), (900 * _MS, Status.UNDERWAY), (1500 * _MS, Status.DELAYED)),
        finish_after=2 * _SECOND,
    )
    short = ChildScript(reports=((400 * _MS, Status.UNDERWAY),), finish_after=_SECOND)
    endless = ChildScript(reports=((300 * _MS, Status.UNDERWAY),), finish_after=None, cancel_after=250 * _MS)
    return Adapter(scripts=(progress, short, endless), default=short)


def _readable(event: TimelineEvent) -> TimelineEvent:
    """Name the position a tick reports (the loopback's summary of a tick is empty)."""
    if event.kind == "tick" and not event.summary:
        record = event.record
        summary = f"{record['map_name']} ({record['x']:g}, {record['y']:g})"
        return attrs.evolve(event, summary=summary)
    return event


def session_events(seed: int) -> list[tuple[int, TimelineEvent]]:
    """Run the scripted session; every timeline event with the index of its step in :data:`STEPS`."""
    session = Loopback(
        cl.ClientState.new("0123456789abcdef", categories=["go_to_place"]),
        machine.State.new("tinyRobot", "tinyRobot1"),
        _config(),
        adapter=_adapter(),
        options=Options(delay=(1 * _MS, 4 * _MS), start_delay=(5 * _MS, 15 * _MS), reorder=True),
        seed=seed,
    )
    tagged: list[tuple[int, TimelineEvent]] = []

    def chapter(index: int, body: Callable[[], Any]) -> None:
        start = len(session.timeline)
        body()
        session.run()
        tagged.extend((index, _readable(event)) for event in session.timeline[start:])

    def tick(x: float) -> None:
        session.server_input(ins.Tick(now=session.now, map_name="L1", x=x, y=2.0))

    def begin() -> None:
        tick(4.0)
        session.begin('{"category": "patrol", "detail": "rounds of the ward"}', event_id=5)

    def stubborn() -> None:
        session.request_next("go_to_place", '{"place": "lobby"}', stubborn_period=0.5)
        session.run()
        for x in (4.0, 4.02, 5.5, 5.5):  # held still, a small drift, a move: re-anchored, then held
            session.advance(_SECOND)
            tick(x)

    def seq() -> int:
        return session.client.seq

    def wrong_cancel() -> None:
        session.request_next("go_to_place", '"charger"')
        session.advance(500 * _MS)
        running = session.server.running
        wrong = (running.child_id if running is not None else 0) + 40
        session.send_foreign(Goal(dynamic_event_seq=seq(), event_type=EventType.CANCEL, id=wrong))

    def race() -> None:
        session.request_next("go_to_place", '"kitchen"')
        rival = Goal(
            dynamic_event_seq=seq(),
            event_type=EventType.NEXT,
            category="go_to_place",
            description='"loading_bay"',
            id=100,
        )
        session.send_foreign(rival)

    def after_end() -> None:
        session.request_next("go_to_place", '"pantry"')  # the client knows the run is over
        late = Goal(
            dynamic_event_seq=seq(),
            event_type=EventType.NEXT,
            category="go_to_place",
            description='"pantry"',
            id=200,
        )
        session.send_foreign(late)

    chapter(0, begin)
    chapter(1, lambda: session.request_next("go_to_place", '"pantry"'))
    chapter(2, stubborn)
    chapter(3, wrong_cancel)
    chapter(4, session.request_cancel)
    chapter(5, race)
    chapter(6, session.request_finish)
    chapter(7, after_end)
    return tagged


def run_demo(seed: int = 0, *, json_lines: bool = False) -> str:
    """The demo's output for ``seed``: a readable timeline, or one JSON object per line."""
    tagged = session_events(seed)
    if json_lines:
        lines = []
        for index, event in tagged:
            record = {"step": index + 1, **event.to_dict()}
            lines.append(_json.dumps(record) + "\n")
        return "".join(lines)
    parts: list[str] = []
    header = f"{'time (s)':>9}  {'direction':<14}  {'message':<20}  summary  -> decision"
    parts.append(f"dynevent demo: tinyRobot/tinyRobot1 over the loopback, seed {seed}\n\n{header}\n")
    for index, caption in enumerate(STEPS):
        events = [event for step, event in tagged if step == index]
        parts.append(f"\n-- {index + 1}. {caption}\n")
        parts.append(format_timeline(events))
    return "".join(parts)


def _run(args: argparse.Namespace) -> int:
    print(run_demo(args.seed, json_lines=args.json), end="")
    return 0


def add_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Register ``dynevent demo``."""
    parser = commands.add_parser(
        "demo",
        help="run a scripted client/server session for one robot and print its timeline",
        description="Run a scripted session between a client machine and a server machine for one "
        "robot, over the in-process loopback: begin, a NEXT with progress and logs, a clamped "
        "stubborn period held over ticks, a wrong CANCEL rejected by the server, a right CANCEL, "
        "two racing NEXT goals, FINISHED, and a goal after the end.  The same seed prints the same "
        "output.  Exit status: 0.",
    )
    parser.add_argument("--json", action="store_true", help="print one JSON object per timeline event")
    parser.add_argument(
        "--seed", type=int, default=0, metavar="N", help="seed of the message delays and the race (0)"
    )
    parser.set_defaults(run=_run)
