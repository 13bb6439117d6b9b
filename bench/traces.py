"""Long, clean traces for ``dynevent check``: a run of many child cycles, as a tap at the server writes it.

Each cycle is a NEXT goal requested, started, reporting progress with a log
line, and completed; every goal has its own UUID.  The records are produced
one at a time, so a trace of any length can be written without holding it.
"""

from __future__ import annotations

from collections.abc import Iterator

from dynevent.conformance.judge import step_records
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.wire import _json
from dynevent.wire.messages import Goal

FLEET, ROBOT = "tinyRobot", "tinyRobot1"
CONFIG = {
    "type": "config",
    "fleet": FLEET,
    "robot": ROBOT,
    "config": {"categories": {"go_to_place": [{"accept": "any"}]}},
}
_MS = 1_000_000


def cycle_lines(cycles: int) -> Iterator[str]:
    """The JSON lines of a trace of ``cycles`` child cycles (7 records, about 1.1 KB, each)."""
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description})
    state = machine.State.new(FLEET, ROBOT)
    yield _json.dumps(CONFIG) + "\n"
    now = 1_000 * _MS

    def step(event: ins.Input) -> Iterator[str]:
        nonlocal state
        transition = machine.step(state, event, config)
        state = transition.state
        for row in step_records(event, transition.outputs):
            yield _json.dumps(row) + "\n"

    yield from step(ins.Begin(description='{"category": "patrol"}', event_id=1, now=now))
    for index in range(cycles):
        uuid = f"{index:032x}"
        goal = Goal(
            dynamic_event_seq=state.seq,
            event_type=1,
            category="go_to_place",
            description='{"place": "pantry"}',
            id=state.last_id + 1,
        )
        now += 10 * _MS
        yield from step(ins.GoalRequested(goal_uuid=uuid, goal=goal, now=now))
        now += 5 * _MS
        yield from step(ins.GoalStarted(goal_uuid=uuid, now=now))
        now += 100 * _MS
        yield from step(ins.ChildProgress(status="underway", log_text="on the way", now=now))
        now += 100 * _MS
        yield from step(ins.ChildFinished(status="completed", now=now))
