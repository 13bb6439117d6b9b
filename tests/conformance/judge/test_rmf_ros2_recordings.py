"""The deployed server's recordings as ground truth (tests/data/rmf_ros2/, lab/rmf_ros2/README.md).

Open-RMF's own fleet adapter (rmf_ros2, kilted d6243d3e) was run in the lab and driven by dynevent's
``send`` and ``probe`` and by rmf_demos' client, each session recorded with ``dynevent record``.  No
RMF is needed here: ``dynevent check`` judges each recording, and must find exactly what
docs/divergences.md lists for rmf_ros2, each finding named by its D-number (or, where the finding
is check's own misreading of what a recording lacks, by the open item that says so).  A change to
check, or a finding the page does not list, fails here.
"""

from __future__ import annotations

import collections
import functools
import re
from pathlib import Path

import attrs
import pytest

pytest.importorskip("rosbags", reason="the bags extra (rosbags) reads the recordings")

from dynevent.bags.reader import check_bag
from dynevent.conformance.judge.divergences import OPEN_ITEMS, label
from dynevent.conformance.judge.trace import Finding

DATA = Path(__file__).resolve().parents[2] / "data" / "rmf_ros2"
DOC = Path(__file__).resolve().parents[3] / "docs" / "divergences.md"

#: Open items: findings that are check's own misreading of what a recording does not hold.
OPEN = OPEN_ITEMS


#: What check finds in each recording, in each mode: {(label, rule, code): count}.
STUBBORN = {
    ("D11", "R12.2", "clamp_not_reported"): 1,
    ("D26", "R2.2", "status_mismatch"): 1,
    ("D9", "R7.3", "log_seq"): 1,
}

#: In ``rmf_ros2`` mode (id policy ``adapter``) a child whose id is above the next one is read as ids
#: the adapter drew for work of its own (R17.8): D10's two-apart numbering is no finding there.
EXPECTED: dict[tuple[str, str], dict[tuple[str, str, str], int]] = {
    ("send", "standard"): {
        ("D10", "R6.2", "child_id"): 2,
        ("D26", "R2.2", "status_mismatch"): 3,
        ("D28", "R2.2", "status_mismatch"): 2,
        ("D9", "R7.3", "log_seq"): 9,
        ("response_seen_late", "R2.2", "status_mismatch"): 3,
        ("task_signal_unseen", "R2.2", "status_mismatch"): 1,
        ("task_signal_unseen", "R3.4", "begin_while_active"): 1,
    },
    # the status of a cancelled child's end, read before its late CANCEL, is what serve's rmf_ros2
    # mode publishes at that end (WAITING canceled, R17.4): only the standard mode finds it
    ("send", "rmf_ros2"): {
        ("D26", "R2.2", "status_mismatch"): 3,
        ("D9", "R7.3", "log_seq"): 9,
        ("response_seen_late", "R2.2", "status_mismatch"): 3,
        ("task_signal_unseen", "R2.2", "status_mismatch"): 1,
        ("task_signal_unseen", "R3.4", "begin_while_active"): 1,
    },
    ("demos", "standard"): {("D9", "R7.3", "log_seq"): 6},
    ("demos", "rmf_ros2"): {("D9", "R7.3", "log_seq"): 6},
    ("stubborn", "standard"): STUBBORN,
    ("stubborn", "rmf_ros2"): STUBBORN,
    # in rmf_ros2 mode R17.1 explains the CANCELs accepted then aborted (D8), and R17.4 the WAITING
    # canceled (D28).  Its action-level cancel of the "running" NEXT came after that NEXT's child had
    # ended (at its place already), and the adapter refused it as of a goal terminated: no D31 here,
    # nor in the calibration run, where the child ended as the cancel came
    ("probe", "standard"): {
        ("D1", "R2.2", "status_mismatch"): 2,
        ("D1", "R4.6", "accepted_busy"): 1,
        ("D1", "R5.2", "race_not_lost"): 1,
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 11,
        ("D26", "R2.2", "status_mismatch"): 2,
        ("D28", "R2.2", "status_mismatch"): 5,
        ("D30", "R2.2", "status_mismatch"): 1,
        ("D30", "R8.2", "feedback_not_running"): 2,
        ("D8", "R4.13", "accepted_cancel_idle"): 3,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 40,
        ("cancel_seen_late", "R9.1", "goal_status"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 18,
    },
    # the probe's calibration run (tests/conformance/probe/test_probe_calibration.py): every case but the
    # stubborn one, with the probe as it is now.  The FINISHED of next.busy_finished is no R4.6 finding
    # there: the goal statuses show child 17's goal succeeded (the child was already at its goal)
    # before the FINISHED came; its answer only arrived after the FINISHED's response
    ("calibration", "standard"): {
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 13,
        ("D26", "R2.2", "status_mismatch"): 2,
        ("D28", "R2.2", "status_mismatch"): 5,
        ("D30", "R2.2", "status_mismatch"): 1,
        ("D7", "R4.4", "accepted_uninitialized_event_type"): 1,
        ("D7", "R4.5", "accepted_unknown_event_type"): 1,
        ("D8", "R4.13", "accepted_cancel_idle"): 1,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 43,
        ("answer_seen_late", "R9.2", "result"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 24,
    },
    ("calibration", "rmf_ros2"): {
        ("D1", "R8.3", "goal_status"): 1,
        ("D26", "R2.2", "status_mismatch"): 2,
        ("D28", "R2.2", "status_mismatch"): 2,
        ("D30", "R2.2", "status_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 43,
        ("answer_seen_late", "R9.2", "result"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 24,
    },
    # the lab's re-measure of a fresh build of the same commits (lab/rmf_ros2/measure.py), the probe
    # as it is now: D31's refusal read as a cancel of a goal not yet started (R10.1).  Two NEXTs are no
    # R4.6 finding: the goal statuses show the last child's goal succeeded (the child `completed`)
    # before each came, its answer after; what they show is D10 (the ids not checked)
    ("remeasure", "standard"): {
        ("D1", "R2.2", "status_mismatch"): 8,
        ("D1", "R4.6", "accepted_busy"): 2,
        ("D1", "R5.2", "race_not_lost"): 1,
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 13,
        ("D26", "R2.2", "status_mismatch"): 3,
        ("D28", "R2.2", "status_mismatch"): 6,
        ("D30", "R10.1", "feedback_not_running"): 2,
        ("D30", "R2.2", "status_mismatch"): 1,
        ("D31", "R10.1", "cancel_response"): 1,
        ("D31", "R10.1", "goal_status"): 1,
        ("D7", "R4.4", "accepted_uninitialized_event_type"): 1,
        ("D7", "R4.5", "accepted_unknown_event_type"): 1,
        ("D8", "R4.13", "accepted_cancel_idle"): 1,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 2,
        ("D9", "R7.3", "log_seq"): 45,
        ("answer_seen_late", "R9.2", "result"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 18,
    },
    ("remeasure", "rmf_ros2"): {
        ("D1", "R2.2", "status_mismatch"): 8,
        ("D1", "R4.6", "accepted_busy"): 2,
        ("D1", "R5.2", "race_not_lost"): 1,
        ("D26", "R2.2", "status_mismatch"): 3,
        ("D28", "R2.2", "status_mismatch"): 4,
        ("D30", "R10.1", "feedback_not_running"): 2,
        ("D30", "R2.2", "status_mismatch"): 1,
        ("D31", "R10.1", "cancel_response"): 1,
        ("D31", "R10.1", "goal_status"): 1,
        ("D9", "R7.3", "log_seq"): 45,
        ("answer_seen_late", "R9.2", "result"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 18,
    },
    # the same probe against the site that adds its robot through EasyFullControl (lab/rmf_ros2/site/
    # easy_adapter.py), every case, the stubborn one included (the adapter survives it there, D27):
    # D31 in a third shape (the cancel's callback stopped the child at once; the NEXT answered
    # aborted `canceled` before the cancel's refusal was read)
    ("easy", "standard"): {
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 17,
        ("D11", "R12.2", "clamp_not_reported"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D28", "R2.2", "status_mismatch"): 7,
        ("D31", "R10.3", "cancel_response"): 1,
        ("D31", "R8.2", "goal_status"): 1,
        ("D7", "R4.4", "accepted_uninitialized_event_type"): 1,
        ("D7", "R4.5", "accepted_unknown_event_type"): 1,
        ("D8", "R4.13", "accepted_cancel_idle"): 1,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 48,
        ("finished_seen_late", "R4.3", "accepted_inactive"): 1,
        ("finished_seen_late", "R5.2", "goal_status"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 19,
    },
    ("easy", "rmf_ros2"): {
        ("D1", "R8.3", "goal_status"): 1,
        ("D11", "R12.2", "clamp_not_reported"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D31", "R10.3", "cancel_response"): 1,
        ("D31", "R8.2", "goal_status"): 1,
        ("D9", "R7.3", "log_seq"): 48,
        ("finished_seen_late", "R4.3", "accepted_inactive"): 1,
        ("finished_seen_late", "R5.2", "goal_status"): 1,
        ("response_seen_late", "R2.2", "status_mismatch"): 19,
    },
    # the recalibration run (2026-11-29, a fresh build of the same commits, lab/rmf_ros2/measure.py):
    # every case of the probe but the stubborn one, the NaN stubborn period's among them (D12: accepted,
    # its child ran), and D31 in the EasyFullControl site's shape
    ("recalibration", "standard"): {
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 17,
        ("D12", "R4.11", "accepted_non_finite_stubborn_period"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D28", "R2.2", "status_mismatch"): 7,
        ("D31", "R10.3", "cancel_response"): 1,
        ("D31", "R8.2", "goal_status"): 1,
        ("D7", "R4.4", "accepted_uninitialized_event_type"): 1,
        ("D7", "R4.5", "accepted_unknown_event_type"): 1,
        ("D8", "R4.13", "accepted_cancel_idle"): 1,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 48,
    },
    # serve's rmf_ros2 mode refuses a NaN stubborn period too (D12 has no compatibility option)
    ("recalibration", "rmf_ros2"): {
        ("D1", "R8.3", "goal_status"): 1,
        ("D12", "R4.11", "accepted_non_finite_stubborn_period"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D31", "R10.3", "cancel_response"): 1,
        ("D31", "R8.2", "goal_status"): 1,
        ("D9", "R7.3", "log_seq"): 48,
    },
    # the lab's run of 2026-11-29 with action.cancel_queued (the recalibration run's build): that case
    # and action.cancel_running both D31, in the EasyFullControl site's shape
    ("queued", "standard"): {
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 18,
        ("D12", "R4.11", "accepted_non_finite_stubborn_period"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D28", "R2.2", "status_mismatch"): 7,
        ("D31", "R10.3", "cancel_response"): 2,
        ("D31", "R8.2", "goal_status"): 2,
        ("D7", "R4.4", "accepted_uninitialized_event_type"): 1,
        ("D7", "R4.5", "accepted_unknown_event_type"): 1,
        ("D8", "R4.13", "accepted_cancel_idle"): 2,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 51,
    },
    ("queued", "rmf_ros2"): {
        ("D12", "R4.11", "accepted_non_finite_stubborn_period"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D28", "R2.2", "status_mismatch"): 2,
        ("D31", "R10.3", "cancel_response"): 2,
        ("D31", "R8.2", "goal_status"): 2,
        ("D9", "R7.3", "log_seq"): 51,
    },
    # the lab's run of 2026-11-29 with action.cancel_waiting (the same build): that case missing, the
    # adapter answering the CANCEL before its cancel came (D1); the rest as in queued
    ("waiting", "standard"): {
        ("D10", "R4.12", "accepted_stale_id"): 1,
        ("D10", "R5.2", "race_not_lost"): 1,
        ("D10", "R6.2", "child_id"): 19,
        ("D12", "R4.11", "accepted_non_finite_stubborn_period"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D28", "R2.2", "status_mismatch"): 8,
        ("D31", "R10.3", "cancel_response"): 2,
        ("D31", "R8.2", "goal_status"): 2,
        ("D7", "R4.4", "accepted_uninitialized_event_type"): 1,
        ("D7", "R4.5", "accepted_unknown_event_type"): 1,
        ("D8", "R4.13", "accepted_cancel_idle"): 1,
        ("D8", "R4.14", "accepted_cancel_id_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 54,
    },
    ("waiting", "rmf_ros2"): {
        ("D12", "R4.11", "accepted_non_finite_stubborn_period"): 1,
        ("D26", "R2.2", "status_mismatch"): 1,
        ("D28", "R2.2", "status_mismatch"): 4,
        ("D31", "R10.3", "cancel_response"): 2,
        ("D31", "R8.2", "goal_status"): 2,
        ("D9", "R7.3", "log_seq"): 54,
    },
    ("probe", "rmf_ros2"): {
        ("D1", "R2.2", "status_mismatch"): 3,
        ("D1", "R4.6", "accepted_busy"): 1,
        ("D1", "R5.2", "race_not_lost"): 1,
        ("D26", "R2.2", "status_mismatch"): 2,
        ("D28", "R2.2", "status_mismatch"): 4,
        ("D30", "R2.2", "status_mismatch"): 1,
        ("D9", "R7.3", "log_seq"): 40,
        ("response_seen_late", "R2.2", "status_mismatch"): 18,
    },
}


@functools.cache
def _findings(name: str, compatibility: str) -> tuple[Finding, ...]:
    report = check_bag(DATA / name, compatibility=compatibility)
    return tuple(finding for robot in report.robots for finding in robot.report.findings)


def _found(name: str, compatibility: str) -> collections.Counter[tuple[str, str, str]]:
    return collections.Counter(
        (label(finding), finding.rule, finding.code) for finding in _findings(name, compatibility)
    )


@pytest.mark.parametrize(("name", "compatibility"), sorted(EXPECTED))
def test_check_finds_exactly_what_the_divergences_page_lists(name: str, compatibility: str) -> None:
    found = _found(name, compatibility)
    assert all(label != "?" for label, _, _ in found), f"a finding no D-number explains: {found}"
    assert dict(found) == EXPECTED[name, compatibility]


@pytest.mark.parametrize(("name", "compatibility"), sorted(EXPECTED))
def test_a_label_reads_the_findings_values_never_its_words(name: str, compatibility: str) -> None:
    """A D-number is attached where its rule is checked: rewording the judge's sentences moves no label."""
    for finding in _findings(name, compatibility):
        reworded = attrs.evolve(finding, message="reworded", expected="reworded too")
        assert label(reworded) == label(finding), finding


def test_every_label_is_a_d_number_of_the_page_that_names_its_recording() -> None:
    text = DOC.read_text(encoding="utf-8")
    sections = dict(re.findall(r"^## (D\d+)\.(.*?)(?=^## |\Z)", text, flags=re.MULTILINE | re.DOTALL))
    for (name, _), counts in EXPECTED.items():
        for label_, _, _ in counts:
            if label_ in OPEN or label_ == "?":
                continue
            assert label_ in sections, f"{label_} is no section of docs/divergences.md"
            assert "**Observed**" in sections[label_], f"{label_} has no Observed line"
            observed = sections[label_].split("**Observed**", 1)[1].split("\n- **", 1)[0]
            assert f"`{name}`" in observed or "every recording" in observed, (
                f"{label_}'s Observed line does not name the recording `{name}`"
            )


def test_the_recordings_are_small_and_carry_their_provenance() -> None:
    size = sum(path.stat().st_size for path in DATA.rglob("*") if path.is_file())
    assert size < 4_000_000, f"{size} bytes"
    readme = (DATA / "README.md").read_text(encoding="utf-8")
    for name, _ in EXPECTED:
        assert (DATA / name / "metadata.yaml").exists()
        assert f"`{name}`" in readme
    assert "d6243d3e" in readme
