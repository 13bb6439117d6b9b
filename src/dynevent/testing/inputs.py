"""The values the kit generates, and plain strategies of well-typed inputs (:func:`server_inputs`,
:func:`input_sequences`) for tests that need no model.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import attrs
from hypothesis import strategies as st

from dynevent.server import inputs as ins
from dynevent.wire._fields import SECOND, U32_MAX, U64_MAX
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import (
    Status,
    Tier,
)

__all__ = [
    "BEGIN_DESCRIPTIONS",
    "DESCRIPTIONS",
    "NON_FINITE",
    "NOT_JSON",
    "STATUSES",
    "STUBBORN_PERIODS",
    "input_sequences",
    "server_inputs",
]


_MS = 1_000_000
#: Descriptions the generators choose from; which are valid depends on the category's rule.
DESCRIPTIONS: tuple[str, ...] = (
    '{"place": "pantry"}',
    '{"place": "lobby", "speed": 0.5, "custom": {"keep": [1, 2, null]}}',
    '{"action": "clean", "parameters": {"zone": "A"}}',
    '"dock"',
    "[1, 2, 3]",
    "{}",
    "42",
    '{"place": NaN}',
)
#: Text that is not JSON as R4.9 reads it (duplicate keys and deep nesting included).
NOT_JSON: tuple[str, ...] = (
    "",
    "{",
    "not json",
    '{"place": "a", "place": "b"}',
    "[" * 65 + "]" * 65,
    "{'place': 'pantry'}",
    '{"place": "pantry"} trailing',
)
BEGIN_DESCRIPTIONS: tuple[str, ...] = (
    "{}",
    '{"category": "patrol"}',
    '{"detail": "inspect", "parameters": [1, {"a": null}], "custom_field": true}',
    '{"estimate": {"category": "go_to_place", "description": {"place": "lobby"}}, '
    '"required": [{"category": "perform_action", "description": "x"}]}',
)
STUBBORN_PERIODS: tuple[float, ...] = (0.0, 0.0, 0.0, -1.0, 0.5, 1.0, 2.0, 2.5, 10.0)
NON_FINITE: tuple[float, ...] = (math.nan, math.inf, -math.inf)
STATUSES: tuple[str, ...] = tuple(status.value for status in Status)


def _same(event: ins.Input) -> ins.Input:
    return event


#: The inputs :func:`server_inputs` draws with a time and nothing else (shutdown aside).
_TIMED_ONLY: tuple[type[ins.Input], ...] = (ins.Interrupt, ins.Resume, ins.DescriptionQuery, ins.IdDrawn)


def _goals(categories: Sequence[str], seq: int) -> st.SearchStrategy[Goal]:
    """Goals from small pools: seqs mostly ``seq``, the common event types, valid and hostile fields."""
    return st.builds(
        Goal,
        dynamic_event_seq=st.sampled_from((*(seq,) * 8, (seq + 1) & U32_MAX, (seq - 1) & U32_MAX, 0)),
        event_type=st.sampled_from((1, 1, 1, 1, 2, 2, 3, 0, 4)),
        category=st.sampled_from((*categories, *categories, "unknown")),
        description=st.sampled_from((DESCRIPTIONS[0],) * 4 + DESCRIPTIONS + NOT_JSON[:4]),
        id=st.one_of(st.integers(1, 8), st.sampled_from((0, U64_MAX))),
        stubborn_period=st.sampled_from(STUBBORN_PERIODS + NON_FINITE),
    )


def server_inputs(
    categories: Sequence[str] = ("go_to_place", "perform_action"),
    *,
    uuids: int = 4,
    seq: int = 1,
    now: st.SearchStrategy[int] | None = None,
    shutdown: bool = True,
) -> st.SearchStrategy[ins.Input]:
    """Any input, drawn from small pools so that random sequences meet often.

    Goal UUIDs come from ``uuids`` fixed values; goal seqs are mostly
    ``seq`` (the run the goals are aimed at), sometimes its neighbours or 0;
    ids come from a handful of small values (and 0 and the largest),
    descriptions and stubborn periods from valid and hostile pools.  Goal
    requests and starts are drawn more often than other inputs.  With
    ``shutdown``, about one input in forty is a shutdown.
    """
    times = now if now is not None else st.integers(0, 20 * SECOND)
    uuid = st.sampled_from([f"{index:032x}" for index in range(1, uuids + 1)])
    goal = _goals(categories, seq)
    status = st.sampled_from(STATUSES)
    request = st.builds(ins.GoalRequested, goal_uuid=uuid, goal=goal, now=times)
    start = st.builds(ins.GoalStarted, goal_uuid=uuid, now=times)
    progress = st.builds(
        ins.ChildProgress,
        status=status,
        now=times,
        log_text=st.one_of(st.none(), st.just("progress")),
        tier=st.sampled_from(tuple(Tier)),
    )
    finished = st.builds(ins.ChildFinished, status=status, now=times)
    begin = st.builds(
        ins.Begin,
        description=st.sampled_from(BEGIN_DESCRIPTIONS),
        event_id=st.sampled_from((0, 0, 1, 4, U64_MAX)),
        now=times,
    )
    kinds: dict[str, tuple[int, st.SearchStrategy[ins.Input]]] = {  # weight, strategy
        "begin": (1, begin),
        "request": (4, request),
        "start": (4, start),
        "cancel": (1, st.builds(ins.CancelRequested, goal_uuid=uuid, now=times)),
        "progress": (2, progress),
        "finished": (2, finished),
        "tick": (
            1,
            st.builds(
                ins.Tick,
                now=times,
                map_name=st.sampled_from(("L1", "L2")),
                x=st.sampled_from((0.0, 0.05, 1.0)),
                y=st.just(0.0),
            ),
        ),
        "signal": (1, st.one_of(st.builds(ins.TaskCancel, now=times), st.builds(ins.TaskKill, now=times))),
        # the inputs that carry a time alone: interrupt, resume, describe, an id the adapter draws
        **{kind.KIND: (1, st.builds(kind, now=times)) for kind in _TIMED_ONLY},
    }
    # one_of draws its branches alike (and merges equal ones): a weight is that many distinct copies
    common: st.SearchStrategy[ins.Input] = st.one_of(
        [strategy.map(_same) for weight, strategy in kinds.values() for _ in range(weight)]
    )
    if not shutdown:
        return common
    # shutdown ends everything: about one input in forty
    return st.tuples(st.integers(0, 39), common, times).map(
        lambda drawn: ins.Shutdown(now=drawn[2]) if drawn[0] == 23 else drawn[1]
    )


@st.composite
def input_sequences(
    draw: st.DrawFn,
    categories: Sequence[str] = ("go_to_place", "perform_action"),
    *,
    max_size: int = 40,
) -> list[ins.Input]:
    """Up to ``max_size`` inputs of :func:`server_inputs`, in runs; ``now`` never goes back.

    The sequence is cut into one to four runs, each a begin followed by
    inputs whose goals are aimed at that run's seq (the seq the run has when
    every earlier begin took effect), and often closed by a task cancel or
    kill so that the next begin takes effect; about one sequence in ten ends
    with a shutdown.
    """
    runs = draw(st.integers(1, 4), label="runs")
    size = max(max_size // runs - 2, 1)
    events: list[ins.Input] = []
    for run in range(1, runs + 1):
        events.append(ins.Begin(description="{}", event_id=draw(st.sampled_from((0, 1, 5))), now=0))
        body = server_inputs(categories, seq=run, now=st.just(0), shutdown=False)
        events.extend(draw(st.lists(body, min_size=size // 2, max_size=size), label=f"run {run}"))
        ending = draw(st.sampled_from(("kill", "cancel", "none")), label="ending")
        if ending == "kill":
            events.append(ins.TaskKill(now=0))
        elif ending == "cancel":
            events.append(ins.TaskCancel(now=0))
    if draw(st.integers(0, 9), label="shut down") == 7:
        events.append(ins.Shutdown(now=0))
    steps = draw(
        st.lists(
            st.sampled_from((0, _MS, 400 * _MS, SECOND, 2 * SECOND)),
            min_size=len(events),
            max_size=len(events),
        ),
        label="time steps",
    )
    now = 1_700_000_000 * SECOND
    result: list[ins.Input] = []
    for event, step in zip(events, steps, strict=True):
        now += step
        result.append(attrs.evolve(event, now=now))
    return result
