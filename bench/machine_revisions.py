"""The machine against an earlier revision of itself, in one process: is it any slower?

Run ``python bench/machine_revisions.py [--base REV] [--quick]`` in a git checkout.  The machine of
``REV`` (default: the revision before the one-oracle change, b54d329) is read with ``git show``
into a module of its own beside today's, and both do the same work, taking turns sample by
sample: ``accept`` of a NEXT and of a CANCEL, and a child's whole cycle (request, start, progress
with a log line, end: four steps).  The table gives the median time per operation and the ratio
today / base (below 1: today is faster).  ``--section`` writes it into bench/results.md.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench.results import machine_description, write_section  # noqa: E402
from dynevent import SECOND, EventType, Goal  # noqa: E402
from dynevent.server import inputs as ins  # noqa: E402
from dynevent.server import machine as today  # noqa: E402

BASE = "b54d329"
MACHINE = "src/dynevent/server/machine.py"


def load_base(revision: str) -> ModuleType:
    """The machine module of ``revision``, loaded under its own name beside today's."""
    source = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{revision}:{MACHINE}"], capture_output=True, text=True, check=True
    ).stdout
    # an input added since the revision (R17.8's id_drawn) has no handler there, and no workload here
    # sends one: the old lookup table leaves it out rather than failing on it
    source = source.replace(
        "HANDLERS[cls.KIND] for cls in typing.get_args(ins.Input)}",
        "HANDLERS[cls.KIND] for cls in typing.get_args(ins.Input) if cls.KIND in HANDLERS}",
    )
    spec = importlib.util.spec_from_loader("dynevent.server._machine_base", loader=None)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    exec(compile(source, f"{revision}:{MACHINE}", "exec"), module.__dict__)
    return module


def workloads(machine: ModuleType) -> dict[str, tuple[Callable[[], object], int]]:
    """Per workload: one operation, and how many operations it does."""
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description})
    waiting = machine.step(
        machine.State.new("f", "r"), ins.Begin(description="{}", event_id=1, now=SECOND), config
    ).state
    next_goal = Goal(
        dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description='"pantry"', id=2
    )
    cancel = Goal(dynamic_event_seq=1, event_type=EventType.CANCEL, id=5)

    def cycles() -> None:
        state = waiting
        for number in range(2, 22):
            goal = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place",
                        description='"pantry"', id=number)  # fmt: skip
            uuid = f"{number:032x}"
            now = number * SECOND
            state = machine.step(state, ins.GoalRequested(goal_uuid=uuid, goal=goal, now=now), config).state
            state = machine.step(state, ins.GoalStarted(goal_uuid=uuid, now=now), config).state
            state = machine.step(
                state, ins.ChildProgress(status="underway", now=now, log_text="x"), config
            ).state
            state = machine.step(state, ins.ChildFinished(status="completed", now=now + 1), config).state

    return {
        "accept: a NEXT with a small JSON description": (
            lambda: machine.accept(waiting, next_goal, config),
            1,
        ),
        "accept: a CANCEL while no child runs": (lambda: machine.accept(waiting, cancel, config), 1),
        "a child's whole cycle (4 steps)": (cycles, 20),
    }


def measure(base: ModuleType, samples: int, ops: int) -> list[tuple[str, float, float]]:
    mine, theirs = workloads(today), workloads(base)
    rows = []
    for name in mine:
        times: dict[str, list[float]] = {"today": [], "base": []}
        for _ in range(samples):
            for label, (work, count) in (("today", mine[name]), ("base", theirs[name])):
                started = time.perf_counter_ns()
                for _ in range(ops):
                    work()
                times[label].append((time.perf_counter_ns() - started) / ops / count / 1000)
        rows.append((name, statistics.median(times["today"]), statistics.median(times["base"])))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--base", default=BASE, help=f"the revision to compare with (default {BASE})")
    parser.add_argument("--quick", action="store_true", help="a few samples (for CI)")
    parser.add_argument("--section", help="write the table as this section of bench/results.md")
    options = parser.parse_args()
    samples, ops = (3, 200) if options.quick else (15, 2000)
    rows = measure(load_base(options.base), samples, ops)
    lines = [
        f"The machine of today beside that of {options.base}, in one process, taking turns "
        f"({samples} samples; median per operation).",
        "",
        f"| workload | today | {options.base} | today / {options.base} |",
        "|---|---|---|---|",
    ]
    lines += [f"| {name} | {mine:.2f} µs | {base:.2f} µs | {mine / base:.2f} |" for name, mine, base in rows]
    text = "\n".join(lines)
    print(text)
    if options.section:
        heading = ["## The machine against an earlier revision (bench/machine_revisions.py)", ""]
        write_section(options.section, heading + machine_description(["dynevent"]) + ["", *lines])


if __name__ == "__main__":
    main()
