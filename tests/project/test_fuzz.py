"""The fuzzer (fuzz/): every entry point keeps its contract under hostile input, and the harness itself
catches what it claims to.

The default budget is small (a few thousand inputs, seconds); ``DYNEVENT_FUZZ_INPUTS=200000`` runs a
long one (``python -m fuzz.run --inputs 200000`` does the same with a report).
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from fuzz import run  # noqa: E402
from fuzz.targets import Target, targets  # noqa: E402

from dynevent.errors import InvalidMessage  # noqa: E402

INPUTS = int(os.environ.get("DYNEVENT_FUZZ_INPUTS", "3400"))


def test_the_harness_covers_at_least_40_entry_points_of_every_kind() -> None:
    names = [target.name for target in targets()]
    assert len(names) == len(set(names)) >= 40
    for kind in (
        "from_dict",
        "from_json",
        "inputs.",
        "records.",
        "snapshot.",
        "Fleet.",
        "EventDescription",
        "names.",
        "check.",
        "vectors.",
        "driver",
        "StateStore",
        "client.",
        "cli: dynevent check",
        "cli: dynevent explain",
        "cli: dynevent vectors",
        "descriptions.Robot",
        "sim.load_config",
        "send_request",
        "bags: metadata.yaml",
        "bags: MCAP storage",
        "runner: a driver's answers",
        "report writers",
        "bags: compressed storage",
        "bags: compressed messages",
        "bags: an MCAP file's compressed chunks",
        "files.check_writable",
        "descriptions API",
    ):
        assert any(kind in name for name in names), kind


def test_every_entry_point_keeps_its_contract_under_hostile_input() -> None:
    report = run.fuzz(INPUTS, seed=int(os.environ.get("DYNEVENT_FUZZ_SEED", "0")))
    assert report.total == INPUTS
    assert min(report.inputs.values()) >= INPUTS // len(report.inputs)
    assert not report.failures, "\n".join(
        f"{f.target}: {f.problem}\n  {f.value}" for f in report.failures[:10]
    )


def _report(call: object, **bounds: float) -> run.Report:
    target = Target("probe", ({"a": 1},), call)  # type: ignore[arg-type]
    return run.fuzz(3, chosen=[target], memory_every=1, **bounds)


def test_the_harness_reports_an_exception_outside_the_projects_family() -> None:
    def broken(value: object) -> None:
        raise KeyError("a")

    report = _report(broken)
    assert [failure.problem.split(":")[0] for failure in report.failures] == ["KeyError"] * 3


def test_the_harness_accepts_the_projects_own_errors() -> None:
    def refuses(value: object) -> None:
        raise InvalidMessage("Goal", "id", value, "refused")

    assert not _report(refuses).failures


def test_the_harness_reports_a_slow_call_and_stops_a_hung_one() -> None:
    slow = _report(lambda value: time.sleep(0.06), time_bound=0.05)
    assert slow.failures and "took" in slow.failures[0].problem

    def hangs(value: object) -> None:
        while True:
            time.sleep(0.01)

    started = time.monotonic()
    hung = _report(hangs, time_bound=0.02)
    assert [failure.problem for failure in hung.failures] == ["hung: over 0.1 s"] * 3
    assert time.monotonic() - started < 5


def test_the_harness_reports_a_call_over_the_memory_bound() -> None:
    report = _report(lambda value: bytearray(3_000_000), memory_bound_mb=1)
    assert report.failures and "allocated 3 MB" in report.failures[0].problem


@pytest.mark.parametrize("seed", [0, 1])
def test_a_run_is_reproducible(seed: int) -> None:
    first = run.fuzz(200, seed=seed)
    second = run.fuzz(200, seed=seed)
    assert first.inputs == second.inputs and first.failures == second.failures
