"""The clients that own their spinning, over DDS against ``dynevent serve``: RobotClient (blocking),
AsyncRobotClient (asyncio) and the example that drives two robots at once; and a client whose node
nothing spins says so at its first wait instead of timing out into a false refusal."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
import threading
from pathlib import Path

import pytest
import rclpy
from ros_support import Child, child_env, finish

from dynevent.client import Outcome, OutcomeKind, Progress
from dynevent.errors import LocalError, NotSpinning, RobotNotReady
from dynevent.ros import AsyncRobotClient, DynamicEventClient, RobotClient, RobotClients

EXAMPLE = Path(__file__).resolve().parents[2] / "docs" / "examples" / "two_robots.py"


def _serve(tmp_path: Path, *robots: str, mode: str = "standard") -> Child:
    config = tmp_path / "fleet.json"
    config.write_text(json.dumps({"categories": {"go_to_place": {"duration": 1.0, "report_every": 0.2}}}))
    names = [argument for robot in robots for argument in ("--robot", robot)]
    serve = Child(["-m", "dynevent", "serve", *names, "--config", str(config), "--compatibility", mode,
                   "--rebegin", "0.3"])  # fmt: skip
    serve.wait_line("serving ")
    return serve


@pytest.mark.spec("R6.4", "R8.2", "R11.1")
@pytest.mark.parametrize("mode", ["standard", "rmf_ros2"])
def test_a_robot_client_spins_itself_through_a_run(tmp_path: Path, mode: str) -> None:
    threads = set(threading.enumerate())
    serve = _serve(tmp_path, "ownRobot", mode=mode)
    try:
        with RobotClient("tinyRobot", "ownRobot", node_name="own_client") as robot:
            robot.ready(15.0)
            seen: list[Progress] = []
            outcome = robot.next("go_to_place", '"pantry"', on_progress=seen.append).wait(30.0)
            assert isinstance(outcome, Outcome) and outcome.kind is OutcomeKind.COMPLETED, outcome
            assert seen and all(progress.id == outcome.id for progress in seen)
            finished = robot.finish().wait(30.0)
            assert finished.kind is OutcomeKind.COMPLETED, finished
            refused = robot.cancel().wait(1.0)  # nothing runs: refused here, read as an outcome is
            assert refused.kind is OutcomeKind.REJECTED and refused.text.startswith("not sent:"), refused
    finally:
        serve.stop()
    assert {thread for thread in threading.enumerate() if thread.is_alive()} <= threads  # nothing left


def test_a_robot_client_that_finds_no_server_says_what_the_graph_has(tmp_path: Path) -> None:
    serve = _serve(tmp_path, "realRobot")
    try:
        with RobotClient("tinyRobot", "noSuchRobot") as robot, pytest.raises(RobotNotReady) as raised:
            robot.ready(3.0)
    finally:
        serve.stop()
    assert "no Dynamic Event server for tinyRobot/noSuchRobot within 3 s" in str(raised.value)
    assert "the graph has fleet tinyRobot: 1 robot(s) (realRobot)" in str(raised.value)


def test_a_client_whose_node_nothing_spins_says_so_at_once() -> None:
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        node = rclpy.create_node("unspun", context=context)
        client = DynamicEventClient(node, "tinyRobot", "anyRobot")
        with pytest.raises(NotSpinning, match="nothing spins node 'unspun'"):
            client.wait_for_status(10.0)
        client.destroy()
        node.destroy_node()
    finally:
        rclpy.try_shutdown(context=context)


@pytest.mark.spec("R6.4", "R11.1")
def test_an_async_client_drives_two_robots_at_once(tmp_path: Path) -> None:
    serve = _serve(tmp_path, "asyncA", "asyncB")

    async def drive(name: str, place: str) -> list[str]:
        async with AsyncRobotClient("tinyRobot", name, node_name=f"async_{name}") as robot:
            await robot.ready(15.0)
            loop_thread = threading.get_ident()
            threads: list[int] = []
            outcome = await robot.next(
                "go_to_place", json.dumps(place), on_progress=lambda _: threads.append(threading.get_ident())
            )
            finished = await robot.finish()
            assert set(threads) == {loop_thread}, "progress is handed to the loop's thread"
            return [outcome.kind.value, finished.kind.value]

    async def both() -> list[list[str]]:
        return list(
            await asyncio.wait_for(asyncio.gather(drive("asyncA", "pantry"), drive("asyncB", "lounge")), 60)
        )

    try:
        results = asyncio.run(both())
    finally:
        serve.stop()
    assert results == [["completed", "completed"], ["completed", "completed"]]


def test_the_two_robot_example_runs_as_written(tmp_path: Path) -> None:
    serve = _serve(tmp_path, "tinyRobot1", "tinyRobot2")
    try:
        process = subprocess.Popen([sys.executable, str(EXAMPLE), "pantry", "lounge"], stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True, env=child_env())  # fmt: skip
        done = finish(process, 90)
    finally:
        serve.stop()
    assert done.returncode == 0, done.stdout + done.stderr
    for robot in ("tinyRobot1", "tinyRobot2"):
        assert f"{robot}: finished: completed" in done.stdout, done.stdout


def _python_blocks(path: Path) -> list[str]:
    text = path.read_text(encoding="utf-8")
    return [block.split("```", 1)[0] for block in text.split("```python\n")[1:]]


def test_the_client_example_of_docs_ros_runs_as_written(tmp_path: Path) -> None:
    """The first client example of docs/ros.md, run as it is written against serve."""
    block = next(b for b in _python_blocks(Path(__file__).resolve().parents[2] / "docs" / "ros.md")
                 if "RobotClient(" in b and "async" not in b)  # fmt: skip
    script = tmp_path / "client_example.py"
    script.write_text(block, encoding="utf-8")
    serve = _serve(tmp_path, "tinyRobot1")
    try:
        done = finish(subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE,
                                       stderr=subprocess.PIPE, text=True, env=child_env()), 120)  # fmt: skip
    finally:
        serve.stop()
    assert done.returncode == 0, done.stdout + done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("completed "), done.stdout
    assert lines[1] == "completed", done.stdout


@pytest.mark.spec("R6.4", "R8.2")
@pytest.mark.parametrize("mode", ["standard", "rmf_ros2"])
def test_many_robots_clients_share_one_hub(tmp_path: Path, mode: str) -> None:
    """Three robots driven at once from one process, their AsyncRobotClients on one RobotClients hub:
    one context, one node, one spinning thread for all of them; each client closes alone, the hub
    after them, and nothing is left running."""
    threads = set(threading.enumerate())
    robots = ("hubRobotA", "hubRobotB", "hubRobotC")
    serve = _serve(tmp_path, *robots, mode=mode)

    async def drive(hub: RobotClients) -> list[object]:
        clients = [AsyncRobotClient("tinyRobot", robot, hub=hub) for robot in robots]
        for client in clients:
            await client.__aenter__()
        try:
            await asyncio.gather(*(client.ready(15.0) for client in clients))
            return list(await asyncio.gather(*(client.next("go_to_place", '"pantry"') for client in clients)))
        finally:
            for client in clients:
                await client.__aexit__(None, None, None)

    try:
        with RobotClients(node_name="hub_client") as hub:
            before = threading.active_count()
            outcomes = asyncio.run(drive(hub))
            assert threading.active_count() <= before + 1  # no thread a robot (asyncio's to_thread aside)
            # the clients made and destroyed under it did not end its spinning thread (an entity
            # destroyed while the executor builds its wait set does: "cannot use Destroyable")
            spinning = [thread for thread in threading.enumerate() if thread.name == "dynevent-clients"]
            assert len(spinning) == 1 and spinning[0].is_alive()
    finally:
        serve.stop()
    for outcome in outcomes:
        assert isinstance(outcome, Outcome) and outcome.kind is OutcomeKind.COMPLETED, outcome
    assert {thread for thread in threading.enumerate() if thread.is_alive()} <= threads
    with pytest.raises(LocalError, match="the hub is not open"):
        RobotClient("tinyRobot", robots[0], hub=RobotClients()).open()
