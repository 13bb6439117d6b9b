"""``dynevent probe``'s cases as data, its selection, reports and exit status, without ROS 2."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

import attrs
import pytest

from dynevent.conformance import probe_cases
from dynevent.conformance.probe_cases import CASES, KNOWN, Case, Finding, Verdict

ROOT = Path(__file__).resolve().parents[2]
SPEC_RULES = set(re.findall(r"\*\*(R\d+\.\d+)\*\*", (ROOT / "docs" / "spec.md").read_text(encoding="utf-8")))
DIVERGENCES = set(
    re.findall(r"^## (D\d+)\.", (ROOT / "docs" / "divergences.md").read_text(encoding="utf-8"), re.M)
)


def test_every_case_cites_rules_of_the_spec_and_divergences_of_the_record() -> None:
    assert len({case.id for case in CASES}) == len(CASES)
    for case in CASES:
        assert case.rules and set(case.rules) <= SPEC_RULES, case
        assert set(case.divergences) <= DIVERGENCES, case
        assert case.needs in ("status", "run", "place", "child"), case
    assert KNOWN["rmf_ros2"] == {"D1", "D2", "D7", "D8", "D9", "D10", "D11", "D26", "D28", "D30", "D31"}


@pytest.mark.parametrize(
    ("patterns", "ids"),
    [
        ((), [case.id for case in CASES]),
        (
            ("cancel",),
            [
                "cancel.wrong_id",
                "cancel.seq_stale",
                "cancel.seq_future",
                "cancel.running_child",
                "cancel.both_answered",
            ],
        ),
        (
            ("request.seq_*",),
            ["request.seq_stale", "request.seq_future", "request.seq_stale_next", "request.seq_future_next"],
        ),
        (("R4.1*",), ["request.cancel_idle", "next.id_stale", "next.race", "cancel.wrong_id"]),
        (
            ("R9.3", "finished.next_after"),
            ["cancel.running_child", "cancel.both_answered", "finished.next_after"],
        ),
        (("nothing",), []),
    ],
)
def test_cases_are_chosen_by_id_section_or_rule(patterns: tuple[str, ...], ids: list[str]) -> None:
    assert [case.id for case in probe_cases.select(patterns)] == ids


CASE = Case("request.event_type_0", "a goal of event_type 0 is refused", ("R4.4",), divergences=("D7",))


def test_a_case_not_run_is_never_a_pass() -> None:
    """A run in which a case was not run exits 3, unless that case was expected to be missing
    (--allow-missing, --known); a failure outranks it; the report says first how many were not run
    and why, and a missing case says why it was not run instead of a blank expectation."""
    place = "no place to send the robot to: give --place"
    missing = [Finding(CASE, Verdict.MISSING, seen=place), Finding(CASE, Verdict.MISSING, seen=place)]
    ran = Finding(CASE, Verdict.PASS, expected="rejected", seen="so")
    assert probe_cases.exit_status([*missing, ran]) == probe_cases.EXIT_NOT_RUN == 3
    allowed = [attrs.evolve(finding, expected_missing=True) for finding in missing]
    assert probe_cases.exit_status([*allowed, ran]) == 0
    failing = Finding(CASE, Verdict.FAIL, expected="rejected", seen="accepted")
    assert probe_cases.exit_status([*missing, failing]) == 1
    text = probe_cases.format_findings([*missing, ran])
    assert text.splitlines()[0] == f"2 of 3 case(s) not run: {place} (2)"
    assert f"  not run:  {place}" in text and "expected: \n" not in text and "  expected: " not in text
    assert probe_cases.format_findings([*allowed, ran]).splitlines()[0] == (
        f"2 of 3 case(s) not run, 2 of them expected: {place} (2)"
    )
    assert "missing (allowed)" in probe_cases.format_findings(allowed)
    assert probe_cases.not_run_summary([ran]) is None
    report = probe_cases.report([*missing, ran], "tinyRobot/r1")
    assert f"2 of 3 case(s) not run: {place} (2)" in report.splitlines()[2]
    assert "- seen: as expected" in report and "- seen: so" not in report
    assert f"- not run: {place}" in report


def test_known_missing_is_the_seq_wrap_for_rmf_ros2() -> None:
    assert {"rmf_ros2": frozenset({"begin.seq_wrap"})} == probe_cases.KNOWN_MISSING
    assert {case.id for case in CASES} >= probe_cases.KNOWN_MISSING["rmf_ros2"]


@pytest.mark.parametrize(
    ("description", "place"),
    [
        (
            '{"estimate": {"category": "go_to_place", "description": {"one_of": [{"waypoint": "pantry"}]}}}',
            "pantry",
        ),
        ('{"estimate": {"category": "go_to_place", "description": "lounge"}}', "lounge"),
        ('{"estimate": {"category": "go_to_place", "description": {"place": "dock"}}}', "dock"),
        ('{"estimate": {"category": "go_to_place", "description": 3}}', None),
        ('{"estimate": {"category": "perform_action", "description": {"category": "x"}}}', None),
        ('{"estimate": {"category": "go_to_place", "description": {"one_of": []}}}', None),
        ("{}", None),
        ("[1]", None),
        ("not json", None),
    ],
)
def test_a_run_s_place_is_its_go_to_place_estimate(description: str, place: str | None) -> None:
    assert probe_cases.place_of_run(description) == place


def test_a_known_divergence_is_shown_and_does_not_fail_the_run() -> None:
    failing = Finding(CASE, Verdict.FAIL, expected="rejected", seen="accepted", divergence="D7")
    assert probe_cases.exit_status([failing]) == 1
    known = Finding(CASE, Verdict.FAIL, expected="rejected", seen="accepted", divergence="D7", known=True)
    assert probe_cases.exit_status([known]) == 0
    assert probe_cases.exit_status([Finding(CASE, Verdict.MISSING), Finding(CASE, Verdict.PASS)]) == 3
    text = probe_cases.format_findings([failing, known, Finding(CASE, Verdict.PASS)])
    assert "fail (D7)" in text and "known (D7)" in text
    assert text.rstrip().endswith("1 pass, 2 fail (1 of the failures known)")


def test_the_junit_report_is_what_a_ci_server_reads() -> None:
    findings = [
        Finding(
            CASE,
            Verdict.FAIL,
            expected="rejected",
            seen="accepted",
            divergence="D7",
            messages=("sent type 0",),
        ),
        Finding(CASE, Verdict.MISSING, seen="no active run"),
        Finding(CASE, Verdict.PASS),
    ]
    suites = ET.fromstring(probe_cases.junit_xml(findings, "tinyRobot/r1"))
    suite = suites.find("testsuite")
    assert suite is not None and suite.get("failures") == "1" and suite.get("skipped") == "1"
    cases = suite.findall("testcase")
    assert [case.get("classname") for case in cases] == ["request"] * 3
    failure = cases[0].find("failure")
    assert failure is not None and "sent type 0" in (failure.text or "")
    assert cases[1].find("skipped") is not None
    rules = cases[2].find("properties/property[@name='rules']")
    assert rules is not None and rules.get("value") == "R4.4"


def test_the_report_a_person_reads_says_per_case_the_rules_verdict_and_messages() -> None:
    import html.parser

    findings = [
        Finding(CASE, Verdict.FAIL, expected="rejected", seen="accepted <then> aborted | D7",
                divergence="D7", messages=("sent type 0 seq=1 id=0", "accepted, answered aborted")),
        Finding(CASE, Verdict.PASS, expected="rejected", seen="so", seconds=0.25),
    ]  # fmt: skip
    text = probe_cases.report(findings, "tinyRobot/r1")
    assert text.startswith("# dynevent probe: tinyRobot/r1\n\n1 pass, 1 fail\n")
    assert f"| `{CASE.id}` | fail (D7) | R4.4 | {CASE.title} |" in text
    assert "- seen: accepted <then> aborted \\| D7" in text  # a table cell's bar is escaped
    assert "```\nsent type 0 seq=1 id=0\naccepted, answered aborted\n```" in text
    assert "- divergence: D7 (docs/divergences.md)" in text and "- time: 0.250 s" in text
    page = probe_cases.report(findings, "tinyRobot/<r1>", html_form=True)
    assert "<title>dynevent probe: tinyRobot/&lt;r1&gt;</title>" in page
    assert "accepted &lt;then&gt; aborted | D7" in page and "<then>" not in page
    assert '<tr class="fail">' in page and '<tr class="pass">' in page

    class Balanced(html.parser.HTMLParser):
        def __init__(self) -> None:
            super().__init__()
            self.open: list[str] = []

        def handle_starttag(self, tag: str, attrs: object) -> None:
            if tag not in ("meta", "br"):
                self.open.append(tag)

        def handle_endtag(self, tag: str) -> None:
            assert self.open.pop() == tag

    parser = Balanced()
    parser.feed(page)
    assert parser.open == []


def test_the_list_names_every_case_with_its_rules() -> None:
    text = probe_cases.format_list(CASES)
    assert text.splitlines()[-1] == f"{len(CASES)} case(s)"
    line = next(line for line in text.splitlines() if line.startswith("request.cancel_idle "))
    assert " ".join(line.split()) == "request.cancel_idle a CANCEL while no child runs is refused (R4.13)"


def test_docs_probe_lists_every_case_with_its_rules_and_divergences() -> None:
    """docs/probe.md's table of cases is the data of CASES, row for row."""
    text = (ROOT / "docs" / "probe.md").read_text(encoding="utf-8")
    rows = re.findall(r"^\| `([a-z_.0-9]+)` \| (.*?) \| (.*?) \| (.*?) \|$", text, re.M)
    assert rows == [
        (case.id, ", ".join(case.rules), case.title, ", ".join(case.divergences)) for case in CASES
    ]
