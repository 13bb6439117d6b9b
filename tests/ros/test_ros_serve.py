"""``dynevent serve`` and ``dynevent send`` as separate processes over DDS, with kill -9 and a restart."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from ros_support import START, Child, Graph, child_env, finish, wait_for

from dynevent import client as cl
from dynevent.errors import ServeError
from dynevent.ros import DynamicEventClient
from dynevent.tools.live import serve as serve_body
from dynevent.tools.live.serve import CALLBACK_FAULT
from dynevent.wire.vocab import Failure, GoalStatus

ROBOT = "serveRobot"


#: Every flow of ``send`` runs against both of serve's modes: the spec's and rmf_ros2's (R17, R20.2).
MODES = ("standard", "rmf_ros2")


class Serve(Child):
    """A ``dynevent serve`` process and its live log."""

    def __init__(self, *args: str, mode: str = "standard") -> None:
        command = ["-m", "dynevent", "serve", "--robot", ROBOT, "--rebegin", "0", "--compatibility", mode]
        super().__init__([*command, *args])

    def ready(self) -> Serve:
        """Wait (bounded) for the line serve prints once its robots are on the graph."""
        self.wait_line("serving ")
        return self


def send(*args: str, timeout: float = 20.0, robot: str = ROBOT) -> subprocess.CompletedProcess[str]:
    """``dynevent send`` to ``robot``, run to its end (bounded)."""
    return finish(_start_send(args, timeout, robot, stderr=subprocess.PIPE), timeout + 15)


def send_in_background(*args: str, timeout: float = 30.0, robot: str = ROBOT) -> subprocess.Popen[str]:
    """``dynevent send`` to ``robot``, started, its errors in its output; end it with ``finish``."""
    return _start_send(args, timeout, robot, stderr=subprocess.STDOUT)


def _start_send(args: tuple[str, ...], timeout: float, robot: str, stderr: int) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [sys.executable, "-m", "dynevent", "send", "--robot", robot, "--timeout", str(timeout), *args],
        stdout=subprocess.PIPE,
        stderr=stderr,
        text=True,
        env=child_env(),
    )


@pytest.fixture(params=MODES)
def mode(request: pytest.FixtureRequest) -> str:
    return str(request.param)


def waiting_after(watcher: DynamicEventClient, last_id: int) -> bool:
    """The watcher sees the robot waiting with ``last_id`` the highest id used: a WAITING status, or
    (rmf_ros2 mode) a RUNNING one that carries the child's final status (R20.2)."""
    state = watcher.state
    if state.current_id != last_id:
        return False
    return state.phase == 1 or (state.phase == 2 and state.ended_id == last_id)


@pytest.fixture
def watcher(graph: Graph) -> Iterator[DynamicEventClient]:
    client: DynamicEventClient = graph.node(
        "watcher", lambda node: DynamicEventClient(node, "tinyRobot", ROBOT)
    )
    yield client


@pytest.mark.spec("R21.1", "R21.2", "R21.3", "R20.1")
def test_serve_and_send_survive_kill_9_in_the_middle_of_a_child(
    tmp_path: Path, watcher: Any, mode: str
) -> None:
    config = tmp_path / "fleet.json"
    config.write_text(
        json.dumps(
            {"categories": {"go_to_place": {"duration": 1.0, "report_every": 0.25}, "slow": {"duration": 60}}}
        ),
        encoding="utf-8",
    )
    state = tmp_path / "state.db"
    planned = _plan_ids(mode)
    serve = Serve("--config", str(config), "--state", str(state), mode=mode).ready()
    try:
        done = send("--place", "pantry")
        assert done.returncode == 0, done.stdout + done.stderr
        assert "outcome: completed" in done.stdout and "[id 2]" in done.stdout
        wait_for(lambda: waiting_after(watcher, 2), "waiting, id 2")
        (tmp_path / "slow.json").write_text('{"category": "slow", "description": {}}', encoding="utf-8")
        slow = send_in_background("--file", str(tmp_path / "slow.json"), timeout=40)
        child = 3 + planned  # after the pantry child's plan id, in rmf_ros2 mode (R17.8)
        wait_for(
            lambda: watcher.state.phase == 2 and watcher.state.current_id == child, f"child {child} running"
        )
        serve.process.send_signal(signal.SIGKILL)
        assert serve.stop() == -signal.SIGKILL
        serve = Serve("--config", str(config), "--state", str(state), mode=mode).ready()
        output = finish(slow, 30).stdout  # R21.4: it asks again and gets the restart's answer
        assert slow.returncode == 1 and "server restarted" in output, output
        wait_for(lambda: serve.saw(f"restored: run 1, last id {child}"), "the restore")
        wait_for(lambda: watcher.state.phase == 1 and watcher.state.current_id == child, "WAITING again")
        assert watcher.state.seq == 1  # the same run goes on
        done = send("--place", "lobby")
        assert done.returncode == 0, done.stdout + done.stderr
        assert f"[id {child + 1}]" in done.stdout  # ids continue
        ended = send("--end")
        assert ended.returncode == 0, ended.stdout
    finally:
        code = serve.stop()
    assert code == 0, serve.output


def _plan_ids(mode: str) -> int:
    """The ids a go_to_place child that moves draws for its plan: one in rmf_ros2 mode, as rmf_ros2's
    does (R17.8, D10), none in standard mode."""
    return 1 if mode == "rmf_ros2" else 0


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
def test_send_explains_and_exits_by_the_outcome(watcher: Any, mode: str) -> None:
    serve = Serve(mode=mode).ready()
    try:
        wait_for(lambda: watcher.state.phase == 1, "WAITING")
        idle = send("--cancel")
        assert idle.returncode == 1
        assert "cancel_idle" in idle.stdout
        usage = send("--cancel", "--end")
        assert usage.returncode == 2 and "exactly one of" in usage.stderr
        missing = send("--end", timeout=2, robot="nobody")
        assert missing.returncode == 2 and "no Dynamic Event server" in missing.stdout
        assert "Traceback" not in missing.stderr
    finally:
        code = serve.stop()
    assert code == 0, serve.output


@pytest.mark.spec("R3.1", "R4.7")
def test_serve_begins_on_command_and_send_explains_a_refusal_it_cannot_see(
    graph: Graph, watcher: Any, mode: str, tmp_path: Path
) -> None:
    from rmf_task_msgs.msg import DynamicEventDescription

    from dynevent.ros.fleet import BEGIN_COMMAND_TOPIC
    from dynevent.ros.server import latched

    serve = Serve(mode=mode).ready()
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
        refused = send("--file", str(_write(tmp_path, '{"category": "fly", "description": {}}')))
        assert refused.returncode == 1
        assert "outcome: rejected" in refused.stdout
        assert "does not support this category" in refused.stdout
    finally:
        code = serve.stop()
    assert code == 0, serve.output


def _write(folder: Path, text: str, name: str = "goal.json") -> Path:
    path = folder / name
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
        sends = [send_in_background("--place", "pantry", timeout=30, robot=robot) for robot in robots]
        for send_process in sends:
            output = finish(send_process, 60).stdout
            assert send_process.returncode == 0, output
            assert "outcome: completed" in output
    finally:
        code = serve.stop()
    assert code == 0, serve.output


def test_a_robot_whose_callback_raises_leaves_its_lane_mates_served() -> None:
    """An exception in one robot's callback (tests/ros/broken_serve.py's ``faulty_callback``: where its
    child starts) is one line of the live log, no traceback; the executor thread of its lane spins
    on, and a robot of the same lane runs a child after it."""
    script = str(Path(__file__).resolve().parent / "broken_serve.py")
    serve = Child([script, "faulty_callback", "--rebegin", "0", "--robot", "faulty", "--robot", "sound"])
    serve.wait_line("serving ")
    # its child never starts: its send would wait out its bound (long enough to find the robot under
    # load, where discovery alone once took more than 3 s), and is ended once the test is done with it
    faulty = send_in_background("--place", "pantry", timeout=60, robot="faulty")
    try:
        serve.wait_line(CALLBACK_FAULT)
        sound = send_in_background("--place", "pantry", timeout=30, robot="sound")
        output = finish(sound, 60).stdout
        assert sound.returncode == 0 and "outcome: completed" in output, output + serve.output
    finally:
        faulty.kill()  # no CANCEL of the goal whose child never started
        finish(faulty, 10)
        code = serve.stop()
    assert code == 0, serve.output
    said = [line for line in serve.output.splitlines() if CALLBACK_FAULT in line]
    assert said == [
        f"dynevent_serve_tinyRobot: {CALLBACK_FAULT} RuntimeError: a deliberate fault at broken_serve.py:"
        f"{said[0].split('broken_serve.py:')[1].split(';')[0]}; its robots are served on (a defect: please "
        "report it)"
    ], serve.output
    assert "Traceback" not in serve.output


def test_a_fault_of_every_pass_is_said_the_1st_10th_and_100th_time() -> None:
    """A fault that comes back on every pass of a lane (its wait set's) does not flood the live log:
    the same lane, type and place is said once, then with its count at each power of ten."""
    said: list[str] = []
    fault_said = serve_body._fault_said(said.append)
    for _ in range(150):
        try:
            raise ValueError("again")
        except ValueError as fault:
            fault_said("lane_1", fault)
    fault_said("lane_2", ValueError("elsewhere"))  # no traceback: no place
    counts = [line.split("(")[1].split(" ")[0] if " times)" in line else "1" for line in said]
    assert counts == ["1", "10", "100", "1"], said
    assert (
        said[-1] == f"lane_2: {CALLBACK_FAULT} ValueError: elsewhere; its robots are served on (a defect: "
        "please report it)"
    )


def test_serves_banner_names_the_namespace_every_name_is_under() -> None:
    """``--ros-args -r __ns:=/site1`` puts the robot's action and topics under /site1: the banner says
    so (a client looking for ``rmf/dynamic_event/...`` at the root would never find them)."""
    serve = Child(["-m", "dynevent", "serve", "--rebegin", "0", "--robot", "nsRobot",
                   "--ros-args", "-r", "__ns:=/site1"])  # fmt: skip
    try:
        serve.wait_line("serving ")
    finally:
        serve.stop()
    banner = next(line for line in serve.output.splitlines() if line.startswith("serving "))
    assert banner.startswith("serving 1 robot(s) of fleet tinyRobot in namespace /site1, "), banner


@pytest.mark.spec("R20.1", "R20.2", "R17.4", "R9.3", "R11.1", "R4.3")
def test_send_drives_every_flow_of_a_run_in_both_modes(tmp_path: Path, watcher: Any, mode: str) -> None:
    """Each goal from a fresh ``send`` process, which knows only the status topic: places one after
    another (rmf_ros2's status says RUNNING with the child's final status after each), a failing place,
    a perform_action from a file, a CANCEL of a running child from another process, FINISHED, and a
    goal after the end."""
    config = tmp_path / "fleet.json"
    config.write_text(
        json.dumps(
            {
                "categories": {
                    "go_to_place": {"duration": 0.3, "report_every": 0.1, "fail_on": ["nowhere"]},
                    "perform_action": {"duration": 0.3, "report_every": 0.1},
                    "slow": {"duration": 60, "report_every": 0.2},
                }
            }
        ),
        encoding="utf-8",
    )
    serve = Serve("--config", str(config), mode=mode).ready()
    planned = _plan_ids(mode)  # each go_to_place that moves draws an id for its plan (R17.8)
    try:
        for place, child in (("pantry", 2), ("lobby", 3 + planned)):
            done = send("--place", place)
            assert done.returncode == 0, done.stdout + done.stderr
            assert "outcome: completed" in done.stdout and f"[id {child}]" in done.stdout
            wait_for(lambda last=child: waiting_after(watcher, last), f"waiting, id {child}")
        failed = send("--place", "nowhere")  # no plan: no id drawn
        assert failed.returncode == 1 and "outcome: failed" in failed.stdout, failed.stdout
        wait_for(lambda: waiting_after(watcher, 4 + 2 * planned), "waiting after the failed child")
        action = _write(
            tmp_path,
            '{"category": "perform_action", "description": {"category": "clean", "description": {}}}',
        )
        done = send("--file", str(action))
        assert done.returncode == 0 and "outcome: completed" in done.stdout, done.stdout
        slow = send_in_background(
            "--file",
            str(_write(tmp_path, '{"category": "slow", "description": {}}', "slow.json")),
            timeout=30,
        )
        slow_child = 6 + 2 * planned
        wait_for(
            lambda: watcher.state.phase == 2 and watcher.state.current_id == slow_child, "the slow child"
        )
        cancel = send("--cancel")
        assert cancel.returncode == 0, cancel.stdout + cancel.stderr
        output = finish(slow, 30).stdout
        assert slow.returncode == 1 and "outcome: canceled" in output, output
        wait_for(lambda: waiting_after(watcher, slow_child), "waiting after the cancel")
        ended = send("--end")
        assert ended.returncode == 0, ended.stdout + ended.stderr
        wait_for(lambda: watcher.state.phase == 0, "INACTIVE")
        after = send("--place", "pantry")
        assert after.returncode == 1 and "inactive" in after.stdout, after.stdout
    finally:
        code = serve.stop()
    assert code == 0, serve.output


@pytest.mark.spec("R21.1", "R21.4")
@pytest.mark.parametrize("point", ["requested", "started", "running", "answered"])
def test_a_crash_at_any_point_of_a_goals_life_loses_no_answer(
    tmp_path: Path, watcher: Any, mode: str, point: str
) -> None:
    """kill -9 of serve with a goal requested (the server frozen before it saw it), started (its child
    started in the store, nothing sent), running, or answered (the answer kept, not sent): after the
    restart the client that sent the goal gets its answer, within its bound, without sending again."""
    config = tmp_path / "fleet.json"
    config.write_text(
        json.dumps({"categories": {"go_to_place": {"duration": 0.5 if point == "answered" else 60}}}),
        encoding="utf-8",
    )
    state = tmp_path / "state.db"
    args = ["--robot", ROBOT, "--rebegin", "0", "--compatibility", mode, "--config", str(config)]
    if point in ("started", "answered"):
        here = Path(__file__).parent
        serve: Child = Child([str(here / "crashing_serve.py"), point, *args, "--state", str(state)])
    else:
        serve = Serve("--config", str(config), "--state", str(state), mode=mode)
    serve.wait_line("serving ")
    try:
        wait_for(lambda: watcher.state.phase == 1, "WAITING")
        if point == "requested":
            serve.process.send_signal(signal.SIGSTOP)  # the request reaches no one
        run = watcher.next("go_to_place", json.dumps({"one_of": ["pantry"]}))
        if point == "running":
            wait_for(lambda: watcher.state.phase == 2, "the child running")
        if point in ("requested", "running"):
            serve.process.send_signal(signal.SIGKILL)
        assert serve.process.wait(timeout=START) == -signal.SIGKILL, serve.output
        serve.stop()
        serve = Serve("--config", str(config), "--state", str(state), mode=mode).ready()
        outcome = run.wait(20.0)
        assert isinstance(outcome, cl.Outcome), outcome
        if point == "requested":  # the restarted server never knew the goal
            assert outcome.execution_failure == Failure.LOST.value, outcome
        elif point == "answered":  # the answer it had given, kept in the store
            assert (outcome.kind, outcome.goal_status) == (cl.OutcomeKind.COMPLETED, GoalStatus.SUCCEEDED)
        else:
            assert outcome.execution_failure == Failure.RESTART.value, outcome
            assert outcome.goal_status is GoalStatus.ABORTED
    finally:
        serve.process.send_signal(signal.SIGCONT)
        code = serve.stop()
    assert code == 0, serve.output


@pytest.mark.spec("R21.4")
def test_a_restart_the_client_takes_as_one_matched_event_still_asks_the_new_process(tmp_path: Path) -> None:
    """The client's executor takes no event while serve, frozen before it saw the client's goal, is
    killed and a new serve is matched in its place: the one matched event it then takes sums both
    (the current count unchanged, the total one up), and the client still asks the new process for
    the goal, which does not know it: the goal ends lost (R21.4).  Found in CI under load, where the
    goal waited for good."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from dynevent.ros.spinning import close_down
    from dynevent.wire.names import status_topic

    config = tmp_path / "fleet.json"
    config.write_text(json.dumps({"categories": {"go_to_place": {"duration": 60}}}), encoding="utf-8")
    state = tmp_path / "state.db"
    serve = Serve("--config", str(config), "--state", str(state)).ready()
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("paused", context=context)
    client = DynamicEventClient(node, "tinyRobot", ROBOT)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    topic = "/" + status_topic("tinyRobot", ROBOT)

    def spin_until(condition: Any, what: str, timeout: float) -> None:
        deadline = time.monotonic() + timeout
        while not condition():
            if time.monotonic() > deadline:
                raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
            executor.spin_once(timeout_sec=0.05)

    def publishers() -> set[bytes]:  # the client's own graph, which its participant keeps unspun
        return {bytes(info.endpoint_gid) for info in node.get_publishers_info_by_topic(topic)}

    try:
        spin_until(lambda: client.state.phase == 1, "WAITING", START)
        old = publishers()
        serve.process.send_signal(signal.SIGSTOP)  # the request reaches no one
        run = client.next("go_to_place", json.dumps({"one_of": ["pantry"]}))
        end = time.monotonic() + 1.0
        spin_until(lambda: time.monotonic() > end, "the goal sent", 5.0)
        serve.process.send_signal(signal.SIGKILL)
        assert serve.process.wait(timeout=START) == -signal.SIGKILL, serve.output
        serve.stop()
        serve = Serve("--config", str(config), "--state", str(state)).ready()
        # unspun until the client's participant has matched the new status publisher and let the old go
        wait_for(lambda: bool(publishers()) and not publishers() & old, "the old process gone", START)
        spin_until(run.done, "the goal's end", 20.0)
        outcome = run.wait(0)
        assert isinstance(outcome, cl.Outcome), outcome
        assert outcome.execution_failure == Failure.LOST.value, outcome
    finally:
        serve.process.send_signal(signal.SIGCONT)
        code = serve.stop()
        client.destroy()
        executor.shutdown(timeout_sec=5)
        close_down([node], context)
    assert code == 0, serve.output


def test_a_sharded_fleet_is_served_by_its_processes_as_by_one(tmp_path: Path) -> None:
    """``--shard K/N``: each process serves the robots whose names hash to its part, every robot is
    served exactly once, and a client drives each robot as it would one process's."""
    from dynevent.sim.config import parse_shard, shard_of

    robots = [f"shardRobot{index}" for index in range(6)]
    parts = {robot: shard_of(robot, 2) for robot in robots}
    assert set(parts.values()) == {1, 2}  # these names fall in both parts
    shards = [
        Child(
            [
                "-m",
                "dynevent",
                "serve",
                "--rebegin",
                "0",
                "--shard",
                f"{index}/2",
                "--state",
                str(tmp_path / f"shard{index}.db"),
                *[f"--robot={robot}" for robot in robots],
            ]
        )
        for index in (1, 2)
    ]
    try:
        for index, shard in enumerate(shards, start=1):
            shard.wait_line("serving ")
            line = next(line for line in shard.lines if line.startswith("serving "))
            mine = [robot for robot in robots if parts[robot] == index]
            assert f"serving {len(mine)} robot(s) of fleet tinyRobot (shard {index}/2 of 6)" in line
            assert all(robot in line for robot in mine)
            assert not any(robot in line for robot in robots if robot not in mine)
        sends = [send_in_background("--place", "pantry", timeout=30, robot=robot) for robot in robots]
        for send_process in sends:
            output = finish(send_process, 60).stdout
            assert send_process.returncode == 0 and "outcome: completed" in output, output
    finally:
        codes = [shard.stop() for shard in shards]
    assert codes == [0, 0], [shard.output for shard in shards]
    assert parse_shard("2/3") == (2, 3)
    for bad in ("0/2", "3/2", "1", "a/b", "1/0", "-1/2"):
        with pytest.raises(ServeError, match="expected K/N"):
            parse_shard(bad)


@pytest.mark.spec("R3.1")
def test_a_fleet_larger_than_a_lane_is_served_by_every_lane(tmp_path: Path, graph: Graph) -> None:
    """serve spreads its robots over lanes (a node and an executor thread each, LANE robots a lane):
    a robot of the first lane and one of the last are both served, begins on command included."""
    from rmf_task_msgs.msg import DynamicEventDescription

    from dynevent.ros.fleet import BEGIN_COMMAND_TOPIC, LANE
    from dynevent.ros.server import latched

    robots = [f"laneRobot{index:03d}" for index in range(LANE + 2)]
    config = tmp_path / "fleet.json"
    config.write_text(
        json.dumps({"robots": robots, "rebegin": 0, "categories": {"go_to_place": {"duration": 0.2}}}),
        encoding="utf-8",
    )
    serve = Child(["-m", "dynevent", "serve", "--config", str(config)])
    serve.wait_line("serving ")
    try:
        first, last = robots[0], robots[-1]
        for robot in (first, last):
            done = send("--end", robot=robot)
            assert done.returncode == 0, done.stdout + done.stderr
        watcher: DynamicEventClient = graph.node(
            "lane_watcher", lambda node: DynamicEventClient(node, "tinyRobot", last)
        )
        wait_for(lambda: watcher.state.phase == 0, "the last lane's robot INACTIVE")
        publisher = graph.node(
            "lane_commander",
            lambda node: node.create_publisher(DynamicEventDescription, BEGIN_COMMAND_TOPIC, latched(10)),
        )
        publisher.publish(DynamicEventDescription(fleet="tinyRobot", robot=last, description="{}"))
        wait_for(lambda: watcher.state.phase == 1 and watcher.state.seq == 2, "run 2 begun on command")
        done = send("--place", "dock", robot=last)
        assert done.returncode == 0 and "outcome: completed" in done.stdout, done.stdout + done.stderr
    finally:
        code = serve.stop()
    assert code == 0, serve.output
