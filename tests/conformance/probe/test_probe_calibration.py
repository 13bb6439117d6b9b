"""``dynevent probe --known rmf_ros2`` calibrated against the deployed server, not serve's emulation.

tests/data/rmf_ros2/calibration/probe-known.txt is the probe's report of a run against Open-RMF's
own fleet adapter in the lab, remeasure/probe-known.txt that of the re-measure of a fresh build,
easy/probe-known.txt that of the site whose robot is added through EasyFullControl (every case), and
recalibration/probe-known.txt, queued/probe-known.txt and waiting/probe-known.txt those of the latest
runs, with every case the
probe had that day
(lab/rmf_ros2/README.md; the command and provenance in tests/data/rmf_ros2/README.md): on the
full_control site every case but ``stubborn.clamp_notice``, whose stubborn period crashes that
adapter (D27). Held here to the probe as it is now: each run covered every case the probe had when
it was made (the cases added later, :data:`FIRST_HELD`, by the latest run), every failure was a way
of breaking its rule that docs/divergences.md records for that case (so ``--known rmf_ros2`` passes
the real adapter), and a case added to the probe, or a divergence taken from a case that the real
adapter showed, fails here until the lab's run is made again (or, for a case whose verdict another
case's shows, is listed in :data:`SINCE_THE_LAB` with that case).
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from dynevent.conformance.probe import cases as probe_cases

DATA = Path(__file__).resolve().parents[2] / "data" / "rmf_ros2"
#: The lab's runs, oldest first.
RUNS = [
    DATA / name / "probe-known.txt"
    for name in ("calibration", "remeasure", "easy", "recalibration", "queued", "waiting")
]
#: The cases added to the probe after its first run, each with the first run that holds it: the runs
#: before it were made without it.
FIRST_HELD = {
    "describe.after_the_run": "recalibration",
    "request.description_invalid": "recalibration",
    "request.stubborn_nan": "recalibration",
    "action.cancel_queued": "queued",
    "action.cancel_waiting": "waiting",
}
#: The cases the lab's runs on the full_control site leave out, and why (the EasyFullControl site's,
#: ``easy``, runs every case).
LEFT_OUT = {"stubborn.clamp_notice": "D27: a stubborn period crashes the full_control adapter"}

#: The cases added to the probe since the lab's last runs, each with the case of those runs whose
#: verdict the deployed adapter gives it too, and why: a case leaves this list when the lab's run is
#: made again (and a run that holds it fails here while it is listed).
SINCE_THE_LAB: dict[str, tuple[str, str]] = {
    "describe.after_child": ("describe.query", "info: the deployed adapter offers no query (D17)"),
}


def _left_out(run: Path) -> set[str]:
    names = [path.parent.name for path in RUNS]
    later = {case for case, first in FIRST_HELD.items() if names.index(first) > names.index(run.parent.name)}
    # the cases that interrupt the robot's task: the probe over DDS cannot, and leaves them out
    interrupting = {case.id for case in probe_cases.CASES if case.interrupts}
    return set(SINCE_THE_LAB) | later | interrupting | (set() if run.parent.name == "easy" else set(LEFT_OUT))


VERDICT = r"(?P<verdict>pass|fail|info|known \((?P<d>D\d+)\)|missing \(allowed\)|missing)"
LINE = re.compile(r"^(?P<case>[a-z]+\.[a-z0-9_]+) +" + VERDICT + "  +")


def _verdicts(run: Path) -> dict[str, tuple[str, str | None]]:
    found = {}
    for line in run.read_text(encoding="utf-8").splitlines():
        match = LINE.match(line)
        if match:
            found[match["case"]] = (match["verdict"], match["d"])
    return found


@pytest.mark.parametrize("run", RUNS, ids=lambda path: path.parent.name)
def test_the_real_run_covered_every_case_of_the_probe(run: Path) -> None:
    cases = {case.id for case in probe_cases.CASES}
    assert set(_verdicts(run)) == cases - _left_out(run)
    assert set(LEFT_OUT) <= cases


@pytest.mark.parametrize("run", RUNS, ids=lambda path: path.parent.name)
def test_a_case_added_since_a_run_is_first_held_by_the_run_named_or_follows_a_case(run: Path) -> None:
    """A case of :data:`FIRST_HELD` is in the run it names and in none before it; one of
    :data:`SINCE_THE_LAB` is in no run, and the case it follows has the verdict it says."""
    verdicts = _verdicts(run)
    cases = {case.id for case in probe_cases.CASES}
    names = [path.parent.name for path in RUNS]
    for added, first in FIRST_HELD.items():
        held = names.index(run.parent.name) >= names.index(first)
        assert added in cases and (added in verdicts) == held, (added, first)
    for added, (like, why) in SINCE_THE_LAB.items():
        assert added in cases and added not in verdicts, f"{added}: in the lab's run, or no case"
        assert verdicts[like][0] == why.split(":", 1)[0], (added, like, verdicts[like])


@pytest.mark.parametrize("run", RUNS, ids=lambda path: path.parent.name)
def test_with_known_rmf_ros2_the_probe_passes_the_real_adapter(run: Path) -> None:
    text = run.read_text(encoding="utf-8")
    assert text.rstrip().endswith("EXIT 0"), text[-300:]
    verdicts = _verdicts(run)
    assert not [case for case, (verdict, _) in verdicts.items() if verdict in ("fail", "missing")]


@pytest.mark.parametrize("run", RUNS, ids=lambda path: path.parent.name)
def test_every_known_failure_is_a_divergence_of_its_case(run: Path) -> None:
    by_id = {case.id: case for case in probe_cases.CASES}
    known = {case: d for case, (verdict, d) in _verdicts(run).items() if d is not None}
    assert known, "the real adapter fails no case: a run that tested nothing?"
    for case, d in known.items():
        assert d in by_id[case].divergences, f"{case}: {d} is not among {by_id[case].divergences}"
        assert d in probe_cases.KNOWN["rmf_ros2"]


@pytest.mark.parametrize("run", RUNS, ids=lambda path: path.parent.name)
def test_missing_cases_are_the_ones_a_fleet_adapter_cannot_reach(run: Path) -> None:
    allowed = {case for case, (verdict, _) in _verdicts(run).items() if verdict == "missing (allowed)"}
    assert allowed <= probe_cases.KNOWN_MISSING["rmf_ros2"]
