"""The cost of a NEXT's judgement per KB of its description, for the costliest shapes known (R4.19).

Run ``python bench/hostile_goals.py`` (``--quick`` for a few samples) from a
virtual environment with the ``descriptions`` extra.  Every shape is a NEXT
judged by ``machine.accept`` under a configuration of the field's categories
(``descriptions.Robot``), as ``dynevent serve --config`` builds it: a robot of
2,000 places for the hostile shapes, and the peer they are measured against,
the check of valid places (30,000 names on a robot of 30,000 places), which
must read every byte of its goal and is the linear bound every shape is held to.

The table gives, per shape, the description's size, the median time of one
``accept``, the time per KB, and the ratio of that to the peer's time per KB
(at most about 1 is within the bound; the implementations take turns, as in
bench/run.py).  Before timing, each shape is checked to be refused (or, for the
peer, accepted) for the reason it is built for.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from dynevent import SECOND, EventType, Goal, ServerConfig, State, accept, inputs, outputs, step  # noqa: E402
from dynevent.descriptions import Robot  # noqa: E402

#: A robot of this many places judges the hostile shapes.
PLACES = 2_000
#: The peer's robot and goal: this many valid places.
PEER_PLACES = 30_000


def _names(count: int) -> list[str]:
    return [f"place_{number:05d}" for number in range(count)]


def _nested_sequence(depth: int) -> Any:
    description: Any = {"one_of": ["nowhere"]}
    category = "go_to_place"
    for _ in range(depth):
        description = [{"category": category, "description": description}]
        category = "sequence"
    return description


#: (name, category, description, accepted): each hostile shape within the accepted size.
def shapes() -> list[tuple[str, str, Any, bool]]:
    names = _names(PLACES)
    return [
        ("300 near-miss names", "go_to_place", {"one_of": [name[:-1] + "x" for name in names[:300]]}, False),
        (
            "30,000 near-miss names",
            "go_to_place",
            {"one_of": [f"plaec_{n:05d}" for n in range(30_000)]},
            False,
        ),
        ("30,000 non-places", "go_to_place", {"one_of": [number + 0.5 for number in range(30_000)]}, False),
        ("30,000 waypoints off the map", "go_to_place", {"one_of": list(range(5_000, 35_000))}, False),
        (
            "10,000 bad payload items",
            "pickup",
            {"place": names[0], "payload": [{"sku": n} for n in range(10_000)]},
            False,
        ),
        ("sequences 31 deep", "sequence", _nested_sequence(31), False),
        (
            "2,000 activities off the map",
            "sequence",
            [{"category": "go_to_place", "description": f"nowhere_{n}"} for n in range(2_000)],
            False,
        ),
    ]


def _state(config: ServerConfig) -> State:
    state = State.new("fleet", "robot")
    return step(state, inputs.Begin(description="{}", event_id=1, now=SECOND), config).state


def _goal(category: str, description: Any) -> Goal:
    text = json.dumps(description, separators=(",", ":"))
    return Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category=category, description=text, id=2)


def _timer(config: ServerConfig, goal: Goal, accepted: bool) -> Callable[[], float]:
    state = _state(config)
    decision = accept(state, goal, config)
    assert isinstance(decision, outputs.Accepted) == accepted, (goal.description[:80], decision)

    def once() -> float:
        started = time.perf_counter_ns()
        accept(state, goal, config)
        return (time.perf_counter_ns() - started) / 1e6

    return once


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a few samples (for CI)")
    args = parser.parse_args(argv)
    repeats = 3 if args.quick else 15
    hostile = ServerConfig(categories=Robot(places=_names(PLACES)).validators())
    peer_config = ServerConfig(categories=Robot(places=_names(PEER_PLACES)).validators())
    peer_goal = _goal("go_to_place", {"one_of": _names(PEER_PLACES)})
    rows = [("peer: 30,000 valid places", peer_goal, _timer(peer_config, peer_goal, True))]
    for name, category, description, accepted in shapes():
        goal = _goal(category, description)
        rows.append((name, goal, _timer(hostile, goal, accepted)))
    samples: dict[str, list[float]] = {name: [] for name, _, _ in rows}
    for repeat in range(repeats):
        for name, _, once in rows[repeat % len(rows) :] + rows[: repeat % len(rows)]:
            samples[name].append(once())
    peer_name, peer, _ = rows[0]
    peer_per_kb = statistics.median(samples[peer_name]) / (len(peer.description) / 1000)
    print(f"{'shape':32} {'size':>9} {'per accept':>12} {'per KB':>10} {'/ peer per KB':>14}")
    for name, goal, _ in rows:
        size = len(goal.description)
        median = statistics.median(samples[name])
        per_kb = median / (size / 1000)
        ratio = per_kb / peer_per_kb
        print(f"{name:32} {size / 1000:7.1f}KB {median:9.2f} ms {per_kb * 1000:7.1f} us {ratio:14.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
