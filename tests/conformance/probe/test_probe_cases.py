"""``dynevent probe``'s cases as data, its selection, reports and exit status, without ROS 2."""

from __future__ import annotations

import ast
import json
import os
import re
import xml.etree.ElementTree as ET
from pathlib import Path

import attrs
import pytest

from dynevent.conformance.judge import divergences
from dynevent.conformance.judge.trace import Finding as JudgeFinding
from dynevent.conformance.probe import cases as probe_cases
from dynevent.conformance.probe.cases import CASES, KNOWN, Case, CaseFinding, Verdict
from dynevent.wire.messages import DynamicEventStatus

ROOT = Path(__file__).resolve().parents[3]
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
    known = ("D1", "D2", "D7", "D8", "D9", "D10", "D11", "D12", "D26", "D28", "D30", "D31")
    assert KNOWN["rmf_ros2"] == set(known)


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
        (
            ("R4.1*",),
            [
                "request.description_invalid",
                "request.stubborn_nan",
                "request.cancel_idle",
                "next.id_stale",
                "next.race",
                "cancel.wrong_id",
                "cancel.both_answered",
                "finished.ends_the_run",
            ],
        ),
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
    missing = [CaseFinding(CASE, Verdict.MISSING, seen=place), CaseFinding(CASE, Verdict.MISSING, seen=place)]
    ran = CaseFinding(CASE, Verdict.PASS, expected="rejected", seen="so")
    assert probe_cases.exit_status([*missing, ran]) == probe_cases.EXIT_NOT_RUN == 3
    allowed = [attrs.evolve(finding, expected_missing=True) for finding in missing]
    assert probe_cases.exit_status([*allowed, ran]) == 0
    failing = CaseFinding(CASE, Verdict.FAIL, expected="rejected", seen="accepted")
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


def test_known_missing_is_the_seq_wrap_and_the_waiting_cancel_for_rmf_ros2() -> None:
    """rmf_ros2 reaches the wrap after four billion runs, and lets no CANCEL wait (D1)."""
    assert {"rmf_ros2": frozenset({"begin.seq_wrap", "action.cancel_waiting"})} == probe_cases.KNOWN_MISSING
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
    failing = CaseFinding(CASE, Verdict.FAIL, expected="rejected", seen="accepted", divergence="D7")
    assert probe_cases.exit_status([failing]) == 1
    known = CaseFinding(CASE, Verdict.FAIL, expected="rejected", seen="accepted", divergence="D7", known=True)
    assert probe_cases.exit_status([known]) == 0
    assert probe_cases.exit_status([CaseFinding(CASE, Verdict.MISSING), CaseFinding(CASE, Verdict.PASS)]) == 3
    text = probe_cases.format_findings([failing, known, CaseFinding(CASE, Verdict.PASS)])
    assert "fail (D7)" in text and "known (D7)" in text
    assert text.rstrip().endswith("1 pass, 2 fail (1 of the failures known)")


def test_the_junit_report_is_what_a_ci_server_reads() -> None:
    findings = [
        CaseFinding(
            CASE,
            Verdict.FAIL,
            expected="rejected",
            seen="accepted",
            divergence="D7",
            messages=("sent type 0",),
        ),
        CaseFinding(CASE, Verdict.MISSING, seen="no active run"),
        CaseFinding(CASE, Verdict.PASS),
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
        CaseFinding(CASE, Verdict.FAIL, expected="rejected", seen="accepted <then> aborted | D7",
                divergence="D7", messages=("sent type 0 seq=1 id=0", "accepted, answered aborted")),
        CaseFinding(CASE, Verdict.PASS, expected="rejected", seen="so", seconds=0.25),
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


# --------------------------------------------------------------------------- the judge beside the cases

CLEAN = (Path(__file__).resolve().parents[3] / "docs" / "examples" / "clean-trace.jsonl").read_text("utf-8")
#: A feedback of NEXT 6 (goal ...01) sent again after its answer and the status that ended its child.
LATE_FEEDBACK = (
    '{"time":103.5,"type":"feedback","goal_uuid":"00000000000000000000000000000001",'
    '"feedback":{"status":"underway","id":6,"logs":[]}}'
)


def _with_cases(text: str, *cases: tuple[str, str]) -> str:
    """``text`` with ``# case ID`` lines put before the first line holding each marker."""
    for case, marker in cases:
        at = text.index(marker)
        start = text.rindex("\n", 0, at) + 1
        text = text[:start] + f"# case {case}\n" + text[start:]
    return text


def _finding(case_id: str, verdict: probe_cases.Verdict) -> probe_cases.CaseFinding:
    case = next(case for case in probe_cases.CASES if case.id == case_id)
    return probe_cases.CaseFinding(case, verdict)


def _late_feedback(case: str = "next.runs_a_child") -> str:
    """The clean trace with NEXT 6's feedback sent again after its answer and the status after it,
    the records from NEXT 6 on those of ``case``."""
    lines = CLEAN.splitlines()
    end = next(n for n, line in enumerate(lines) if line.startswith('{"time":103,"type":"status"'))
    lines.insert(end + 1, LATE_FEEDBACK)
    first = '"goal_uuid":"00000000000000000000000000000001"'
    return _with_cases("\n".join(lines) + "\n", (case, first))


@pytest.mark.spec("R19.1")
def test_the_judge_finds_what_no_case_did_and_it_fails_the_run() -> None:
    passed = [_finding("next.runs_a_child", probe_cases.Verdict.PASS)]
    judged = probe_cases.judge_exchange(_late_feedback(), passed)
    assert [(item.case, item.finding.rule, item.finding.code) for item in judged] == [
        ("next.runs_a_child", "R19.1", "after_answer")
    ]
    assert judged[0].label == "?" and judged[0].counts
    assert probe_cases.exit_status(passed) == probe_cases.EXIT_OK
    assert probe_cases.exit_status(passed, judged) == probe_cases.EXIT_FAILED
    said = probe_cases.format_findings(passed, judged)
    assert "the judge, over every record of the exchange: 1 finding(s)" in said
    assert "next.runs_a_child: fail: R19.1 after_answer: " in said
    junit = ET.fromstring(probe_cases.junit_xml(passed, "f/r", judged))
    assert [suite.get("name") for suite in junit.iter("testsuite")] == ["f/r", "the judge, over every record"]
    assert "R19.1 after_answer" in probe_cases.report(passed, "f/r", judged=judged)
    assert 'id="judge"' in probe_cases.report(passed, "f/r", html_form=True, judged=judged)
    # a case that failed on the finding's rule already said so: not said twice
    failed = [attrs.evolve(_finding("next.runs_a_child", probe_cases.Verdict.FAIL))]
    assert probe_cases.judge_exchange(_late_feedback(), failed) == []


@pytest.mark.spec("R7.3")
def test_a_finding_the_deployed_server_showed_is_known_to_known() -> None:
    text = CLEAN.replace('"logs":[{"seq":1,', '"logs":[{"seq":0,', 1)  # a log seq repeats
    judged = probe_cases.judge_exchange(text, [])
    assert [(item.finding.rule, item.finding.code, item.label) for item in judged] == [
        ("R7.3", "log_seq", "D9")
    ]
    assert judged[0].counts and probe_cases.exit_status([], judged) == probe_cases.EXIT_FAILED
    known = probe_cases.judge_exchange(text, [], known=KNOWN["rmf_ros2"])
    assert known[0].known and not known[0].counts
    assert probe_cases.exit_status([], known) == probe_cases.EXIT_OK
    assert ": known (D9): R7.3" in known[0].line()


@pytest.mark.spec("R3.1")
def test_a_seq_that_skips_is_the_judges_finding_and_a_clean_exchange_has_none() -> None:
    assert probe_cases.judge_exchange(CLEAN, []) == []
    skipped = CLEAN + (
        '{"time":110,"type":"begin","message":{"fleet":"tinyRobot","robot":"tinyRobot1",'
        '"dynamic_event_seq":3,"description":"{}","start_time":{"sec":110,"nanosec":0}}}\n'
        '{"time":110,"type":"status","message":{"dynamic_event_seq":3,"dynamic_state":1,'
        '"status":"standby","id":1,"time":{"sec":110,"nanosec":0}}}\n'
    )
    judged = probe_cases.judge_exchange(skipped, [])
    assert ("R3.1", "begin_seq") in {(item.finding.rule, item.finding.code) for item in judged}
    assert all(item.case == "" for item in judged)  # before the first case
    assert probe_cases.exit_status([], judged) == probe_cases.EXIT_FAILED


def test_an_open_item_of_the_judge_is_uncertain_and_does_not_fail_the_run() -> None:
    seen = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=2, status="underway", id=6)
    owed = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=5)
    finding = JudgeFinding(
        line=3, rule="R2.2", code="status_mismatch", message="status RUNNING seq=1 id=6 underway",
        expected="WAITING seq=1 id=5 standby", seen=seen, owed=owed,
    )  # fmt: skip
    item = probe_cases.Judged("next.runs_a_child", finding, divergences.label(finding))
    assert item.label == "response_seen_late" and item.uncertain and not item.counts
    assert probe_cases.exit_status([], [item]) == probe_cases.EXIT_OK
    assert "uncertain" in item.line() and "(1 uncertain)" in probe_cases.judged_summary([item])


@pytest.mark.spec("R19.1")
def test_what_the_judge_finds_in_a_case_the_link_kept_from_running_is_uncertain() -> None:
    """A case not run because the link lost, delayed or reordered its messages: the judge's findings
    in its records may be the link's doing, and are reported uncertain, failing no run; the same
    findings in a case not run for another reason still count."""
    by_link = attrs.evolve(_finding("next.runs_a_child", probe_cases.Verdict.MISSING), by_link=True)
    verdicts, judged = probe_cases.judge_verdicts(_late_feedback(), [by_link])
    assert verdicts == [by_link] and [item.finding.code for item in judged] == ["after_answer"]
    assert judged[0].uncertain and not judged[0].counts, judged
    assert probe_cases.exit_status(verdicts, judged) == probe_cases.EXIT_NOT_RUN
    other = _finding("next.runs_a_child", probe_cases.Verdict.MISSING)
    verdicts, judged = probe_cases.judge_verdicts(_late_feedback(), [other])
    assert [item.counts for item in judged] == [True]
    assert probe_cases.exit_status(verdicts, judged) == probe_cases.EXIT_FAILED


@pytest.mark.spec("R19.1", "R7.3")
def test_a_case_whose_own_records_break_its_rules_fails_with_the_judges_finding() -> None:
    """judge_verdicts: the judge decides a case its script passed when the case's own records break
    one of its rules (or R19.1); a finding on another rule stays beside the cases; an untraced case
    keeps its script's verdict."""
    passed = [_finding("next.runs_a_child", probe_cases.Verdict.PASS)]
    verdicts, judged = probe_cases.judge_verdicts(_late_feedback(), passed)
    assert judged == []
    (finding,) = verdicts
    assert finding.verdict is probe_cases.Verdict.FAIL and finding.divergence is None
    assert finding.seen.startswith("the judge: feedback underway id=6") and "(R19.1)" in finding.expected
    assert probe_cases.exit_status(verdicts, judged) == probe_cases.EXIT_FAILED
    # the log seq the deployed server repeats: R7.3 is no rule of request.seq_stale, whose records
    # hold it here: the finding stays beside the cases, and the case keeps its verdict
    repeated = _with_cases(
        CLEAN.replace('"logs":[{"seq":1,', '"logs":[{"seq":0,', 1),
        ("request.seq_stale", '"goal_uuid":"00000000000000000000000000000001"'),
    )
    stale = [_finding("request.seq_stale", probe_cases.Verdict.PASS)]
    verdicts, judged = probe_cases.judge_verdicts(repeated, stale, known=KNOWN["rmf_ros2"])
    assert verdicts == stale
    assert [(item.finding.rule, item.label, item.known) for item in judged] == [("R7.3", "D9", True)]
    # in feedback.log_seq's records the same finding fails the case, known as the deployed server's
    logs = _with_cases(
        CLEAN.replace('"logs":[{"seq":1,', '"logs":[{"seq":0,', 1),
        ("feedback.log_seq", '"goal_uuid":"00000000000000000000000000000001"'),
    )
    verdicts, judged = probe_cases.judge_verdicts(
        logs, [_finding("feedback.log_seq", probe_cases.Verdict.PASS)], known=KNOWN["rmf_ros2"]
    )
    assert judged == [] and verdicts[0].verdict is probe_cases.Verdict.FAIL
    assert (verdicts[0].divergence, verdicts[0].known) == ("D9", True)
    assert probe_cases.exit_status(verdicts, judged) == probe_cases.EXIT_OK
    # an untraced case (what it fails on a trace cannot show) keeps its script's verdict
    untraced = [_finding("next.status_after_child", probe_cases.Verdict.PASS)]
    verdicts, judged = probe_cases.judge_verdicts(_late_feedback("next.status_after_child"), untraced)
    assert verdicts == untraced and [item.finding.code for item in judged] == ["after_answer"]


def _race(*records: str) -> str:
    """A trace of next.race at a client: run 1 waiting at event 5, NEXTs 6 (goal 1) and 7 (goal 2)
    sent at once and both accepted, then ``records``."""
    begin = {"fleet": "tinyRobot", "robot": "tinyRobot1", "dynamic_event_seq": 1, "description": "{}"}
    lines = [
        json.dumps({"type": "config", "fleet": "tinyRobot", "robot": "tinyRobot1", "tap": "client"}),
        json.dumps({"time": 100, "type": "begin", "message": begin}),
        _race_status(100.1, 1, "standby", 5),
        "# case next.race",
    ]
    for goal, event_id in ((1, 6), (2, 7)):
        next_goal = {"dynamic_event_seq": 1, "event_type": 1, "category": "go_to_place", "description": "{}"}
        next_goal["id"] = event_id
        lines.append(
            json.dumps({"time": 101, "type": "goal", "goal_uuid": f"{goal:032d}", "goal": next_goal})
        )
    for goal in (1, 2):
        lines.append(
            json.dumps(
                {"time": 101.1, "type": "goal_response", "goal_uuid": f"{goal:032d}", "accepted": True}
            )
        )
    return "\n".join([*lines, *records]) + "\n"


def _race_status(time: float, phase: int, status: str, event_id: int) -> str:
    message = {"dynamic_event_seq": 1, "dynamic_state": phase, "status": status, "id": event_id}
    return json.dumps({"time": time, "type": "status", "message": message})


def _race_record(time: float, kind: str, goal: int, event_id: int, failure: str = "") -> str:
    """Goal ``goal``'s start feedback; or its answer: succeeded, completed, or aborted for ``failure``."""
    record: dict[str, object] = {"time": time, "type": kind, "goal_uuid": f"{goal:032d}"}
    if kind == "feedback":
        record["feedback"] = {"status": "underway", "id": event_id, "logs": []}
    elif failure:
        record |= {"result": {"execution_failure": failure, "status": "", "id": 0}, "status": "aborted"}
    else:
        record |= {
            "result": {"execution_failure": "", "status": "completed", "id": event_id},
            "status": "succeeded",
        }
    return json.dumps(record)


@pytest.mark.spec("R5.2", "R6.4")
@pytest.mark.parametrize(
    ("records", "rule"),
    [
        (  # both NEXTs ran a child: the second did not lose the race
            [_race_record(101.2, "feedback", 1, 6), _race_status(101.2, 2, "underway", 6),
             _race_record(101.3, "feedback", 2, 7), _race_status(101.3, 2, "underway", 7),
             _race_record(107, "result", 1, 6), _race_record(107.1, "result", 2, 7),
             _race_status(107.2, 1, "standby", 7)],
            "R5.2",
        ),
        (  # the NEXT that ran no child answered as if it had
            [_race_record(101.2, "feedback", 1, 6), _race_status(101.2, 2, "underway", 6),
             _race_record(107, "result", 1, 6), _race_record(107.1, "result", 2, 7),
             _race_status(107.2, 1, "standby", 6)],
            "R6.4",
        ),
    ],
)  # fmt: skip
def test_a_race_that_two_nexts_won_is_the_judges_failure(records: list[str], rule: str) -> None:
    """next.race's script passes what ran to the judge: two children that ran, or a NEXT that ran none
    answered succeeded, fail the case by the judge's finding on its records, under its rules."""
    verdicts, judged = probe_cases.judge_verdicts(
        _race(*records), [_finding("next.race", probe_cases.Verdict.PASS)]
    )
    (race,) = verdicts
    assert race.verdict is probe_cases.Verdict.FAIL and race.cause == "judge", race
    assert race.expected.endswith(f"({rule})") and judged == [], (race, judged)
    # the NEXT that lost, aborted without a child (R5.2): the script's pass stands
    lost = _race_record(101.3, "result", 2, 7, failure="race condition")
    clean = [_race_record(101.2, "feedback", 1, 6), _race_status(101.2, 2, "underway", 6), lost]
    clean += [_race_record(107, "result", 1, 6), _race_status(107.2, 1, "standby", 6)]
    passed = [_finding("next.race", probe_cases.Verdict.PASS)]
    assert probe_cases.judge_verdicts(_race(*clean), passed) == (passed, [])


@pytest.mark.spec("R19.1")
def test_a_late_record_of_a_goal_belongs_to_the_case_that_sent_it() -> None:
    """A feedback after its goal's answer, received once a later case had begun: the finding is the
    case's that sent the goal, not the later one's, which did nothing wrong; and a case the script
    left ``info`` fails on a finding of its own rules too."""
    text = _late_feedback()
    late = text.index(LATE_FEEDBACK)
    start = text.rindex("\n", 0, late) + 1
    text = text[:start] + "# case request.seq_stale\n" + text[start:]  # the late feedback falls here
    cases = [
        _finding("next.runs_a_child", probe_cases.Verdict.INFO),
        _finding("request.seq_stale", probe_cases.Verdict.PASS),
    ]
    verdicts, judged = probe_cases.judge_verdicts(text, cases)
    assert [finding.verdict for finding in verdicts] == [probe_cases.Verdict.FAIL, probe_cases.Verdict.PASS]
    assert judged == []


# ------------------------------------------------------------------ the inventory of scripted failures

RUNNER = ROOT / "src" / "dynevent" / "conformance" / "probe" / "runner.py"


def _causes(node: ast.expr) -> list[str]:
    """The causes a ``_fails`` call's argument may take: a string, or a choice between strings."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str):
        return [node.value]
    if isinstance(node, ast.IfExp):
        return [*_causes(node.body), *_causes(node.orelse)]
    raise AssertionError(f"runner.py:{node.lineno}: a cause _fails takes is not written as a string")


def test_no_case_fails_but_through_the_judge_or_what_a_trace_cannot_carry() -> None:
    """The runner fails a case in one place, ``_fails``, for a cause of cases.UNTRACEABLE (what a trace
    cannot carry); every other failure is the judge's (judge_verdicts).  Every listed cause is used."""
    tree = ast.parse(RUNNER.read_text(encoding="utf-8"))
    fails = [node for node in ast.walk(tree) if isinstance(node, ast.FunctionDef) and node.name == "_fails"]
    assert len(fails) == 1
    inside = {id(node) for node in ast.walk(fails[0])}
    compared = {
        id(side)
        for node in ast.walk(tree)
        if isinstance(node, ast.Compare)
        for side in (node.left, *node.comparators)
    }
    made = [
        node.lineno
        for node in ast.walk(tree)
        if isinstance(node, ast.Attribute) and node.attr == "FAIL" and id(node) not in inside | compared
        and not _in_tuple_compare(tree, node)
    ]  # fmt: skip
    assert made == [], f"runner.py sets a fail verdict outside _fails, on lines {made}"
    used = [
        cause
        for node in ast.walk(tree)
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "_fails"
        for cause in _causes(node.args[1])
    ]
    listed = set(probe_cases.UNTRACEABLE)
    assert set(used) <= listed, set(used) - listed
    assert set(used) == listed, f"listed and never used: {listed - set(used)}"
    assert "judge" not in listed


def _in_tuple_compare(tree: ast.Module, attribute: ast.Attribute) -> bool:
    """Whether ``attribute`` is an element of a tuple a comparison reads (``verdict in (PASS, FAIL)``)."""
    return any(
        isinstance(node, ast.Compare)
        and any(isinstance(side, ast.Tuple) and attribute in side.elts for side in node.comparators)
        for node in ast.walk(tree)
    )


PROBE_DOC = ROOT / "docs" / "probe.md"
CAUSES = (
    "<!-- the causes a script fails a case for: begin -->",
    "<!-- the causes a script fails a case for: end -->",
)


def test_docs_probe_lists_the_causes_a_script_fails_a_case_for() -> None:
    """docs/probe.md prints cases.causes_text; ``DYNEVENT_UPDATE_CAUSES=1`` rewrites it."""
    text = PROBE_DOC.read_text(encoding="utf-8")
    before, _, rest = text.partition(CAUSES[0] + "\n")
    _, _, after = rest.partition(CAUSES[1])
    fresh = before + CAUSES[0] + "\n" + probe_cases.causes_text() + CAUSES[1] + after
    if os.environ.get("DYNEVENT_UPDATE_CAUSES") == "1":
        PROBE_DOC.write_text(fresh, encoding="utf-8")
    how = "DYNEVENT_UPDATE_CAUSES=1 pytest tests/conformance/probe/test_probe_cases.py"
    assert all(marker in text for marker in CAUSES) and text == fresh, f"docs/probe.md's list is stale: {how}"


@pytest.mark.spec("R19.1")
def test_a_case_that_waited_in_vain_fails_by_the_judge_where_its_records_show_what_never_came() -> None:
    """A case whose script waited out --timeout for NEXT 6's answer (``absent``): the trace shows the
    child's end (its WAITING status) and no answer by its end, so the verdict is the judge's
    (R19.1 answer_missing), not the script's wait; the judge's section does not say it twice."""
    lines = _late_feedback().replace(LATE_FEEDBACK + "\n", "").splitlines()
    text = "\n".join(line for line in lines if not line.startswith('{"time":103,"type":"result"')) + "\n"
    case = next(case for case in probe_cases.CASES if case.id == "next.runs_a_child")
    waited = probe_cases.CaseFinding(
        case, probe_cases.Verdict.FAIL, expected="an answer", seen="no answer within 3 s", absent=True,
        cause="timeout",
    )  # fmt: skip
    verdicts, judged = probe_cases.judge_verdicts(text, [waited])
    (verdict,) = verdicts
    assert (verdict.verdict, verdict.cause, verdict.absent) == (probe_cases.Verdict.FAIL, "judge", False)
    assert verdict.seen.startswith("the judge: goal 00000000000000000000000000000001 never answered")
    assert verdict.expected.endswith("(R19.1)") and judged == [], (verdict, judged)
    # where the trace does not show it (the child still running at its end), the script's wait stands
    running = text[: text.index('{"time":103,"type":"status"')]
    assert probe_cases.judge_verdicts(running, [waited]) == ([waited], [])
    # nor does a finding that says nothing of what never came take the wait over: a divergence --known
    # covers (D9, a log seq repeated) would hide the wait, and the case fails counted for its wait,
    # which says the rest of what it failed on its rules
    repeated = running.replace('"logs":[{"seq":1,', '"logs":[{"seq":0,', 1)
    logs = attrs.evolve(
        waited, case=next(case for case in probe_cases.CASES if case.id == "feedback.log_seq")
    )
    verdicts, judged = probe_cases.judge_verdicts(
        repeated.replace("# case next.runs_a_child", "# case feedback.log_seq"),
        [logs],
        known=KNOWN["rmf_ros2"],
    )
    assert (verdicts, judged) == ([logs], []), (verdicts, judged)
    assert probe_cases.exit_status(verdicts, judged) == probe_cases.EXIT_FAILED


def test_a_known_divergence_in_a_cases_records_never_hides_a_failure_beside_it() -> None:
    """Two findings of the judge in one case's records, the first a divergence --known covers (D9, a
    log seq repeated) and the second not (R19.1, an answer missing): the case fails, counted."""
    text = CLEAN.replace('"logs":[{"seq":1,', '"logs":[{"seq":0,', 1)
    text = "\n".join(line for line in text.splitlines() if not line.startswith('{"time":103,"type":"result"'))
    text = _with_cases(text + "\n", ("feedback.log_seq", '"goal_uuid":"00000000000000000000000000000001"'))
    verdicts, judged = probe_cases.judge_verdicts(
        text, [_finding("feedback.log_seq", probe_cases.Verdict.PASS)], known=KNOWN["rmf_ros2"]
    )
    (verdict,) = verdicts
    assert verdict.verdict is probe_cases.Verdict.FAIL and not verdict.known, verdict
    assert verdict.seen.startswith("the judge: goal 00000000000000000000000000000001 never answered"), verdict
    assert verdict.divergence is None and any("R7.3 log_seq" in said for said in verdict.messages), verdict
    assert probe_cases.exit_status(verdicts, judged) == probe_cases.EXIT_FAILED
