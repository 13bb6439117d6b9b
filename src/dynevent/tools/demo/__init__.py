"""``dynevent demo``: one robot's scripted session, client machine to server machine, in a
simulated session (:mod:`dynevent.tools.demo.simulated_session`).

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
from the seed, so the same seed prints byte-identical output.  The timeline
fits 100 columns, explains its notation first and ends with what the session
showed; ``--mermaid`` renders the same session as a Mermaid sequence diagram.
"""

from __future__ import annotations

import argparse
import collections
import textwrap
from collections.abc import Callable, Sequence
from typing import Any

import attrs

from dynevent import client as cl
from dynevent.conformance.records import rule_validator
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.tools.demo.simulated_session import (
    Adapter,
    ChildScript,
    Options,
    SimulatedSession,
    TimelineEvent,
)
from dynevent.wire import _json
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType, Failure, Status

__all__ = ["STEPS", "WIDTH", "mermaid", "run", "run_demo", "session_events", "summary"]

_SECOND = cl.SECOND  # instants (event.time) are nanoseconds; durations below are seconds

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
        reports=((0.3, Status.UNDERWAY), (0.9, Status.UNDERWAY), (1.5, Status.DELAYED)),
        finish_after=2,
    )
    short = ChildScript(reports=((0.4, Status.UNDERWAY),), finish_after=1)
    endless = ChildScript(reports=((0.3, Status.UNDERWAY),), finish_after=None, cancel_after=0.25)
    return Adapter(scripts=(progress, short, endless), default=short)


#: The widest line of the text timeline.
WIDTH = 100

#: Who an event's ``direction`` names, in the text timeline's second column.
_WHO = {"client": "C", "client->server": "C->S", "server->client": "S->C", "adapter": "A"}

_LEGEND = (
    "How to read it:",
    "  time   simulated seconds since the start; messages take 1 to 4 ms on the simulated network",
    "  C      an event of the client machine",
    "  A      an event between the robot's server machine and its fleet adapter",
    "  C->S   a goal from the client to the robot's server; S->C a message back",
    "  =>     what the receiver made of it",
    "  0123..0000  a goal's UUID: its first and last four hex digits",
    "  at L1 (4, 2)  the robot's position as the adapter reports it: map L1, x = 4 m, y = 2 m",
    "  stubborn  a stubborn period: once its child ends, the robot holds its place that long",
)


def _readable(event: TimelineEvent) -> TimelineEvent:
    """Name the position a tick reports (the session's summary of a tick is empty)."""
    if event.kind == "tick" and not event.summary:
        record = event.record
        summary = f"at {record['map_name']} ({record['x']:g}, {record['y']:g})"
        return attrs.evolve(event, summary=summary)
    return event


def _text_lines(event: TimelineEvent) -> list[str]:
    """One event in at most :data:`WIDTH` columns: on one line if it fits, else wrapped under itself."""
    head = f"{event.time / _SECOND:7.3f}  {_WHO.get(event.direction, event.direction):<4}  {event.kind:<16}  "
    decision = f"=> {event.decision}" if event.decision else ""
    whole = (
        f"{head}{event.summary}  {decision}"
        if event.summary and decision
        else head + event.summary + decision
    )
    if len(whole) <= WIDTH:
        return [whole.rstrip()]
    indent = " " * len(head)
    width = WIDTH - len(head)
    lines = [head + line for line in _wrap(event.summary, width)[:1]]
    lines += [indent + line for line in _wrap(event.summary, width)[1:]]
    if not lines:
        lines = [head.rstrip()]
    lines += [indent + line for line in _wrap(decision, width, "   ")]
    return [line.rstrip() for line in lines]


def _wrap(text: str, width: int, indent: str = "") -> list[str]:
    return textwrap.wrap(text, width, subsequent_indent=indent, break_on_hyphens=False) if text else []


def _lost_race(event: TimelineEvent) -> bool:
    """Did the server abort a goal at this step because it lost the race to its start (R5.2)?"""
    return any(
        isinstance(output, outs.AnswerGoal) and Failure.of(output.result.execution_failure) is Failure.RACE
        for output in event.outputs
    )


def summary(tagged: Sequence[tuple[int, TimelineEvent]]) -> list[str]:
    """What the session showed, counted from its events."""
    events = [event for _, event in tagged]
    sent = [event for event in events if event.direction == "client" and event.decision.startswith("send ")]
    raw = sum(1 for event in sent if event.kind == "send_foreign")
    refused = [event.decision.split(" ", 2)[1] for event in events if event.decision.startswith("refused: ")]
    requested = [event.decision for event in events if event.kind == "goal_requested"]
    accepted = sum(1 for decision in requested if decision == "accepted")
    rejected = [decision.split(" ", 2)[1] for decision in requested if decision.startswith("rejected: ")]
    outcomes = collections.Counter(str(e.record.get("kind")) for e in events if e.kind == "outcome")
    races = sum(1 for event in events if _lost_race(event))
    clamps = [e.record for e in events if e.kind == "stubborn_clamped"]
    holds = sum(1 for event in events if event.kind in ("stubborn_begin", "stubborn_hold"))
    delays = sum(1 for event in events if event.kind == "stubborn_delay")
    lines = [
        f"What the session showed, in {events[-1].time / _SECOND:.3f} s of simulated time:",
        f"  - the client sent {len(sent)} goals ({raw} of them raw, past its own checks)"
        + (f" and refused {len(refused)} itself ({', '.join(refused)})" if refused else ""),
        f"  - the server accepted {accepted} and rejected {len(rejected)}"
        + (f" ({', '.join(rejected)})" if rejected else ""),
        "  - the client's outcomes: "
        + ", ".join(f"{count} {kind}" for kind, count in sorted(outcomes.items())),
        f"  - {races} accepted goal(s) beaten at start by a rival (race condition)",
    ]
    for clamp in clamps:
        lines.append(
            f"  - a stubborn period of {clamp['requested']:g} s clamped to {clamp['applied']:g} s: "
            f"held {holds} time(s), re-checked after a delay {delays} time(s)"
        )
    return lines


class _Script:
    """The demo's chapters (:data:`STEPS`), played on one simulated session."""

    def __init__(self, seed: int) -> None:
        self.session = SimulatedSession(
            cl.ClientState.new("0123456789abcdef", categories=["go_to_place"]),
            machine.State.new("tinyRobot", "tinyRobot1"),
            _config(),
            adapter=_adapter(),
            options=Options(delay=(0.001, 0.004), start_delay=(0.005, 0.015), reorder=True),
            seed=seed,
        )
        self.tagged: list[tuple[int, TimelineEvent]] = []

    def chapter(self, index: int, body: Callable[[], Any]) -> None:
        start = len(self.session.timeline)
        body()
        self.session.run()
        self.tagged.extend((index, _readable(event)) for event in self.session.timeline[start:])

    def tick(self, x: float) -> None:
        self.session.server_input(ins.Tick(now=self.session.now, map_name="L1", x=x, y=2.0))

    def foreign_next(self, place: str, id: int) -> None:
        """Another client's NEXT, unknown to the client machine."""
        description = f'"{place}"'
        seq = self.session.client.seq
        goal = Goal(
            dynamic_event_seq=seq,
            event_type=EventType.NEXT,
            category="go_to_place",
            description=description,
            id=id,
        )
        self.session.send_foreign(goal)

    def begin(self) -> None:
        self.tick(4.0)
        self.session.begin('{"category": "patrol", "detail": "rounds of the ward"}', event_id=5)

    def stubborn(self) -> None:
        self.session.request_next("go_to_place", '{"place": "lobby"}', stubborn_period=0.5)
        self.session.run()
        for x in (4.0, 4.02, 5.5, 5.5):  # held still, a small drift, a move: re-anchored, then held
            self.session.advance(1)
            self.tick(x)

    def wrong_cancel(self) -> None:
        self.session.request_next("go_to_place", '"charger"')
        self.session.advance(0.5)
        running = self.session.server.running
        wrong = (running.child_id if running is not None else 0) + 40
        seq = self.session.client.seq
        self.session.send_foreign(Goal(dynamic_event_seq=seq, event_type=EventType.CANCEL, id=wrong))

    def race(self) -> None:
        self.session.request_next("go_to_place", '"kitchen"')
        self.foreign_next("loading_bay", 100)

    def after_end(self) -> None:
        self.session.request_next("go_to_place", '"pantry"')  # the client knows the run is over
        self.foreign_next("pantry", 200)


def session_events(seed: int) -> list[tuple[int, TimelineEvent]]:
    """Run the scripted session; every timeline event with the index of its step in :data:`STEPS`."""
    script = _Script(seed)
    session = script.session
    script.chapter(0, script.begin)
    script.chapter(1, lambda: session.request_next("go_to_place", '"pantry"'))
    script.chapter(2, script.stubborn)
    script.chapter(3, script.wrong_cancel)
    script.chapter(4, session.request_cancel)
    script.chapter(5, script.race)
    script.chapter(6, session.request_finish)
    script.chapter(7, script.after_end)
    return script.tagged


def run_demo(seed: int = 0, *, json_lines: bool = False) -> str:
    """The demo's output for ``seed``: a readable timeline, or one JSON object per line."""
    tagged = session_events(seed)
    if json_lines:
        lines = []
        for index, event in tagged:
            record = {"step": index + 1, **event.to_dict()}
            lines.append(_json.dumps(record) + "\n")
        return "".join(lines)
    parts = [
        f"dynevent demo: robot tinyRobot/tinyRobot1, a client machine and a server machine in a\n"
        f"simulated session (seed {seed})\n\n",
        "\n".join(_LEGEND) + "\n\n",
        f"{'time':>7}  {'who':<4}  {'event':<16}  what  => decision\n",
    ]
    for index, caption in enumerate(STEPS):
        parts.append(f"\n-- {index + 1}. {caption}\n")
        for step, event in tagged:
            if step == index:
                parts.extend(line + "\n" for line in _text_lines(event))
    parts.append("\n" + "\n".join(summary(tagged)) + "\n")
    return "".join(parts)


#: Inputs the adapter gives the server (arrows to the server); every other adapter event is an output.
_ADAPTER_INPUTS = frozenset(ins.INPUT_TYPES)


def mermaid(seed: int = 0) -> str:
    """The session of ``seed`` as a Mermaid sequence diagram (GitHub and most doc sites draw it)."""
    lines = [
        "sequenceDiagram",
        "    participant C as Client",
        "    participant S as Server (tinyRobot1)",
        "    participant A as Fleet adapter",
    ]
    tagged = session_events(seed)
    step = -1
    for index, event in tagged:
        if index != step:
            step = index
            lines.append(f"    Note over C,A: {index + 1}. {_mermaid_text(STEPS[index])}")
        text = _mermaid_text(f"{event.kind} {event.summary}".strip())
        decision = _mermaid_text(event.decision)
        if event.direction == "client->server":
            lines.append(f"    C->>S: {text}")
            if decision.startswith("rejected"):
                lines.append(f"    S--xC: {decision}")
        elif event.direction == "server->client":
            lines.append(f"    S-->>C: {text}")
        elif event.direction == "adapter":
            lines.append(f"    A->>S: {text}" if event.kind in _ADAPTER_INPUTS else f"    S->>A: {text}")
            if _lost_race(event):
                lines.append(f"    Note over S: {decision}")
        elif decision.startswith(("outcome", "refused")):
            lines.append(f"    Note over C: {decision}")
    return "\n".join(lines) + "\n"


def _mermaid_text(text: str) -> str:
    """A message text Mermaid takes literally: no statement separators, comments or entity codes."""
    for bad, good in ((";", ","), ("#", "no."), ("%%", "%"), ("\n", " ")):
        text = text.replace(bad, good)
    return text if len(text) <= 90 else text[:87] + "..."


def run(args: argparse.Namespace) -> int:
    """``dynevent demo``: print the session for ``--seed``, as a timeline, JSON lines or Mermaid; 0."""
    if args.mermaid:
        print(mermaid(args.seed), end="")
    else:
        print(run_demo(args.seed, json_lines=args.json), end="")
    return 0
