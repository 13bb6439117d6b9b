"""Run the fuzzer: ``python -m fuzz.run [--inputs N] [--seed S]`` from the repository's root.

Every entry point of fuzz/targets.py gets its share of ``--inputs`` mutated
seeds, in turn.  A call fails when it raises anything but dynevent's own
errors (a command line: exits other than 0, 1 or 2, or prints a
traceback), when it takes longer than ``--time-bound`` seconds, or when it
allocates more than ``--memory-bound`` MB at its peak (measured on every
``--memory-every``-th call with tracemalloc).  The run prints one line per
failure and a summary, and exits 1 when anything failed.  The same seed
runs the same inputs.
"""

from __future__ import annotations

import argparse
import random
import signal
import sys
import threading
import time
import traceback
import tracemalloc
from collections.abc import Sequence
from typing import Any

import attrs

from dynevent.errors import DyneventError

from . import mutate
from .targets import Target, targets


class _Hung(BaseException):
    """A call ran past the hang bound (raised by an interval timer)."""


@attrs.frozen
class Failure:
    """One input that broke an entry point's contract."""

    target: str
    problem: str
    value: str


@attrs.define
class Report:
    """What a run did: inputs per entry point, failures, and the slowest call."""

    inputs: dict[str, int] = attrs.field(factory=dict)
    failures: list[Failure] = attrs.field(factory=list)
    slowest: tuple[float, str] = (0.0, "")
    peak: tuple[int, str] = (0, "")

    @property
    def total(self) -> int:
        return sum(self.inputs.values())


def _shown(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 400 else text[:397] + "..."


def fuzz_one(
    target: Target, value: Any, report: Report, *, time_bound: float, memory_bound: int, measure: bool
) -> None:
    """Call ``target`` on ``value``; record a failure if its contract breaks."""
    problem = None
    if measure:
        tracemalloc.start()
    started = time.perf_counter()
    timer = threading.current_thread() is threading.main_thread()
    if timer:
        signal.setitimer(signal.ITIMER_REAL, time_bound * 5)
    try:
        target.call(value)
    except DyneventError:
        pass
    except _Hung:
        problem = f"hung: over {time_bound * 5:g} s"
    except RecursionError:
        problem = "RecursionError"
    except Exception as exc:
        frames = traceback.extract_tb(exc.__traceback__)
        where = frames[-1] if frames else None
        at = f" at {where.filename.rsplit('/', 2)[-1]}:{where.lineno}" if where is not None else ""
        problem = "".join(traceback.format_exception_only(type(exc), exc)).strip()[-300:] + at
    finally:
        if timer:
            signal.setitimer(signal.ITIMER_REAL, 0)
    elapsed = time.perf_counter() - started
    if measure:
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        if peak > report.peak[0]:
            report.peak = (peak, target.name)
        if problem is None and peak > memory_bound:
            problem = f"allocated {peak / 1e6:.0f} MB at its peak (bound {memory_bound / 1e6:.0f} MB)"
    if elapsed > report.slowest[0]:
        report.slowest = (elapsed, target.name)
    if problem is None and elapsed > time_bound:
        problem = f"took {elapsed:.2f} s (bound {time_bound:g} s)"
    if problem is not None:
        report.failures.append(Failure(target.name, problem, _shown(value)))


def fuzz(
    inputs: int,
    seed: int = 0,
    *,
    chosen: Sequence[Target] | None = None,
    time_bound: float = 2.0,
    memory_bound_mb: float = 64.0,
    memory_every: int = 25,
    progress: bool = False,
) -> Report:
    """Run ``inputs`` mutated inputs over the entry points (round robin); the report of the run."""
    everything = list(chosen) if chosen is not None else targets()
    report = Report(inputs={target.name: 0 for target in everything})
    previous = signal.getsignal(signal.SIGALRM)
    if threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGALRM, _raise_hung)
    try:
        for index in range(inputs):
            target = everything[index % len(everything)]
            rng = random.Random(f"{seed}:{index}")
            value = _input(target, rng)
            fuzz_one(
                target,
                value,
                report,
                time_bound=time_bound,
                memory_bound=int(memory_bound_mb * 1e6),
                measure=index % memory_every == 0,
            )
            report.inputs[target.name] += 1
            if progress and index % 1000 == 999:
                print(f"\r{index + 1:,} inputs, {len(report.failures)} failures", end="", file=sys.stderr)
    finally:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGALRM, previous)
    if progress:
        print(file=sys.stderr)
    return report


def _raise_hung(signum: int, frame: Any) -> None:
    raise _Hung


def _input(target: Target, rng: random.Random) -> Any:
    seed = rng.choice(target.seeds)
    if isinstance(seed, bytes):
        data = bytearray(seed)
        for _ in range(rng.randint(1, 8)):
            data[rng.randrange(len(data))] = rng.randrange(256)
        return bytes(data[: rng.randrange(len(data) + 1)] if rng.random() < 0.3 else data)
    if target.text and isinstance(seed, str):
        if rng.random() < 0.5:
            return mutate.mutate_text(seed, rng)
        lines = seed.splitlines(keepends=True)
        index = rng.randrange(len(lines))
        try:
            document = mutate.json.loads(lines[index])
        except ValueError:
            return mutate.mutate_text(seed, rng)
        lines[index] = mutate.dumps(mutate.mutate_json(document, rng)) + "\n"
        return "".join(lines)
    if rng.random() < 0.03:
        return seed  # the seed itself must pass as well
    if target.kwargs and isinstance(seed, dict) and seed:
        arguments = dict(seed)
        for key in rng.sample(sorted(arguments), rng.randint(1, min(2, len(arguments)))):
            arguments[key] = (
                mutate.mutate_json(arguments[key], rng) if rng.random() < 0.7 else mutate.hostile(rng)
            )
        return arguments
    return mutate.mutate_json(seed, rng)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m fuzz.run", description=__doc__.splitlines()[0])
    parser.add_argument("--inputs", type=int, default=200_000, help="how many inputs in all (200,000)")
    parser.add_argument("--seed", type=int, default=0, help="the run's seed (0)")
    parser.add_argument("--time-bound", type=float, default=2.0, help="longest call, in seconds (2)")
    parser.add_argument("--memory-bound", type=float, default=64.0, help="largest peak, in MB (64)")
    parser.add_argument("--memory-every", type=int, default=25, help="measure every Nth call's memory (25)")
    args = parser.parse_args(argv)
    started = time.perf_counter()
    report = fuzz(
        args.inputs,
        args.seed,
        time_bound=args.time_bound,
        memory_bound_mb=args.memory_bound,
        memory_every=args.memory_every,
        progress=sys.stderr.isatty(),
    )
    for failure in report.failures:
        print(f"FAIL {failure.target}: {failure.problem}\n     input: {failure.value}")
    seconds = time.perf_counter() - started
    print(
        f"{report.total:,} inputs over {len(report.inputs)} entry points in {seconds:.0f} s: "
        f"{len(report.failures)} failures; slowest call {report.slowest[0] * 1e3:.0f} ms "
        f"({report.slowest[1]}); largest measured peak {report.peak[0] / 1e6:.1f} MB ({report.peak[1]})"
    )
    return 1 if report.failures else 0


if __name__ == "__main__":
    sys.exit(main())
