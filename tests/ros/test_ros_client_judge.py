"""``dynevent serve`` judges the clients that talk to it (docs/spec.md section 22), over DDS: each
deliberately broken client (a probe case that sends what a client must not, run as its own process,
so its own action client) is caught by its rule and named by its action client's GID; dynevent's own
``send`` (the client machine) is judged clean; a run left open is its last driver's at exit; the
summary, the ``--report`` and a ``--trace`` that check finds clean are written at exit, and ``send
--trace`` writes what send sent and received, which check finds clean too."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest
from ros_support import Child, child_env, finish, wait_for

from dynevent.conformance.judge import check_trace

ROBOT = "judged1"

#: Each broken client (the probe cases it runs) and the one rule serve must name for it.
BROKEN_CLIENTS = [
    (["request.seq_stale"], "R22.2 stale_seq"),
    (["request.event_type_0"], "R22.7 never_acceptable"),
    (["request.cancel_idle"], "R22.5 cancel_not_running"),
    (["next.id_stale"], "R22.6 stale_id"),
    (["next.busy"], "R22.4 next_while_running"),
    (["finished.ends_the_run", "finished.next_after"], "R22.3 after_finished"),
]


def _run(*args: str) -> subprocess.CompletedProcess[str]:
    process = subprocess.Popen(
        [sys.executable, "-m", "dynevent", *args, "--robot", ROBOT],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )  # fmt: skip
    return finish(process, 90)


def _findings(serve: Child) -> list[str]:
    return [line for line in serve.lines if "  client judge: " in line]


@pytest.mark.spec("R22.1", "R22.2", "R22.3", "R22.4", "R22.5", "R22.6", "R22.7", "R22.8")
def test_serve_names_each_broken_client_by_its_rule_and_judges_send_clean(tmp_path: Path) -> None:
    config = tmp_path / "fleet.json"
    config.write_text(json.dumps({"categories": {"go_to_place": {"duration": 0.5, "report_every": 0.1}},
                                  "rebegin": 0.5}), encoding="utf-8")  # fmt: skip
    report, trace = tmp_path / "judgement.md", tmp_path / "serve.jsonl"
    serve = Child(["-m", "dynevent", "serve", "--robot", ROBOT, "--config", str(config),
                   "--report", str(report), "--trace", str(trace)])  # fmt: skip
    clients = []
    try:
        serve.wait_line("serving ")
        for cases, rule in BROKEN_CLIENTS:
            before = len(_findings(serve))
            done = _run("probe", "--place", "pantry", "--timeout", "5", "--cases", *cases)
            assert done.returncode == 0, done.stdout + done.stderr
            serve.wait_line(rule)
            new = _findings(serve)[before:]
            assert len(new) == 1 and rule in new[0], (cases, new)
            clients.append(re.search(r"client judge: (client \d+ \(gid [0-9a-f]{32}\))", new[0]).group(1))  # type: ignore[union-attr]
        assert len(set(clients)) == len(clients), clients  # each process its own action client (R22.1)
        before = len(_findings(serve))
        for name, args in (("next", ["--place", "pantry"]), ("end", ["--end"])):  # the client machine
            sent = _run("send", "--timeout", "20", "--trace", str(tmp_path / f"send-{name}.jsonl"), *args)
            assert sent.returncode == 0, sent.stdout + sent.stderr
        runs = sum(1 for line in serve.lines if "begin: run" in line)
        wait_for(
            lambda: sum(1 for line in serve.lines if "begin: run" in line) > runs, "the next run (rebegin)"
        )
        left_open = _run("send", "--timeout", "20", "--place", "pantry")  # a run driven, never ended
        assert left_open.returncode == 0, left_open.stdout + left_open.stderr
        assert _findings(serve)[before:] == [], serve.output
    finally:
        code = serve.stop()
    assert code == 0, serve.output
    last = _findings(serve)[-1]
    assert "R22.8 run_left_open" in last and clients[0] not in last, serve.output
    summary = next(line for line in serve.lines if "client judgement:" in line)
    assert f"{len(BROKEN_CLIENTS) + 1} finding(s)" in summary, summary
    text = report.read_text("utf-8")
    assert text.startswith("# dynevent serve: the judgement of its clients")
    assert sum(1 for line in text.splitlines() if line.startswith("| ") and " R22." in line) == 7
    checked = check_trace(trace.read_text("utf-8"), str(trace))
    assert checked.records > 30 and checked.clean, checked.findings[:3]
    # the goals serve refused are in its trace too, each with its reason (R4.15)
    rows = [json.loads(line) for line in trace.read_text("utf-8").splitlines()]
    reasons = {row.get("reason") for row in rows if row["type"] == "goal_response" and not row["accepted"]}
    assert {
        "seq_mismatch",
        "uninitialized_event_type",
        "cancel_idle",
        "stale_id",
        "busy",
        "inactive",
    } <= reasons
    # send's own --trace, a tap at the client: every message it sent and received, clean under check
    kinds = {"next": ["status", "begin", "goal", "goal_response", "feedback", "result"],
             "end": ["status", "begin", "goal", "goal_response", "result"]}  # fmt: skip
    for name, wanted in kinds.items():
        text = (tmp_path / f"send-{name}.jsonl").read_text("utf-8")
        rows = [json.loads(line) for line in text.splitlines()[1:]]
        assert sorted({row["type"] for row in rows}, key=wanted.index) == wanted, (name, rows)
        checked = check_trace(text, name)
        assert checked.clean, (name, checked.findings[:3])


@pytest.mark.spec("R22.1", "R22.2")
def test_without_introspection_a_refused_goal_is_judged_as_the_one_clients() -> None:
    """Where rclpy cannot introspect the action server, every goal is one client's, judged from the
    server's steps: a refused goal is the step of its request (the binding knows its UUID), so it is
    judged too."""
    from dynevent.server import inputs as ins
    from dynevent.server import machine
    from dynevent.tools.live.serve import Watch, _Clients, _Judged
    from dynevent.wire.messages import Goal

    said: list[str] = []
    config = machine.ServerConfig()
    judged = _Judged("tinyRobot", ROBOT, config, Watch(), _Clients(), said.append, None)
    state = machine.State.new("tinyRobot", ROBOT)
    begin = ins.Begin(description="{}", event_id=1, now=10**9)
    state, outputs = machine.step(state, begin, config)
    judged.on_step(begin, outputs)
    stale = ins.GoalRequested(
        goal_uuid="ab" * 16, goal=Goal(dynamic_event_seq=0, event_type=3), now=5 * 10**9
    )
    _, outputs = machine.step(state, stale, config)
    judged.on_step(stale, outputs)
    assert len(said) == 1 and "R22.2 stale_seq" in said[0] and ": a client: " in said[0], said
