"""``dynevent probe`` against ``dynevent serve`` over DDS: every case passes against the standard
mode, and against the rmf_ros2 mode fails exactly where docs/divergences.md says rmf_ros2 differs and
the mode reproduces it, naming the D-number; ``--known rmf_ros2`` then exits 0.  (How long a probe
takes is measured, not asserted: docs/probe.md.)"""

from __future__ import annotations

import json
import re
import shlex
import signal
import subprocess
import sys
import time
import xml.etree.ElementTree as ET
from collections.abc import Callable
from pathlib import Path

import pytest
from ros_support import Child, child_env, finish

from dynevent.conformance.judge import check_trace
from dynevent.conformance.judge.trace import Finding
from dynevent.conformance.probe.cases import CASES as ALL_CASES
from dynevent.ros.probe import VOLATILE, RosLink
from support.probe_expected import (
    BROKEN,
    INTERRUPTS_IN_PROCESS,
    RMF_ROS2_FAILS,
    RMF_ROS2_INFO,
    UNSEEN_BY_CASES,
)

#: The last seq before the wrap: serve starts there, so that the probe sees the seq wrap (R3.2).
LAST_SEQ = 2**32 - 1

#: The cases the probe runs over DDS without --interrupt-command and --resume-command: it cannot
#: interrupt the robot's task then, and leaves out the cases that do.
CASES = [case for case in ALL_CASES if not case.interrupts]


def _task_commands(robot: str) -> tuple[str, ...]:
    """The probe's flags that interrupt and resume ``robot``'s task: ``dynevent task`` (R14)."""
    task = f"{shlex.quote(sys.executable)} -m dynevent task --robot {robot}"
    return ("--interrupt-command", f"{task} interrupt", "--resume-command", f"{task} resume")


def _config(tmp_path: Path, rebegin: float) -> Path:
    """serve's configuration: brief children that log often, the first run at the seq wrap."""
    config = tmp_path / "fleet.json"
    categories = {"go_to_place": {"duration": 0.5, "report_every": 0.1}}
    config.write_text(
        json.dumps({"categories": categories, "rebegin": rebegin, "first_seq": LAST_SEQ}), encoding="utf-8"
    )
    return config


def _serve(tmp_path: Path, robot: str, mode: str, rebegin: float = 0.5) -> Child:
    config = _config(tmp_path, rebegin)
    serve = Child(
        ["-m", "dynevent", "serve", "--robot", robot, "--config", str(config), "--compatibility", mode]
    )
    serve.wait_line("serving ")
    return serve


def _probe(robot: str, *args: str) -> subprocess.CompletedProcess[str]:
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "dynevent",
            "probe",
            "--robot",
            robot,
            "--place",
            "pantry",
            "lounge",  # the in-process probe's places too (tests/support/probe_expected.py holds both)
            "--timeout",
            "5",
            *args,
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=child_env(),
    )
    return finish(process, 120)


def _verdicts(output: str) -> dict[str, str]:
    ids = {case.id for case in ALL_CASES}
    verdicts = {}
    for line in output.splitlines():
        words = line.split()
        if words and words[0] in ids and words[0] not in verdicts:
            # fail (D7), known (D7), missing (allowed)
            numbered = len(words) > 2 and (words[2].startswith("(D") or words[2] == "(allowed)")
            verdicts[words[0]] = " ".join(words[1:3]) if numbered else words[1]
    return verdicts


def _waiting_canceled(finding: Finding) -> bool:
    """check's finding of D28: the status after a cancelled child's end says WAITING ``canceled``."""
    return (
        finding.rule == "R2.2"
        and re.search(r"status WAITING seq=\d+ id=\d+ canceled", finding.message) is not None
    )


def _rmf_ros2_everywhere(finding: Finding) -> bool:
    """What check, in standard mode, finds wherever a child ends or starts under rmf_ros2 mode: D28's
    status, and D10's numbering (a child whose plan drew an id, R17.8, puts the next child two on,
    whichever case sends it)."""
    return _waiting_canceled(finding) or (finding.rule == "R6.2" and finding.code == "child_id")


def _check_agrees(
    trace: Path, junit: Path, *, only_failed: bool = True, everywhere: Callable[[Finding], bool] | None = None
) -> set[str]:
    """``dynevent check`` on the probe's trace agrees with the probe's verdicts: it finds a violation
    within every case the probe failed on a message it saw (not one that never came) whose failure a
    trace shows (``Case.trace_shows_failure``); with ``only_failed``, within no case the probe passed.
    (A defect that shows in every message, a wrong feedback id, is found by check in every case, and
    by the probe in the case of its rule: so not ``only_failed`` for broken servers; ``everywhere``
    names the findings of such a defect that check may make in the other cases.)  The cases it found."""
    text = trace.read_text("utf-8")
    case_at: dict[int, str] = {}
    current = ""
    for number, line in enumerate(text.splitlines(), start=1):
        if line.startswith("# case "):
            current = line.removeprefix("# case ")
        case_at[number] = current
    report = check_trace(text, str(trace))
    found = {case_at[finding.line] for finding in report.findings}
    elsewhere = {
        case_at[finding.line] for finding in report.findings if everywhere is None or not everywhere(finding)
    }
    failed, seen = set(), set()
    cases = ET.parse(junit).getroot().find("testsuite")  # the cases' suite (the judge's is the second)
    assert cases is not None
    for test in cases.iter("testcase"):
        properties = {item.get("name"): item.get("value") for item in test.iter("property")}
        if str(properties["verdict"]).startswith(("fail", "known")):
            failed.add(test.get("name"))
            # a RUNNING status with the child's end (D2) is one a passive observer cannot tell from
            # the moment R20.2 allows a server: check does not see it
            if "absent" not in properties and "(D2)" not in str(properties["verdict"]):
                seen.add(test.get("name"))
    shown_by_trace = {case.id for case in CASES if case.trace_shows_failure}
    findings = [finding.to_dict() for finding in report.findings]
    assert seen & shown_by_trace <= found, findings
    if only_failed:
        assert elsewhere <= failed, findings
    assert failed or report.clean, findings
    return found


@pytest.mark.spec(
    "R3.2", "R4.2", "R4.4", "R4.13", "R7.3", "R9.3", "R10.3", "R10.5", "R11.1", "R12.2", "R16.2", "R20.1"
)
def test_the_standard_mode_of_serve_passes_every_case(tmp_path: Path) -> None:
    """Every case, those that interrupt the robot's task too (through ``dynevent task``)."""
    serve = _serve(tmp_path, "probeStandard", "standard")
    try:
        outputs = ("--junit", str(tmp_path / "probe.xml"), "--trace", str(tmp_path / "t"))
        done = _probe("probeStandard", *outputs, *_task_commands("probeStandard"))
    finally:
        code = serve.stop()
    assert done.returncode == 0, done.stdout + done.stderr
    assert _verdicts(done.stdout) == {case.id: "pass" for case in ALL_CASES}, done.stdout
    assert _check_agrees(tmp_path / "t", tmp_path / "probe.xml") == set()
    # over a link that lost nothing the probe heard the server out: the trace says so, last
    assert '"type":"end"' in (tmp_path / "t").read_text("utf-8").splitlines()[-1]
    assert done.stdout.splitlines()[-2:-1] == [f"{len(ALL_CASES)} pass"], done.stdout  # then the run's time
    run_took(done.stdout)
    suite = ET.parse(tmp_path / "probe.xml").getroot().find("testsuite")
    assert suite is not None and suite.get("tests") == str(len(ALL_CASES)) and suite.get("failures") == "0"
    assert code == 0, serve.output


@pytest.mark.spec("R14.2", "R6.3", "R9.4", "R10.4")
def test_a_server_that_ignores_an_interruption_fails_the_cases_that_interrupt_it_over_dds(
    tmp_path: Path,
) -> None:
    """The cases a link that cannot interrupt the task leaves out run over DDS with the task commands,
    and fail a server whose interruption changes nothing, as in process."""
    robot = "broken_ignores_interrupt"
    done = _probe_broken(
        tmp_path, "ignores_interrupt", robot, "--cases", "interrupt.*", *_task_commands(robot)
    )
    assert done.returncode == 1, done.stdout + done.stderr
    assert _verdicts(done.stdout) == INTERRUPTS_IN_PROCESS["ignores_interrupt"], done.stdout
    assert "feedback 'underway'" in done.stdout, done.stdout


@pytest.mark.spec("R17.4")
def test_the_rmf_ros2_mode_fails_exactly_at_its_recorded_divergences(tmp_path: Path) -> None:
    serve = _serve(tmp_path, "probeCompat", "rmf_ros2")
    try:
        strict = _probe("probeCompat", "--trace", str(tmp_path / "t"), "--junit", str(tmp_path / "j.xml"),
                        "--report", str(tmp_path / "report.html"))  # fmt: skip
        known = _probe("probeCompat", "--known", "rmf_ros2")
    finally:
        code = serve.stop()
    assert strict.returncode == 1, strict.stdout + strict.stderr
    expected = {case.id: "pass" for case in CASES}
    expected.update(dict.fromkeys(RMF_ROS2_INFO, "info"))  # no description service (D17): the spec allows
    expected.update({case: f"fail ({number})" for case, number in RMF_ROS2_FAILS.items()})
    assert _verdicts(strict.stdout) == expected, strict.stdout
    # D28 shows wherever a child is cancelled, the probe's own clean-ups too: the probe judges it in
    # cancel.running_child, check at every such end; D10 wherever a child comes after one that planned
    _check_agrees(tmp_path / "t", tmp_path / "j.xml", everywhere=_rmf_ros2_everywhere)
    page = (tmp_path / "report.html").read_text("utf-8")
    for case, number in RMF_ROS2_FAILS.items():
        assert f'<h2 id="{case}">{case}: fail ({number})</h2>' in page
    assert known.returncode == 0, known.stdout + known.stderr
    expected.update({case: f"known ({number})" for case, number in RMF_ROS2_FAILS.items()})
    # the first probe saw the one wrap: the runs are at 1 now, and --known rmf_ros2 expects it missing
    expected["begin.seq_wrap"] = "missing (allowed)"
    verdicts = _verdicts(known.stdout)
    # the second probe does not know where the first left the robot: a case whose child comes first
    # after a NEXT to where the robot already stood (no plan, no id drawn, R17.8) gets the id it
    # predicted, as on the deployed adapter
    for case in ("next.id_zero", "next.stateless_id"):
        assert verdicts.pop(case) in ("pass", expected.pop(case)), known.stdout
    assert verdicts == expected, known.stdout
    assert code == 0, serve.output


def test_no_server_is_exit_2_in_one_line(tmp_path: Path) -> None:
    done = _probe("nobodyHere", "--server-wait", "1")
    assert done.returncode == 2
    line = done.stdout.strip()
    assert line.startswith("no Dynamic Event server for tinyRobot/nobodyHere within 1 s; "), line
    assert "\n" not in line
    assert "Traceback" not in done.stderr


def _probe_broken(tmp_path: Path, defect: str, robot: str, *args: str) -> subprocess.CompletedProcess[str]:
    """The probe (``--timeout 3``, JUnit in j.xml) against a server of tests/ros/broken_serve.py."""
    config = _config(tmp_path, rebegin=0.3)
    script = Path(__file__).resolve().parent / "broken_serve.py"
    serve = Child([str(script), defect, "--robot", robot, "--config", str(config)])
    serve.wait_line("serving ")
    try:
        return _probe(robot, "--timeout", "3", "--junit", str(tmp_path / "j.xml"), *args)
    finally:
        serve.stop()


def _over_dds(verdicts: dict[str, str]) -> dict[str, str]:
    """Of the verdicts the probe in process gives, those of the cases it runs over DDS."""
    ids = {case.id for case in CASES}
    return {case: verdict for case, verdict in verdicts.items() if case in ids}


@pytest.mark.parametrize("defect", list(BROKEN))
def test_a_broken_server_is_caught_by_the_case_of_the_rule_it_breaks(tmp_path: Path, defect: str) -> None:
    """Every other case passes: no false failure (a case that cannot be reached is missing, and
    only where the defect makes it so)."""
    done = _probe_broken(tmp_path, defect, f"broken_{defect}", "--trace", str(tmp_path / "t"))
    assert done.returncode == 1, done.stdout + done.stderr
    expected = {case.id: "pass" for case in CASES}
    expected.update(_over_dds(BROKEN[defect]))
    assert _verdicts(done.stdout) == expected, done.stdout
    _check_agrees(tmp_path / "t", tmp_path / "j.xml", only_failed=False)
    rules = {case.id: case.rules for case in CASES}
    for case in _over_dds(BROKEN[defect]):
        if BROKEN[defect][case].startswith("fail"):
            assert f"{case} ({', '.join(rules[case])}): fail" in done.stdout, done.stdout


@pytest.mark.spec("R3.1")
@pytest.mark.parametrize("defect", list(UNSEEN_BY_CASES))
def test_the_judge_over_every_record_finds_what_no_case_looks_for(tmp_path: Path, defect: str) -> None:
    """The probe's verdicts come from its cases and from the judge ``dynevent check`` runs, fed every
    record of the exchange: a defect no case looks for still fails the run, in its own section."""
    done = _probe_broken(tmp_path, defect, f"unseen_{defect}")
    cases, found = UNSEEN_BY_CASES[defect]
    assert done.returncode == 1, done.stdout + done.stderr
    expected = {case.id: "pass" for case in CASES}
    expected.update(cases)
    assert _verdicts(done.stdout) == expected, done.stdout
    section = done.stdout.split("the judge, over every record of the exchange: ", 1)
    assert len(section) == 2, done.stdout
    assert f": fail: {found}: " in section[1], done.stdout
    suites = ET.parse(tmp_path / "j.xml").getroot().findall("testsuite")
    assert [suite.get("name") for suite in suites][1:] == ["the judge, over every record"]
    assert int(suites[1].get("failures", "0")) >= 1


@pytest.mark.parametrize("begin", [(), ("--begin-command", "true")], ids=["alone", "with a begin command"])
def test_a_volatile_status_is_caught_and_the_run_stops_early(tmp_path: Path, begin: tuple[str, ...]) -> None:
    """A server whose status and begin topics are volatile (R1.4 says transient-local) fails
    status.latched; the probe says at once that no status came, and the cases that need a run are
    not run, saying why, rather than each wait out the timeout (it once took over 4 minutes, 10 s a
    case; 370 s with a begin command, run for each case that finds no run)."""
    config = _config(tmp_path, rebegin=0.3)
    serve = Child([str(Path(__file__).resolve().parent / "broken_serve.py"), "volatile_status",
                   "--robot", "brokenVolatile", "--config", str(config)])  # fmt: skip
    serve.wait_line("serving ")
    try:
        done = _probe("brokenVolatile", "--timeout", "2", *begin)
    finally:
        serve.stop()
    assert done.returncode == 1, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    # the cause, from rclpy's incompatible-QoS event: the topic's durability, not a silent server
    said = f"within 2 s: the status topic is {VOLATILE}"
    assert lines[0] == f"no status from tinyRobot/brokenVolatile {said}", done.stdout
    assert _verdicts(done.stdout)["status.latched"] == "fail", done.stdout
    assert f"seen:     the status topic is {VOLATILE}" in done.stdout
    assert f"no status was heard {said}" in done.stdout
    assert run_took(done.stdout) < silent_bound(2.0), done.stdout


@pytest.mark.spec("R1.4")
def test_a_status_topic_offered_volatile_is_named_and_still_heard() -> None:
    """The probe's reader asks for transient-local; a volatile writer never matches it.  The link
    names the durability from rclpy's incompatible-QoS event and reads the topic volatile too, so
    that what the server publishes from then on is heard, and the rest of it can still be judged."""
    from rclpy.event_handler import PublisherEventCallbacks
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from ros_support import Graph, wait_for

    from dynevent.ros import convert
    from dynevent.wire.messages import DynamicEventStatus, Time
    from dynevent.wire.names import status_topic

    server_side, probe_side = Graph(), Graph()  # two participants, as a server and a probe are
    try:
        qos = QoSProfile(
            depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE
        )
        topic = status_topic("tinyRobot", "volatile1")
        # the writer's own side of the event is not the test's: rclpy's default would warn of it
        quiet = PublisherEventCallbacks(incompatible_qos=lambda _: None)
        publisher = server_side.node(
            "volatile_server",
            lambda node: node.create_publisher(convert.RosStatus, topic, qos, event_callbacks=quiet),
        )
        link = probe_side.node("volatile_probe", lambda node: RosLink(node, "tinyRobot", "volatile1"))
        wait_for(lambda: link.offered.get("status") == VOLATILE, "the durability named")
        status = DynamicEventStatus(
            dynamic_event_seq=3, dynamic_state=1, status="standby", id=1, time=Time(sec=5, nanosec=0)
        )

        def heard() -> bool:  # the volatile reader is matched a moment after the event: publish till then
            publisher.publish(convert.status_to_ros(status))
            return link.wait_status(lambda _: True, 0.1) is not None

        wait_for(heard, "a status heard on the volatile reader")
        assert link.status == status
    finally:
        probe_side.close()
        server_side.close()


@pytest.mark.spec("R1.4")
def test_the_server_is_found_once_its_status_publisher_is_matched_too() -> None:
    """Over a lossy link the action server and the status publisher are discovered apart, seconds
    apart: the probe's link finds the server only once its status reader is matched too (a status it
    is not matched to cannot come, and R1.4 would be judged on discovery), and within its bound finds
    a server that has no status publisher at all."""
    import threading

    from rclpy.action import ActionServer
    from ros_support import Graph

    from dynevent.ros import convert
    from dynevent.ros.qos import latched
    from dynevent.wire.names import action_name, status_topic

    server_side, probe_side = Graph(), Graph()
    try:
        server_side.node(
            "statusless_server",
            lambda node: ActionServer(
                node, convert.DynamicEvent, action_name("tinyRobot", "late1"), lambda goal: None
            ),
        )
        link = probe_side.node("late_probe", lambda node: RosLink(node, "tinyRobot", "late1"))
        assert link.wait_for_server(2.0)  # no status publisher: found all the same, within the bound
        published = threading.Event()
        found: list[int] = []

        def find() -> None:
            found.append(link.wait_for_server(60.0))
            found.append(link._subscriptions[0].get_publisher_count())
            found.append(published.is_set())

        finder = threading.Thread(target=find)
        finder.start()
        time.sleep(1.0)
        published.set()
        server_side.node(
            "late_status",
            lambda node: node.create_publisher(
                convert.RosStatus, status_topic("tinyRobot", "late1"), latched(1)
            ),
        )
        finder.join(60.0)
        assert found == [True, 1, True]
    finally:
        probe_side.close()
        server_side.close()


#: What the probe's own work may add to the waits that bound a run, in seconds: the bounds below are the
#: probe's own clock of its run, from the server found to the last case's end (the line "the run
#: took"), never the time a process takes to start and close, which depends on the machine.
WORK = 2.0


def silent_bound(timeout: float) -> float:
    """The bound docs/probe.md gives for a run against a server that answers nothing, once the server
    is found: the first status, and three cases of at most two waits each."""
    return timeout * 7 + WORK


def run_took(stdout: str) -> float:
    """The seconds the probe says its run took."""
    match = re.fullmatch(r"the run took ([0-9.]+) s \(--deadline [0-9.]+ s\)", stdout.splitlines()[-1])
    assert match is not None, stdout  # the run's last line
    return float(match.group(1))


def test_a_silent_server_ends_the_run_within_its_bound(tmp_path: Path) -> None:
    """A server on the graph that publishes nothing and answers no goal: the run ends within
    docs/probe.md's bound, every case failed or not run, none passed, and the exit status says so."""
    silent = Child([str(Path(__file__).resolve().parent / "silent_server.py"), "silentRobot"])
    silent.wait_line("serving silently")
    try:
        done = _probe("silentRobot", "--timeout", "2")
    finally:
        silent.stop()
    assert done.returncode == 1, done.stdout + done.stderr
    verdicts = _verdicts(done.stdout)
    assert len(verdicts) == len(CASES) and "pass" not in verdicts.values(), done.stdout
    assert sum(1 for verdict in verdicts.values() if verdict == "missing") >= len(CASES) - 6, done.stdout
    assert done.stdout.splitlines()[0].startswith("no status from tinyRobot/silentRobot"), done.stdout
    assert "no status was heard within 2 s (R1.4)" in done.stdout
    took = run_took(done.stdout)
    assert took < silent_bound(2.0), f"{took:.1f} s"
    print(f"probe against a silent server, --timeout 2: {took:.1f} s")


@pytest.mark.spec("R19.1")
def test_a_server_that_never_answers_a_next_ends_the_run_within_its_deadline(tmp_path: Path) -> None:
    """A NEXT whose child completes is never answered: every case that runs a child to its end waits
    out its --timeout; --deadline bounds the run (it once took 372 s), the cases left not run, with why."""
    config = _config(tmp_path, rebegin=0.3)
    script = Path(__file__).resolve().parent / "broken_serve.py"
    serve = Child([str(script), "hangs_next", "--robot", "hangsDeadline", "--config", str(config)])
    serve.wait_line("serving ")
    deadline = 15.0
    try:
        done = _probe("hangsDeadline", "--timeout", "3", "--deadline", str(deadline))
    finally:
        serve.stop()
    assert done.returncode == 1, done.stdout + done.stderr
    assert "the run's --deadline of 15 s passed" in done.stdout, done.stdout
    assert "missing" in _verdicts(done.stdout).values()
    took = run_took(done.stdout)  # the close-down after it has its own bound (spinning.CLOSE_BOUND)
    assert deadline <= took < deadline + WORK, f"{took:.1f} s"


def test_missing_cases_fail_the_run_unless_allowed(tmp_path: Path) -> None:
    """Without a place, the cases that send the robot somewhere are not run: the first line says so,
    the run exits 3 (it once exited 0, a green CI for a server mostly not tested), and 0 when those
    cases are allowed to be missing."""
    serve = _serve(tmp_path, "probeNoPlace", "standard")
    try:
        command = [sys.executable, "-m", "dynevent", "probe", "--robot", "probeNoPlace", "--timeout", "5",
                   "--cases", "request.*", "next.runs_a_child"]  # fmt: skip
        plain = finish(subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                        env=child_env()), 120)  # fmt: skip
        allowing = ["--allow-missing", "next.*", "request.seq_*_next", "request.stubborn_nan"]
        allowed = finish(
            subprocess.Popen(
                [*command, *allowing],
                stdout=subprocess.PIPE,
                stderr=subprocess.PIPE,
                text=True,
                env=child_env(),
            ),
            120,
        )
    finally:
        serve.stop()
    assert plain.returncode == 3, plain.stdout + plain.stderr
    lines = plain.stdout.splitlines()
    assert lines[0] == (
        "no --place, and no run's description names one: the 4 case(s) that send the robot somewhere "
        "will not run"
    ), plain.stdout
    assert lines[1].startswith("4 of 12 case(s) not run: no place to send the robot to"), plain.stdout
    assert _verdicts(plain.stdout)["next.runs_a_child"] == "missing"
    assert allowed.returncode == 0, allowed.stdout + allowed.stderr
    assert "4 of 12 case(s) not run, 4 of them expected" in allowed.stdout
    assert _verdicts(allowed.stdout)["next.runs_a_child"] == "missing (allowed)"


def test_a_begin_command_that_cannot_run_makes_the_cases_missing_not_a_crash(tmp_path: Path) -> None:
    """No run is active (the robot's run ended and serve begins no other), so the probe runs the
    begin command; one that cannot run is said, per case, and nothing crashes."""
    serve = _serve(tmp_path, "probeNoRun", "standard", rebegin=0)
    try:
        assert _probe("probeNoRun", "--cases", "finished.ends_the_run").returncode == 0
        done = _probe("probeNoRun", "--cases", "request.seq_stale", "--timeout", "1",
                      "--begin-command", "no-such-command-here")  # fmt: skip
    finally:
        serve.stop()
    assert done.returncode == 3, done.stdout + done.stderr  # not run: not a failure, not a pass
    assert _verdicts(done.stdout) == {"request.seq_stale": "missing"}, done.stdout
    assert "--begin-command 'no-such-command-here' did not run" in done.stdout
    assert "Traceback" not in done.stderr


def _interrupted_probe(robot: str, signum: int, after: float) -> subprocess.CompletedProcess[str]:
    argv = [sys.executable, "-m", "dynevent", "probe", "--robot", robot, "--place", "pantry",
            "--timeout", "5", "--server-wait", "30"]  # fmt: skip
    process = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env()
    )
    time.sleep(after)
    process.send_signal(signum)
    return finish(process, 30)


def test_a_probe_interrupted_says_what_it_ran_and_stops_without_a_traceback(tmp_path: Path) -> None:
    """SIGTERM while the probe waits for a server, and Ctrl-C in the middle of its cases: each ends it
    in a line (128 + the signal), after the report of the cases that ended (rcl's traceback once)."""
    waiting = _interrupted_probe("nobodyHere", signal.SIGTERM, 2.0)
    assert waiting.returncode == 143, waiting.stdout + waiting.stderr
    assert "Traceback" not in waiting.stderr, waiting.stderr
    assert f"SIGTERM: stopped after 0 of {len(CASES)} case(s); the rest not run" in waiting.stdout
    serve = _serve(tmp_path, "stopRobot", "standard")
    try:
        midway = _interrupted_probe("stopRobot", signal.SIGINT, 6.0)
    finally:
        serve.stop()
    assert midway.returncode == 130, midway.stdout + midway.stderr
    assert "Traceback" not in midway.stderr, midway.stderr
    ran = re.search(rf"SIGINT: stopped after (\d+) of {len(CASES)} case\(s\)", midway.stdout)
    assert ran is not None and 0 < int(ran[1]) < len(CASES), midway.stdout
    assert "status.latched                pass" in midway.stdout  # the report of the cases that ran


#: ``dynevent probe`` in a process whose ROS close-down hangs (the middleware's, inside
#: ``close_down``), bounded at 2 s instead of 20.
_HANGS_AT_CLOSE = """
import sys, time
from dynevent.ros import spinning
from dynevent.tools.cli import main
spinning.close_down = lambda *args, **kwargs: time.sleep(600)
spinning.Session.close.__kwdefaults__["bound"] = 2.0
sys.exit(main(["probe", *sys.argv[1:]]))
"""


def test_a_close_down_that_hangs_ends_at_its_bound_after_the_report(tmp_path: Path) -> None:
    """The probe's report (its verdicts and the run's last line) is printed, and reaches a pipe, before
    its ROS close-down, which a bound ends (every thread's stack, exit status 1): a close-down that
    hangs in the middleware loses no verdict (found in CI: a probe whose close-down outlasted its
    bound printed nothing, its report held in Python's buffer at the ending)."""
    serve = _serve(tmp_path, "hangsAtClose", "standard")
    try:
        process = subprocess.Popen(
            [sys.executable, "-c", _HANGS_AT_CLOSE, "--robot", "hangsAtClose", "--timeout", "5",
             "--cases", "status.waiting"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
        )  # fmt: skip
        done = finish(process, 60)
    finally:
        serve.stop()
    assert done.returncode == 1, done.stdout + done.stderr
    assert _verdicts(done.stdout) == {"status.waiting": "pass"}, done.stdout + done.stderr
    assert "the run took" in done.stdout, done.stdout
    # the bound's ending: every thread's stack, the main thread's in the session's close
    assert done.stderr.startswith("Timeout (0:00:02)!"), done.stderr
    assert re.search(r"dynevent/ros/spinning\.py\", line \d+ in close\n", done.stderr), done.stderr
