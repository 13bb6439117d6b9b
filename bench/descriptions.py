"""The description check of every NEXT (R4.18), beside the JSON Schema validators that could do it.

Run ``python bench/descriptions.py`` (``--quick`` for a few samples) from a
virtual environment with the ``bench`` extra.  Each implementation checks the
same descriptions against the same schemas (the project's own,
``src/dynevent/descriptions/schemas``, whose verdicts the test suite proves
equal to the fleet adapter's schema text's):

- ``dynevent``: ``Robot().check`` (the compiled verdict; the reasons, from
  ``jsonschema``, only for a refusal);
- ``jsonschema``: a ``Draft202012Validator`` built once, ``is_valid`` (and
  ``iter_errors`` for a refusal, as a server must say why);
- ``fastjsonschema``: the schema compiled once to Python code (draft 7
  semantics, which these schemas do not tell apart from 2020-12's).

Before timing, every implementation's verdict is checked against dynevent's
on every description: a peer that disagreed would be measured doing other
work.  Method as bench/run.py's: the implementations take turns, a sample
times ``ops`` checks with ``time.perf_counter_ns``; the table gives the
median time per check and the spread (interquartile range / median).
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from dynevent import descriptions  # noqa: E402
from dynevent.descriptions import shapes  # noqa: E402

#: Workloads: (name, category, descriptions).  The everyday go_to_place shapes of the field, valid.
WORKLOADS: list[tuple[str, str, list[Any]]] = [
    (
        "go_to_place, valid",
        "go_to_place",
        [
            "pantry",
            3,
            {"waypoint": "pantry", "orientation": 1.57},
            {"place": "pantry"},
            {"place": {"waypoint": 4, "orientation": 0.0}, "followed_by": ["lobby", 7]},
            {"one_of": ["pantry", "lobby", {"waypoint": 2}]},
        ],
    ),
    (
        "go_to_place, refused (with reasons)",
        "go_to_place",
        [
            {"one_of": ["A", 5.5]},
            {"place": "A", "followed_by": [1.5]},
            {"place": "A", "start_at_departure": "x"},
        ],
    ),
    (
        "perform_action, valid",
        "perform_action",
        [{"category": "wave", "description": {"arm": "left"}, "unix_millis_action_duration_estimate": 2000}],
    ),
    (
        "sequence of 3, valid",
        "sequence",
        [
            {
                "activities": [
                    {"category": "go_to_place", "description": {"one_of": ["pantry"]}},
                    {"category": "perform_action", "description": {"category": "wave", "description": {}}},
                    {"category": "go_to_place", "description": 3},
                ]
            }
        ],
    ),
]

Check = Callable[[str, Any], bool]


def dynevent_check() -> Check:
    robot = descriptions.Robot()
    return lambda category, description: not robot.check(category, description)


def jsonschema_check() -> Check:
    import jsonschema
    import referencing

    registry: Any = referencing.Registry().with_resources(
        (name, referencing.Resource.from_contents(schema)) for name, schema in shapes.schemas().items()
    )
    validators = {
        category: jsonschema.Draft202012Validator(shapes.schema(category), registry=registry)
        for category in descriptions.CATEGORIES
    }

    def check(category: str, description: Any) -> bool:
        validator = validators[category]
        if validator.is_valid(description):
            return True
        list(validator.iter_errors(description))  # a refusal says why
        return False

    return check


def fastjsonschema_check() -> Check:
    import fastjsonschema

    base = "https://dynevent.invalid/schemas/"  # a base its resolver joins "place.json" to; never fetched
    store = dict(shapes.schemas())
    compiled = {
        category: fastjsonschema.compile(
            {**shapes.schema(category), "$id": f"{base}{category}.json"},
            handlers={"https": lambda uri: store[uri.removeprefix(base)]},
            use_default=False,  # else it writes "start_at_departure": false into the description
        )
        for category in ("go_to_place", "perform_action")
    }

    def check(category: str, description: Any) -> bool:
        try:
            compiled[category](description)
        except fastjsonschema.JsonSchemaValueException:
            return False
        return True

    return check


IMPLEMENTATIONS: dict[str, Callable[[], Check]] = {
    "dynevent": dynevent_check,
    "jsonschema": jsonschema_check,
    "fastjsonschema": fastjsonschema_check,
}


def available() -> dict[str, Check]:
    found = {}
    for name, make in IMPLEMENTATIONS.items():
        try:
            found[name] = make()
        except ImportError:
            print(f"note: {name} is not installed; it is left out", file=sys.stderr)
    return found


def honest(checks: dict[str, Check]) -> None:
    """Every implementation gives dynevent's verdict on every description it is timed on."""
    reference = checks["dynevent"]
    for _, category, items in WORKLOADS:
        for name, check in checks.items():
            if name == "fastjsonschema" and category == "sequence":
                continue  # a sequence's activities are checked by the robot, not by a schema alone
            for description in items:
                assert check(category, description) == reference(category, description), (name, description)


def sample(check: Check, category: str, items: list[Any], ops: int) -> float:
    """Nanoseconds per check over ``ops`` checks (cycling through ``items``)."""
    count = len(items)
    started = time.perf_counter_ns()
    for number in range(ops):
        check(category, items[number % count])
    return (time.perf_counter_ns() - started) / ops


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a few samples (for CI)")
    args = parser.parse_args(argv)
    repeats, ops = (3, 200) if args.quick else (15, 3_000)
    checks = available()
    honest(checks)
    print(f"{'workload':40} {'implementation':16} {'per check':>12} {'spread':>8} {'dynevent/peer':>14}")
    for workload, category, items in WORKLOADS:
        names = [name for name in checks if not (name == "fastjsonschema" and category == "sequence")]
        samples: dict[str, list[float]] = {name: [] for name in names}
        for repeat in range(repeats):
            for name in names[repeat % len(names) :] + names[: repeat % len(names)]:
                samples[name].append(sample(checks[name], category, items, ops))
        medians = {name: statistics.median(values) for name, values in samples.items()}
        for name in names:
            values = sorted(samples[name])
            spread = (values[(3 * len(values)) // 4] - values[len(values) // 4]) / medians[name] * 100
            ratio = "" if name == "dynevent" else f"{medians['dynevent'] / medians[name]:.3f}"
            print(f"{workload:40} {name:16} {medians[name] / 1000:9.2f} us {spread:7.0f}% {ratio:>14}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
