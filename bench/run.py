"""dynevent's benchmarks: every workload, every implementation, interleaved in one process.

Run ``python bench/run.py`` (full) or ``python bench/run.py --quick`` (a few
repeats of each workload, for CI), from a virtual environment with the
``bench`` extra for the ``transitions`` and ``python-statemachine`` peers (a
peer whose library is missing is left out).  Prints each workload's median
and spread per implementation and the ratios dynevent/peer, and writes
bench/results.md.  ``--profile`` prints cProfile's view of dynevent's progress
update and full child cycle instead.

Method: for each repeat, the implementations take turns (in a rotated order)
at one sample of each workload; a sample builds its fixtures outside the
timed region, then times ``ops`` operations with ``time.perf_counter_ns`` and
records the time per operation.  The table gives the median of the samples
and their spread (the interquartile range as a percentage of the median).
Memory is measured with ``tracemalloc`` (allocations while building the
objects; names are built beforehand, since the adapter holds them anyway).

Only the standard library is used, plus the peers' libraries.
"""

from __future__ import annotations

import argparse
import cProfile
import gc
import importlib
import importlib.metadata
import io
import json
import pstats
import random
import statistics
import sys
import time
import tracemalloc
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script: make `bench` importable
    sys.path.insert(0, str(ROOT))

import attrs  # noqa: E402

from bench import results  # noqa: E402
from bench.peers.rules import parse as strict_json  # noqa: E402
from bench.peers.script import (  # noqa: E402
    CATEGORIES,
    DESCRIPTION,
    EVENT_DESCRIPTION,
    DyneventDriver,
    child_cycle,
    uuid,
    whole_event,
)
from dynevent.server import inputs as ins  # noqa: E402
from dynevent.server import machine, snapshot  # noqa: E402
from dynevent.server.fleet import Fleet  # noqa: E402
from dynevent.server.machine import ServerConfig, State  # noqa: E402
from dynevent.wire.names import action_name  # noqa: E402

IMPLEMENTATIONS = ("dynevent", "tuples", "transitions", "statemachine")
PEERS = ("tuples", "transitions", "statemachine")
_PEER_MODULES = {
    "tuples": ("bench.peers.tuples", "TupleServer"),
    "transitions": ("bench.peers.with_transitions", "TransitionsServer"),
    "statemachine": ("bench.peers.with_statemachine", "StatemachineServer"),
}
_LIBRARIES = {"transitions": "transitions", "statemachine": "python-statemachine"}
NOW = 1_700_000_000 * 1_000_000_000
CONFIG = ServerConfig(categories=CATEGORIES)

Run = Callable[[], Any]
Prepare = Callable[[], tuple[Run, int]]


@dataclass(frozen=True)
class Sizes:
    """How much each sample does, and how many samples."""

    repeats: int
    accept: int
    cycles: int
    progress: int
    routing: int
    snapshots: int
    fleets: tuple[int, ...]
    library_fleets: tuple[int, ...]
    snapshot_fleet: int
    memory_states: int
    memory_fleet: int
    library_memory_fleet: int


FULL = Sizes(
    repeats=15,
    accept=2_000,
    cycles=200,
    progress=2_000,
    routing=2_000,
    snapshots=200,
    fleets=(10, 1_000, 100_000),
    library_fleets=(10, 1_000),
    snapshot_fleet=10_000,
    memory_states=1_000,
    memory_fleet=100_000,
    library_memory_fleet=1_000,
)
QUICK = Sizes(
    repeats=3,
    accept=200,
    cycles=20,
    progress=200,
    routing=500,
    snapshots=20,
    fleets=(10, 1_000, 100_000),
    library_fleets=(10, 1_000),
    snapshot_fleet=10_000,
    memory_states=200,
    memory_fleet=100_000,
    library_memory_fleet=200,
)


# --------------------------------------------------------------------------- implementations


def peer_class(name: str) -> Any:
    module, cls = _PEER_MODULES[name]
    return getattr(importlib.import_module(module), cls)


def available() -> list[str]:
    """The implementations whose libraries are installed."""
    found = ["dynevent", "tuples"]
    for name in ("transitions", "statemachine"):
        try:
            peer_class(name)
        except ImportError:
            print(f"note: {_LIBRARIES[name]} is not installed; its peer is left out", file=sys.stderr)
        else:
            found.append(name)
    return found


def new_driver(impl: str, fleet: str = "fleet", robot: str = "robot") -> Any:
    """A fresh server of ``impl`` for one robot (dynevent through its RobotServer)."""
    if impl == "dynevent":
        return DyneventDriver(fleet, robot)
    return peer_class(impl)(fleet, robot, CATEGORIES)


def waiting(impl: str, fleet: str = "fleet", robot: str = "robot") -> Any:
    """A server with an active dynamic event (seq 1, event id 10) and no child."""
    driver = new_driver(impl, fleet, robot)
    driver.begin(10, EVENT_DESCRIPTION, NOW)
    return driver


def running(impl: str, fleet: str = "fleet", robot: str = "robot") -> Any:
    """A server whose child 11 runs, started by goal 1."""
    driver = waiting(impl, fleet, robot)
    driver.request(uuid(1), (1, 1, "go_to_place", DESCRIPTION, 11, 0.0), NOW)
    driver.start(uuid(1), NOW)
    return driver


# --------------------------------------------------------------------------- workloads


@dataclass
class Workload:
    """One row of the table: a fixture builder per implementation."""

    key: str
    title: str
    prepare: dict[str, Prepare]
    samples: dict[str, list[float]] = field(default_factory=dict)


def _accept_next(impl: str, sizes: Sizes) -> Prepare:
    raw = (1, 1, "go_to_place", DESCRIPTION, 11, 0.0)

    def prepare() -> tuple[Run, int]:
        driver = waiting(impl)
        n = sizes.accept
        if impl == "dynevent":
            server, goal = (
                driver.server,
                DyneventDriver.goal,
            )  # the Goal built from raw values, as peers check them

            def run() -> None:
                for _ in range(n):
                    server.accept(goal(raw))

            return run, n
        accept = driver.accept

        def run_peer() -> None:
            for _ in range(n):
                accept(raw)

        return run_peer, n

    return prepare


def _accept_cancel(impl: str, sizes: Sizes) -> Prepare:
    raw = (1, 2, "", "", 11, 0.0)

    def prepare() -> tuple[Run, int]:
        driver = running(impl)
        n = sizes.accept
        if impl == "dynevent":
            server, goal = (
                driver.server,
                DyneventDriver.goal,
            )  # the Goal built from raw values, as peers check them

            def run() -> None:
                for _ in range(n):
                    server.accept(goal(raw))

            return run, n
        accept = driver.accept

        def run_peer() -> None:
            for _ in range(n):
                accept(raw)

        return run_peer, n

    return prepare


def _calls(
    driver: Any, events: Sequence[tuple[Any, ...]]
) -> list[tuple[Callable[..., Any], tuple[Any, ...]]]:
    """The bound method and arguments of each event, so that no dispatch is timed."""
    return [(getattr(driver, kind), (*values, NOW + index)) for index, (kind, *values) in enumerate(events)]


def _child_cycles(impl: str, sizes: Sizes) -> Prepare:
    def prepare() -> tuple[Run, int]:
        driver = waiting(impl)
        n = sizes.cycles
        events = [event for k in range(n) for event in child_cycle(1, 100 + k, uuid(100 + k))]
        calls = _calls(driver, events)

        def run() -> None:
            for method, args in calls:
                method(*args)

        return run, n

    return prepare


def _progress(impl: str, sizes: Sizes) -> Prepare:
    def prepare() -> tuple[Run, int]:
        driver = running(impl)
        n = sizes.progress
        progress = driver.progress

        def run() -> None:
            for k in range(n):
                progress("underway", "moving along", "info", NOW + k)

        return run, n

    return prepare


def _progress_step_only(sizes: Sizes) -> Prepare:
    def prepare() -> tuple[Run, int]:
        state = running("dynevent").server.state
        event = ins.ChildProgress(status="underway", log_text="moving along", now=NOW)
        n = sizes.progress
        step = machine.step

        def run() -> None:
            current = state
            for _ in range(n):
                current = step(current, event, CONFIG).state

        return run, n

    return prepare


def _whole_event(impl: str, sizes: Sizes) -> Prepare:
    events = whole_event(100)

    def prepare() -> tuple[Run, int]:
        calls = _calls(new_driver(impl), events)

        def run() -> None:
            for method, args in calls:
                method(*args)

        return run, 1

    return prepare


# fleets are built once per (implementation, size) and reused by every sample
_FLEETS: dict[tuple[str, int], Any] = {}


def _robot_names(count: int) -> list[tuple[str, str]]:
    return [(f"fleet_{index % 10}", f"robot_{index}") for index in range(count)]


def running_fleet(impl: str, count: int) -> Any:
    """A fleet of ``count`` robots, each running a child: a dynevent Fleet, or a dict of peers."""
    key = (impl, count)
    if key not in _FLEETS:
        names = _robot_names(count)
        if impl == "dynevent":
            template = running("dynevent", "fleet_0", "robot_0").server.state
            fleet = Fleet(CONFIG)
            for fleet_name, robot in names:
                fleet.add(fleet_name, robot, state=attrs.evolve(template, fleet=fleet_name, robot=robot))
            _FLEETS[key] = fleet
        else:
            _FLEETS[key] = {
                (fleet_name, robot): running(impl, fleet_name, robot) for fleet_name, robot in names
            }
    return _FLEETS[key]


def _routing(impl: str, count: int, sizes: Sizes, by_name: bool = False) -> Prepare:
    def prepare() -> tuple[Run, int]:
        fleet = running_fleet(impl, count)
        n = sizes.routing
        chooser = random.Random(count)
        targets = [(f"fleet_{index % 10}", f"robot_{index}") for index in chooser.choices(range(count), k=n)]
        if impl == "dynevent" and by_name:
            names = [action_name(*target) for target in targets]
            step_by_name = fleet.step_by_name

            def run_by_name() -> None:
                for k, name in enumerate(names):
                    step_by_name(name, ins.ChildProgress(status="underway", log_text="moving", now=NOW + k))

            return run_by_name, n
        if impl == "dynevent":
            step = fleet.step

            def run() -> None:
                for k, (fleet_name, robot) in enumerate(targets):
                    step(
                        fleet_name,
                        robot,
                        ins.ChildProgress(status="underway", log_text="moving", now=NOW + k),
                    )

            return run, n
        if by_name:  # the tuple peer's best: a dict from action name to peer
            by_action = {action_name(*key): peer for key, peer in fleet.items()}
            names = [action_name(*target) for target in targets]

            def run_peer_by_name() -> None:
                for k, name in enumerate(names):
                    by_action[name].progress("underway", "moving", "info", NOW + k)

            return run_peer_by_name, n

        def run_peer() -> None:
            for k, target in enumerate(targets):
                fleet[target].progress("underway", "moving", "info", NOW + k)

        return run_peer, n

    return prepare


def _snapshot_one(impl: str, sizes: Sizes, restore: bool) -> Prepare:
    def prepare() -> tuple[Run, int]:
        driver = running(impl)
        driver.progress("underway", "left the lobby", "info", NOW)
        n = sizes.snapshots
        if impl == "dynevent":
            state = driver.server.state
            text = snapshot.dumps(state)
            if restore:

                def run_restore() -> None:
                    for _ in range(n):
                        snapshot.loads(text)

                return run_restore, n

            def run_dump() -> None:
                for _ in range(n):
                    snapshot.dumps(state)

            return run_dump, n
        cls, text = type(driver), driver.dumps()
        if restore:

            def run_peer_restore() -> None:
                for _ in range(n):
                    cls.loads(text, CATEGORIES)

            return run_peer_restore, n

        def run_peer_dump() -> None:
            for _ in range(n):
                driver.dumps()

        return run_peer_dump, n

    return prepare


_SNAPSHOT_FLEETS: dict[str, Any] = {}


def snapshot_fleet(impl: str, count: int) -> Any:
    """``count`` robots, every other one running a child, the rest idle."""
    if impl not in _SNAPSHOT_FLEETS:
        names = _robot_names(count)
        if impl == "dynevent":
            template = running("dynevent", "fleet_0", "robot_0").server.state
            fleet = Fleet(CONFIG)
            for index, (fleet_name, robot) in enumerate(names):
                state = attrs.evolve(template, fleet=fleet_name, robot=robot) if index % 2 else None
                fleet.add(fleet_name, robot, state=state)
            _SNAPSHOT_FLEETS[impl] = fleet
        else:
            _SNAPSHOT_FLEETS[impl] = [
                running(impl, *name) if index % 2 else new_driver(impl, *name)
                for index, name in enumerate(names)
            ]
    return _SNAPSHOT_FLEETS[impl]


def _snapshot_fleet(impl: str, sizes: Sizes, restore: bool) -> Prepare:
    def prepare() -> tuple[Run, int]:
        fleet = snapshot_fleet(impl, sizes.snapshot_fleet)
        if impl == "dynevent":
            text = fleet.dumps()
            return ((lambda: Fleet.loads(text, config=CONFIG)) if restore else fleet.dumps), 1
        cls = peer_class(impl)

        def dump() -> str:
            return json.dumps({"robots": [peer.snapshot() for peer in fleet]})

        text = dump()

        def load() -> dict[tuple[str, str], Any]:
            robots = strict_json(text)["robots"]
            return {(data["fleet"], data["robot"]): cls.restore(data, CATEGORIES) for data in robots}

        return (load if restore else dump), 1

    return prepare


def workloads(impls: Sequence[str], sizes: Sizes) -> list[Workload]:
    """Every timed workload, in table order."""
    rows = [
        Workload(
            "1a",
            "accept: NEXT with a small JSON description (goal built from raw values)",
            {i: _accept_next(i, sizes) for i in impls},
        ),
        Workload(
            "1b",
            "accept: CANCEL of the running child (goal built from raw values)",
            {i: _accept_cancel(i, sizes) for i in impls},
        ),
        Workload(
            "2",
            "full child cycle (request, start, 3 progress + log, finish)",
            {i: _child_cycles(i, sizes) for i in impls},
        ),
        Workload("2p", "one progress update with a log line", {i: _progress(i, sizes) for i in impls}),
        Workload(
            "2s",
            "one progress update, machine.step only (input prebuilt)",
            {"dynevent": _progress_step_only(sizes)},
        ),
        Workload(
            "3",
            "whole dynamic event: 100 children, 1 stubborn, 1 cancel",
            {i: _whole_event(i, sizes) for i in impls},
        ),
    ]
    for count in sizes.fleets:
        allowed = [i for i in impls if i in ("dynevent", "tuples") or count in sizes.library_fleets]
        rows.append(
            Workload(
                f"4k{count}",
                f"route a progress update by key, {count:,} robots",
                {i: _routing(i, count, sizes) for i in allowed},
            )
        )
    for count in sizes.fleets:
        allowed = [i for i in impls if i in ("dynevent", "tuples")]
        rows.append(
            Workload(
                f"4n{count}",
                f"route a progress update by action name, {count:,} robots",
                {i: _routing(i, count, sizes, by_name=True) for i in allowed},
            )
        )
    rows += [
        Workload(
            "6a", "snapshot one robot (running child)", {i: _snapshot_one(i, sizes, False) for i in impls}
        ),
        Workload("6b", "restore one robot", {i: _snapshot_one(i, sizes, True) for i in impls}),
        Workload(
            "6c",
            f"snapshot a fleet of {sizes.snapshot_fleet:,} robots",
            {i: _snapshot_fleet(i, sizes, False) for i in impls},
        ),
        Workload(
            "6d",
            f"restore a fleet of {sizes.snapshot_fleet:,} robots",
            {i: _snapshot_fleet(i, sizes, True) for i in impls},
        ),
    ]
    return rows


def sample(prepare: Prepare) -> float:
    """One sample: nanoseconds per operation."""
    run, ops = prepare()
    gc.collect()
    start = time.perf_counter_ns()
    run()
    return (time.perf_counter_ns() - start) / ops


def measure(rows: list[Workload], impls: Sequence[str], repeats: int) -> None:
    """Fill every workload's samples, the implementations taking turns in a rotated order."""
    for repeat in range(repeats):
        order = list(impls[repeat % len(impls) :]) + list(impls[: repeat % len(impls)])
        for row in rows:
            for impl in order:
                if impl in row.prepare:
                    row.samples.setdefault(impl, []).append(sample(row.prepare[impl]))
        print(f"  repeat {repeat + 1}/{repeats} done", file=sys.stderr)


# --------------------------------------------------------------------------- memory


def traced_bytes(build: Callable[[], Any]) -> int:
    """Bytes allocated (and still held) while ``build`` runs."""
    gc.collect()
    tracemalloc.start()
    before = tracemalloc.get_traced_memory()[0]
    held = build()
    after = tracemalloc.get_traced_memory()[0]
    tracemalloc.stop()
    del held
    return after - before


def memory(impls: Sequence[str], sizes: Sizes) -> dict[str, dict[str, tuple[float, int]]]:
    """Per implementation: bytes per idle robot, alone and in a fleet, with the robot count measured."""
    results: dict[str, dict[str, tuple[float, int]]] = {"idle robot": {}, "idle fleet": {}}
    for impl in impls:
        count = sizes.memory_states
        names = _robot_names(count)
        if impl == "dynevent":
            per_state = traced_bytes(lambda names=names: [State.new(f, r) for f, r in names]) / count
        else:
            cls = peer_class(impl)
            per_state = (
                traced_bytes(lambda cls=cls, names=names: [cls(f, r, CATEGORIES) for f, r in names]) / count
            )
        results["idle robot"][impl] = (per_state, count)
        count = sizes.memory_fleet if impl in ("dynevent", "tuples") else sizes.library_memory_fleet
        names = _robot_names(count)
        if impl == "dynevent":

            def build_fleet(names: list[tuple[str, str]] = names) -> Fleet:
                fleet = Fleet(CONFIG)
                for fleet_name, robot in names:
                    fleet.add(fleet_name, robot)
                return fleet

            total = traced_bytes(build_fleet)
        else:
            cls = peer_class(impl)
            total = traced_bytes(
                lambda cls=cls, names=names: {(f, r): cls(f, r, CATEGORIES) for f, r in names}
            )
        results["idle fleet"][impl] = (total / count, count)
    return results


# --------------------------------------------------------------------------- report


def fmt_ns(value: float) -> str:
    if value < 1_000:
        return f"{value:.0f} ns"
    if value < 1_000_000:
        return f"{value / 1_000:.2f} µs"
    if value < 1_000_000_000:
        return f"{value / 1_000_000:.2f} ms"
    return f"{value / 1_000_000_000:.2f} s"


def spread(samples: list[float]) -> float:
    """Interquartile range as a percentage of the median."""
    if len(samples) < 4:
        return (max(samples) - min(samples)) / statistics.median(samples) * 100
    q1, _, q3 = statistics.quantiles(samples, n=4)
    return (q3 - q1) / statistics.median(samples) * 100


def table(rows: list[Workload], impls: Sequence[str]) -> list[str]:
    peers = [impl for impl in impls if impl != "dynevent"]
    head = ["#", "workload", *[f"{impl} median (±IQR)" for impl in impls], *[f"dynevent/{p}" for p in peers]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for row in rows:
        cells = [row.key, row.title]
        medians = {impl: statistics.median(samples) for impl, samples in row.samples.items()}
        for impl in impls:
            if impl in row.samples:
                cells.append(f"{fmt_ns(medians[impl])} (±{spread(row.samples[impl]):.0f}%)")
            else:
                cells.append("n/a")
        for peer in peers:
            if "dynevent" in medians and peer in medians:
                cells.append(f"{medians['dynevent'] / medians[peer]:.2f}")
            else:
                cells.append("n/a")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def memory_table(results: dict[str, dict[str, tuple[float, int]]], impls: Sequence[str]) -> list[str]:
    peers = [impl for impl in impls if impl != "dynevent"]
    head = ["#", "memory", *[f"{impl} B/robot" for impl in impls], *[f"dynevent/{p}" for p in peers]]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key, (label, values) in zip(("5a", "5b"), results.items(), strict=True):
        cells = [key, f"{label} (tracemalloc)"]
        for impl in impls:
            per, count = values[impl]
            cells.append(f"{per:,.0f} (of {count:,})")
        for peer in peers:
            cells.append(f"{values['dynevent'][0] / values[peer][0]:.2f}")
        lines.append("| " + " | ".join(cells) + " |")
    return lines


def targets(rows: list[Workload], mem: dict[str, dict[str, tuple[float, int]]], sizes: Sizes) -> list[str]:
    by_key = {row.key: {impl: statistics.median(s) for impl, s in row.samples.items()} for row in rows}
    lines: list[str] = []

    def check(text: str, value: float | None, limit: float, shown: str) -> None:
        if value is None:
            lines.append(f"- {text}: not measured (peer missing)")
            return
        verdict = "met" if value <= limit else "MISSED"
        lines.append(f"- {text}: {shown} — **{verdict}**")

    cycle = by_key["2"]
    for peer, limit in (("transitions", 1.5), ("tuples", 2.5)):
        ratio = cycle["dynevent"] / cycle[peer] if peer in cycle else None
        check(
            f"full child cycle within {limit}x of the {peer} peer",
            ratio,
            limit,
            "—" if ratio is None else f"dynevent/{peer} = {ratio:.2f}",
        )
    progress, floor = by_key["2p"]["dynevent"], by_key["2p"].get("tuples")
    beside = "" if floor is None else f" (the tuple peer: {fmt_ns(floor)})"
    check("a progress update, input built, at most 3 µs", progress, 3_000, fmt_ns(progress) + beside)
    small, large = min(sizes.fleets), max(sizes.fleets)
    for kind, label in (("k", "by key"), ("n", "by name")):
        flat = by_key[f"4{kind}{large}"]["dynevent"] / by_key[f"4{kind}{small}"]["dynevent"]
        check(
            f"fleet routing {label} flat ({large:,} robots within 1.5x of {small})", flat, 1.5, f"{flat:.2f}x"
        )
    restore = by_key["6d"]["dynevent"] / sizes.snapshot_fleet
    check(
        f"fleet restore at most 25 µs per robot ({sizes.snapshot_fleet:,} robots)",
        restore,
        25_000,
        f"{fmt_ns(restore)} per robot",
    )
    idle = mem["idle robot"]["dynevent"][0]
    check("idle robot state under 1 KiB", idle, 1024, f"{idle:,.0f} B")
    return lines


def machine_description() -> list[str]:
    return results.machine_description(("dynevent", "attrs", "transitions", "python-statemachine"))


def report(rows: list[Workload], mem: dict[str, Any], impls: Sequence[str], sizes: Sizes, mode: str) -> str:
    lines = [
        "# dynevent benchmark results",
        "",
        "Written by `python bench/run.py` (see docs/performance.md for the method). Times are per",
        "operation: median over the samples, spread = interquartile range / median. Ratios below 1 mean",
        "dynevent is faster than the peer. The `transitions` and `python-statemachine` peers are left out",
        "of fleets above 1,000 robots (a machine per robot would not fit in memory at 100,000).",
        "",
        *machine_description(),
        f"- mode: {mode} ({sizes.repeats} samples per workload and implementation)",
        "",
        "## Time",
        "",
        *table(rows, impls),
        "",
        "## Memory",
        "",
        *memory_table(mem, impls),
        "",
        "## Targets",
        "",
        *targets(rows, mem, sizes),
        "",
    ]
    return "\n".join(lines)


# --------------------------------------------------------------------------- profile


def profile(cycles: int = 2_000) -> str:
    """cProfile's view (by own time) of dynevent's progress updates and of full child cycles."""
    out = io.StringIO()
    driver = running("dynevent")
    profiler = cProfile.Profile()
    profiler.enable()
    for k in range(cycles * 5):
        driver.progress("underway", "moving along", "info", NOW + k)
    profiler.disable()
    out.write(f"== {cycles * 5} progress updates (input built + step)\n")
    pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(18)
    driver = waiting("dynevent")
    calls = _calls(driver, [e for k in range(cycles) for e in child_cycle(1, 100 + k, uuid(100 + k))])
    profiler = cProfile.Profile()
    profiler.enable()
    for method, args in calls:
        method(*args)
    profiler.disable()
    out.write(f"== {cycles} full child cycles\n")
    pstats.Stats(profiler, stream=out).sort_stats("tottime").print_stats(25)
    return out.getvalue()


# --------------------------------------------------------------------------- main


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="a few samples of each workload (for CI)")
    parser.add_argument("--repeats", type=int, help="samples per workload and implementation")
    parser.add_argument("--output", type=Path, default=ROOT / "bench" / "results.md", help="where to write")
    parser.add_argument("--no-write", action="store_true", help="print only; leave results.md alone")
    parser.add_argument("--profile", action="store_true", help="print cProfile's view of dynevent and stop")
    parser.add_argument(
        "--only",
        metavar="KEYS",
        help="time only these workloads (comma-separated keys, e.g. 2,2p); implies --no-write",
    )
    parser.add_argument(
        "--section",
        metavar="NAME",
        help="with --only: write the table as section NAME of results.md (a run with another library)",
    )
    args = parser.parse_args(argv)
    if args.profile:
        print(profile())
        return 0
    sizes = QUICK if args.quick else FULL
    if args.repeats:
        sizes = Sizes(**{**sizes.__dict__, "repeats": args.repeats})
    impls = available()
    rows = workloads(impls, sizes)
    if args.only:
        keys = set(args.only.split(","))
        rows = [row for row in rows if row.key in keys]
        measure(rows, impls, sizes.repeats)
        lines = table(rows, impls)
        if args.section:
            lines = [
                f"## Workloads {args.only}, {sizes.repeats} samples (`bench/run.py --only {args.only}`)",
                "",
                *machine_description(),
                "",
                *lines,
            ]
            results.write_section(args.section, lines, args.output)
        print("\n".join(lines))
        return 0
    print(
        f"measuring {len(rows)} workloads x {len(impls)} implementations x {sizes.repeats}", file=sys.stderr
    )
    for row in rows:  # build the fleets before timing
        for prepare in row.prepare.values():
            prepare()
    gc.collect()
    gc.freeze()  # the fixtures live on: keep them out of every later collection
    measure(rows, impls, sizes.repeats)
    mem = memory(impls, sizes)
    text = report(rows, mem, impls, sizes, "quick" if args.quick else "full")
    print(text)
    if not args.no_write:
        args.output.write_text(results.keep_sections(text, args.output), encoding="utf-8")
        print(f"wrote {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
