"""``dynevent task``: a robot's task told to a running ``dynevent serve`` from outside, over DDS: its
interruption (R14) a parameter of the serving shard's node, set once the server took it, so that the
NEXT sent after the command ends meets the task interrupted; a dynamic event begun on command (R3)."""

from __future__ import annotations

import subprocess
import sys
import time

import pytest
from ros_support import Child, child_env, finish

from dynevent.sim.config import shard_of

ROBOTS = [f"taskRobot{index}" for index in (0, 1, 4, 5)]  # two in each of two shards


def task(*args: str, timeout: float = 10.0) -> subprocess.CompletedProcess[str]:
    """``dynevent task``, run to its end (bounded)."""
    command = [sys.executable, "-m", "dynevent", "task", "--timeout", str(timeout), *args]
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env()
    )
    return finish(process, timeout + 30)


def _send(robot: str, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "dynevent", "send", "--robot", robot, "--timeout", "40", *args],
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=child_env(),
    )  # fmt: skip


def _serve(*args: str) -> Child:
    return Child(["-m", "dynevent", "serve", "--rebegin", "0", "--no-judge", *args])


@pytest.mark.spec("R14.2", "R6.3", "R14.3", "R14.5")
def test_a_task_interrupted_from_outside_defers_the_next_child_until_its_resume() -> None:
    """Two shards: the command finds the node of the robot's own; the NEXT sent once it ended is
    accepted and waits (feedback queued, no start in serve's log) until the resume starts it."""
    robot = next(robot for robot in ROBOTS if shard_of(robot, 2) == 2)
    shards = [_serve("--shard", f"{index}/2", *[f"--robot={name}" for name in ROBOTS]) for index in (1, 2)]
    try:
        for shard in shards:
            shard.wait_line("serving ")
        done = task("interrupt", "--robot", robot)
        assert done.returncode == 0, done.stdout + done.stderr
        assert done.stdout == f"tinyRobot/{robot}: the task interrupted (/dynevent_serve_tinyRobot_2_of_2)\n"
        shards[1].wait_line(f"{robot}  interrupted: the task", 10)
        sending = _send(robot, "--place", "pantry")
        shards[1].wait_line(f"{robot}  status: RUNNING seq=1 id=2 queued", 60)
        time.sleep(1.0)  # a child started at once would show in its first report's time
        assert not shards[1].saw(f"{robot}  start: child"), shards[1].output
        assert sending.poll() is None
        done = task("resume", "--robot", robot)
        assert done.returncode == 0, done.stdout + done.stderr
        output = finish(sending, 60).stdout
        assert sending.returncode == 0 and "outcome: completed" in output, output
        lines = output.splitlines()
        assert lines.index("[id 2] queued") < lines.index("[id 2] underway"), output
    finally:
        codes = [shard.stop() for shard in shards]
    assert codes == [0, 0], [shard.output for shard in shards]


@pytest.mark.spec("R3.1", "R14.2")
def test_a_robot_started_interrupted_begins_its_runs_so_and_a_run_begins_on_command() -> None:
    """``--ros-args -p interrupted.<robot>:=true``: the first run begins with the task interrupted; a
    robot no serve has, or a fleet no serve serves, is named with the serve nodes seen, within the
    bound; ``task begin`` begins a run after the last ended."""
    robot = ROBOTS[0]
    serve = _serve("--robot", robot, "--ros-args", "-p", f"interrupted.{robot}:=true")
    try:
        serve.wait_line("serving ")
        sending = _send(robot, "--place", "pantry")
        serve.wait_line(f"{robot}  status: RUNNING seq=1 id=2 queued", 60)
        assert task("resume", "--robot", robot).returncode == 0
        assert finish(sending, 60).returncode == 0
        for args, named in (
            (["--robot", "nobody"], "tinyRobot/nobody"),
            (["--fleet", "other", "--robot", robot], f"other/{robot}"),
        ):
            started = time.monotonic()
            done = task("interrupt", *args, timeout=3)
            assert done.returncode == 2, done.stdout + done.stderr
            seen = "(serve nodes seen: /dynevent_serve_tinyRobot)"
            assert done.stdout == f"no dynevent serve of {named} within 3 s {seen}\n"
            assert time.monotonic() - started < 3 + 20  # the bound, and a process's start and close
        ended = _send(robot, "--end")
        assert finish(ended, 60).returncode == 0
        serve.wait_line(f"{robot}  status: INACTIVE seq=1", 30)
        done = task("begin", "--robot", robot, "--description", '{"category": "tour"}')
        assert done.returncode == 0, done.stdout + done.stderr
        serve.wait_line(f"{robot}  begin: run 2", 30)
    finally:
        code = serve.stop()
    assert code == 0, serve.output
