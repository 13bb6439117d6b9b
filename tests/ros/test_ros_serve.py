"""``dynevent serve`` and ``dynevent send`` as separate processes over DDS, with kill -9 and a restart."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from ros_support import START, Child, Graph, wait_for

from dynevent.ros import DynamicEventClient

ROBOT = "serveRobot"


class Serve(Child):
    """A ``dynevent serve`` process and its live log."""

    def __init__(self, *args: str) -> None:
        import tempfile

        self.tmp = tempfile.mkdtemp(prefix="dynevent-serve-")
        super().__init__(["-m", "dynevent", "serve", "--robot", ROBOT, "--rebegin", "0", *args])

    def ready(self) -> Serve:
        """Wait (bounded) for the line serve prints once its robots are on the graph."""
        self.wait_line("serving ")
        return self


def send(*args: str, timeout: float = 20.0) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "dynevent", "send", "--robot", ROBOT, "--timeout", str(timeout), *args],
        capture_output=True,
        text=True,
        timeout=timeout + 15,
        env=os.environ.copy(),
        check=False,
    )


@pytest.fixture
def watcher(graph: Graph) -> Iterator[DynamicEventClient]:
    client: DynamicEventClient = graph.node(
        "watcher", lambda node: DynamicEventClient(node, "tinyRobot", ROBOT)
    )
    yield client


@pytest.mark.spec("R21.1", "R21.2", "R21.3", "R20.1")
def test_serve_and_send_survive_kill_9_in_the_middle_of_a_child(tmp_path: Path, watcher: Any) -> None:
    config = tmp_path / "fleet.json"
    config.write_text(
        json.dumps(
            {"categories": {"go_to_place": {"duration": 1.0, "report_every": 0.25}, "slow": {"duration": 60}}}
        ),
        encoding="utf-8",
    )
    state = tmp_path / "state.db"
    serve = Serve("--config", str(config), "--state", str(state)).ready()
    try:
        done = send("--place", "pantry")
        assert done.returncode == 0, done.stdout + done.stderr
        assert "outcome: completed" in done.stdout and "[id 2]" in done.stdout
        assert (
            wait_for(lambda: watcher.state.current_id == 2 and watcher.state.phase == 1, "WAITING id 2")
            is None
        )
        (tmp_path / "slow.json").write_text('{"category": "slow", "description": {}}', encoding="utf-8")
        slow = subprocess.Popen(
            [
                sys.executable,
                "-m",
                "dynevent",
                "send",
                "--robot",
                ROBOT,
                "--timeout",
                "6",
                "--file",
                str(tmp_path / "slow.json"),
            ],
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=os.environ.copy(),
        )
        wait_for(lambda: watcher.state.phase == 2 and watcher.state.current_id == 3, "child 3 running")
        serve.process.send_signal(signal.SIGKILL)
        assert serve.stop() == -signal.SIGKILL
        assert slow.wait(timeout=30) == 1  # its server died: no answer within its bound
        serve = Serve("--config", str(config), "--state", str(state)).ready()
        wait_for(lambda: serve.saw("restored: run 1, last id 3"), "the restore")
        wait_for(lambda: watcher.state.phase == 1 and watcher.state.current_id == 3, "WAITING id 3 again")
        assert watcher.state.seq == 1  # the same run goes on
        done = send("--place", "lobby")
        assert done.returncode == 0, done.stdout + done.stderr
        assert "[id 4]" in done.stdout  # ids continue
        ended = send("--end")
        assert ended.returncode == 0, ended.stdout
    finally:
        code = serve.stop()
    assert code == 0, serve.output


def test_a_foreign_state_file_is_refused_and_left_as_it_was(tmp_path: Path) -> None:
    state = tmp_path / "state.db"
    state.write_bytes(b"not a database" * 100)
    serve = Serve("--state", str(state), "--seconds", "5")
    assert serve.process.wait(timeout=START) == 2
    serve.stop()
    assert any("is not a dynevent state store" in line for line in serve.lines), serve.lines
    assert not any("Traceback" in line for line in serve.lines)
    assert state.read_bytes() == b"not a database" * 100


@pytest.mark.spec("R4.13")
def test_send_explains_and_exits_by_the_outcome(watcher: Any) -> None:
    serve = Serve().ready()
    try:
        wait_for(lambda: watcher.state.phase == 1, "WAITING")
        idle = send("--cancel")
        assert idle.returncode == 1
        assert "cancel_idle" in idle.stdout
        usage = send("--cancel", "--end")
        assert usage.returncode == 2 and "exactly one of" in usage.stderr
        missing = subprocess.run(
            [sys.executable, "-m", "dynevent", "send", "--robot", "nobody", "--end", "--timeout", "2"],
            capture_output=True,
            text=True,
            timeout=30,
            env=os.environ.copy(),
            check=False,
        )
        assert missing.returncode == 2 and "no Dynamic Event server" in missing.stdout
        assert "Traceback" not in missing.stderr
    finally:
        code = serve.stop()
    assert code == 0, serve.output


@pytest.mark.spec("R3.1", "R4.7")
def test_serve_begins_on_command_and_send_explains_a_refusal_it_cannot_see(
    graph: Graph, watcher: Any
) -> None:
    from rmf_task_msgs.msg import DynamicEventDescription

    from dynevent.ros.serve import BEGIN_COMMAND_TOPIC
    from dynevent.ros.server import latched

    serve = Serve().ready()
    try:
        wait_for(lambda: watcher.state.phase == 1, "WAITING")
        assert send("--end").returncode == 0
        wait_for(lambda: watcher.state.phase == 0, "INACTIVE: --rebegin 0 begins nothing")
        publisher = graph.node(
            "commander",
            lambda node: node.create_publisher(DynamicEventDescription, BEGIN_COMMAND_TOPIC, latched(10)),
        )
        publisher.publish(
            DynamicEventDescription(fleet="tinyRobot", robot=ROBOT, description='{"category": "tour"}')
        )
        wait_for(lambda: watcher.state.phase == 1 and watcher.state.seq == 2, "run 2 begun on command")
        refused = send("--file", str(_write(Path(serve.tmp), '{"category": "fly", "description": {}}')))
        assert refused.returncode == 1
        assert "outcome: rejected" in refused.stdout
        assert "does not support this category" in refused.stdout
    finally:
        code = serve.stop()
    assert code == 0, serve.output


def _write(folder: Path, text: str) -> Path:
    path = folder / "goal.json"
    path.write_text(text, encoding="utf-8")
    return path


@pytest.mark.spec("R6.2", "R8.2")
def test_serve_runs_children_of_several_robots_at_once(graph: Graph) -> None:
    """Robots number their children alike (each run's ids start at its own id): one robot's child
    must never stop another's."""
    robots = ("twinA", "twinB", "twinC")
    serve = Child(["-m", "dynevent", "serve", "--rebegin", "0", *[f"--robot={robot}" for robot in robots]])
    serve.wait_line("serving ")
    try:
        sends = [
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "dynevent",
                    "send",
                    "--robot",
                    robot,
                    "--place",
                    "pantry",
                    "--timeout",
                    "30",
                ],
                stdout=subprocess.PIPE,
                stderr=subprocess.STDOUT,
                text=True,
                env=os.environ.copy(),
            )
            for robot in robots
        ]
        for send_process in sends:
            output, _ = send_process.communicate(timeout=60)
            assert send_process.returncode == 0, output
            assert "outcome: completed" in output
    finally:
        code = serve.stop()
    assert code == 0, serve.output
