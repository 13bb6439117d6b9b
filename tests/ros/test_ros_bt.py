"""dynevent.bt's behaviours in py_trees trees, over DDS against ``dynevent serve`` in both modes: a
sequence through a whole run, a fallback on a place the robot refuses, and a halted branch whose
child is cancelled on the robot; and docs/bt.md's drawing is py_trees' own rendering of its tree."""

from __future__ import annotations

import json
import operator
import subprocess
import sys
import time
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status
from ros_support import Child, child_env, finish

from dynevent.bt import FinishRun, RunEvent
from dynevent.client import Outcome, OutcomeKind
from dynevent.ros import RobotClient

EXAMPLES = Path(__file__).resolve().parents[2] / "docs" / "examples"
sys.path.insert(0, str(EXAMPLES))
from errand_tree import errand, run  # noqa: E402  (docs/bt.md's tree, as the docs show it)


def _serve(tmp_path: Path, robot: str, mode: str, duration: float) -> Child:
    config = tmp_path / "fleet.json"
    categories = {"go_to_place": {"duration": duration, "report_every": 0.2}}
    config.write_text(json.dumps({"categories": categories, "places": ["pantry", "lounge", "hall"]}))
    serve = Child(["-m", "dynevent", "serve", "--robot", robot, "--config", str(config),
                   "--compatibility", mode, "--rebegin", "0.3"])  # fmt: skip
    serve.wait_line("serving ")
    return serve


def _named(root: py_trees.behaviour.Behaviour, name: str) -> py_trees.behaviour.Behaviour:
    (found,) = [node for node in root.iterate() if node.name == name]
    return found


@pytest.mark.spec("R4.10", "R6.4", "R11.1")
@pytest.mark.parametrize("mode", ["standard", "rmf_ros2"])
def test_a_sequence_with_a_fallback_runs_a_whole_run(tmp_path: Path, mode: str) -> None:
    serve = _serve(tmp_path, "btRobot", mode, duration=1.0)
    try:
        with RobotClient("tinyRobot", "btRobot", node_name="bt_client") as robot:
            robot.ready(15.0)
            py_trees.blackboard.Blackboard.set("/place", "pantry")
            tree = py_trees.trees.BehaviourTree(errand(robot))
            assert run(tree, 60.0) is Status.SUCCESS
            root = tree.root
            attic = _named(root, "to the attic")
            assert isinstance(attic.result, Outcome) and attic.result.kind is OutcomeKind.REJECTED, (
                attic.result
            )
            assert attic.feedback_message.startswith("rejected: refused by the server"), (
                attic.feedback_message
            )
            asked = _named(root, "to the place asked for")
            lounge = _named(root, "to the lounge")
            for done in (asked, lounge):
                assert done.result.kind is OutcomeKind.COMPLETED, done.result
            assert asked.run.progress and asked.run.progress[-1].id == asked.result.id  # the child it ran
            assert _named(root, "done").result.kind is OutcomeKind.COMPLETED
            estimate = py_trees.blackboard.Blackboard.get("/estimate")
            assert estimate == robot.state.description != ""  # the run's begin description
    finally:
        py_trees.blackboard.Blackboard.clear()
        serve.stop()
    assert "client judgement: 4 goal(s) judged, no finding(s)" in serve.output, serve.output


@pytest.mark.spec("R8.2", "R8.4")
@pytest.mark.parametrize("mode", ["standard", "rmf_ros2"])
def test_a_halted_branch_cancels_its_child_on_the_robot(tmp_path: Path, mode: str) -> None:
    serve = _serve(tmp_path, "haltRobot", mode, duration=6.0)
    try:
        with RobotClient("tinyRobot", "haltRobot", node_name="bt_halt") as robot:
            robot.ready(15.0)
            py_trees.blackboard.Blackboard.set("/stop", False)
            stop = py_trees.behaviours.CheckBlackboardVariableValue(
                "asked to stop",
                check=py_trees.common.ComparisonExpression("/stop", True, operator.eq),
            )
            long_walk = RunEvent("long walk", robot, "go_to_place", '{"one_of": ["hall"]}')
            root = py_trees.composites.Selector("unless stopped", memory=False, children=[stop, long_walk])
            tree = py_trees.trees.BehaviourTree(root)
            deadline = time.monotonic() + 20.0
            while not (long_walk.run is not None and long_walk.run.progress):  # the child runs
                assert time.monotonic() < deadline, long_walk.feedback_message
                tree.tick()
                time.sleep(0.05)
            child = long_walk.run.progress[-1].id
            py_trees.blackboard.Blackboard.set("/stop", True)
            tree.tick()  # the higher priority succeeds: the selector halts the walk
            assert root.status is Status.SUCCESS and long_walk.status is Status.INVALID
            # at once, the next errand: its NEXT waits for the withdrawn one to end (the client machine
            # would refuse it as busy), then runs
            walk_again = RunEvent("walk again", robot, "go_to_place", '{"one_of": ["pantry"]}')
            again = py_trees.composites.Sequence(
                "walk again, then finish", memory=True, children=[walk_again, FinishRun("done", robot)]
            )
            again_tree = py_trees.trees.BehaviourTree(again)
            still_open = not long_walk.run.done()
            again_tree.tick()
            if still_open:  # (the usual case: the CANCEL's answer takes a round trip)
                assert walk_again.feedback_message == "waiting for a withdrawn event to end"
            halted = long_walk.run.wait(10.0)  # well before the 6 s walk would have completed
            assert isinstance(halted, Outcome), halted
            assert (halted.kind, halted.id) == (OutcomeKind.CANCELED, child), halted
            assert run(again_tree, 30.0) is Status.SUCCESS, walk_again.feedback_message
    finally:
        py_trees.blackboard.Blackboard.clear()
        serve.stop()
    assert f"cancel: child {child}" in serve.output
    assert "client judgement: 4 goal(s) judged, no finding(s)" in serve.output, serve.output


def test_the_errand_example_runs_as_written(tmp_path: Path) -> None:
    serve = _serve(tmp_path, "tinyRobot1", "standard", duration=1.0)
    try:
        argv = [sys.executable, str(EXAMPLES / "errand_tree.py"), "tinyRobot1", "hall"]
        process = subprocess.Popen(
            argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env()
        )
        done = finish(process, 90)
    finally:
        serve.stop()
    assert done.returncode == 0, done.stdout + done.stderr
    assert "errand: SUCCESS" in done.stdout
    assert 'go_to_place {"one_of": ["hall"]}' in serve.output, serve.output  # the place it was given


# ------------------------------------------------------------------- the patterns py_trees users write


def _stopped() -> py_trees.behaviour.Behaviour:
    return py_trees.behaviours.CheckBlackboardVariableValue(
        "asked to stop", check=py_trees.common.ComparisonExpression("/stop", True, operator.eq)
    )


def _priority(walk: RunEvent, charger: RunEvent) -> py_trees.behaviour.Behaviour:
    """The pattern everyone writes first: a higher priority (stop, then charge) over a long walk."""
    return py_trees.composites.Selector("unless stopped", memory=False, children=[
        py_trees.composites.Sequence("charge when stopped", memory=True, children=[_stopped(), charger]),
        walk,
    ])  # fmt: skip


def _parallel(walk: RunEvent, charger: RunEvent) -> py_trees.behaviour.Behaviour:
    """A parallel whose policy halts the walk when the stop comes; then the charger."""
    until = py_trees.behaviours.WaitForBlackboardVariableValue(
        "until stopped", check=py_trees.common.ComparisonExpression("/stop", True, operator.eq)
    )
    race = py_trees.composites.Parallel(
        "walk until stopped", policy=py_trees.common.ParallelPolicy.SuccessOnOne(), children=[until, walk]
    )
    return py_trees.composites.Sequence("walk, then charge", memory=True, children=[race, charger])


def _guarded(walk: RunEvent, charger: RunEvent) -> py_trees.behaviour.Behaviour:
    """An eternal guard over the walk; the charger is the fallback."""
    guard = py_trees.decorators.EternalGuard(
        "while not stopped", child=walk, condition=lambda: not py_trees.blackboard.Blackboard.get("/stop")
    )
    return py_trees.composites.Selector("guarded", memory=False, children=[guard, charger])


def _timed(walk: RunEvent, charger: RunEvent) -> py_trees.behaviour.Behaviour:
    """A timeout over the walk (it takes 6 s, the timeout 2 s); the charger is the fallback."""
    timeout = py_trees.decorators.Timeout("at most 2 s", child=walk, duration=2.0)
    return py_trees.composites.Selector("in time", memory=True, children=[timeout, charger])


PATTERNS = {"priority": _priority, "parallel": _parallel, "eternal guard": _guarded, "timeout": _timed}


@pytest.mark.spec("R8.2", "R9.4", "R10.4")
@pytest.mark.parametrize("mode", ["standard", "rmf_ros2"])
@pytest.mark.parametrize("pattern", list(PATTERNS))
def test_a_pattern_that_halts_a_running_event_cancels_its_child_and_runs_the_next(
    tmp_path: Path, pattern: str, mode: str
) -> None:
    """A higher priority, a parallel's policy, a guard or a timeout halts a RunEvent whose child runs:
    the child is cancelled on the robot, and the RunEvent that takes over, started in the same tick
    (py_trees ticks it before it halts the other), waits for that child's end, then runs its own."""
    robot_name = f"bt{pattern.title().replace(' ', '')}{mode.title().replace('_', '')}"
    serve = _serve(tmp_path, robot_name, mode, duration=6.0)
    try:
        with RobotClient("tinyRobot", robot_name, node_name="bt_patterns") as robot:
            robot.ready(15.0)
            py_trees.blackboard.Blackboard.set("/stop", False)
            walk = RunEvent("long walk", robot, "go_to_place", '{"one_of": ["hall"]}')
            charger = RunEvent("to the charger", robot, "go_to_place", '{"one_of": ["pantry"]}')
            tree = py_trees.trees.BehaviourTree(PATTERNS[pattern](walk, charger))
            deadline = time.monotonic() + 20.0
            while not (walk.run is not None and walk.run.progress):  # the walk's child runs
                assert time.monotonic() < deadline, walk.feedback_message
                tree.tick()
                time.sleep(0.05)
            child = walk.run.progress[-1].id
            py_trees.blackboard.Blackboard.set("/stop", True)
            assert run(tree, 30.0) is Status.SUCCESS, (walk.feedback_message, charger.feedback_message)
            halted = walk.run.result
            assert isinstance(halted, Outcome) and (halted.kind, halted.id) == (OutcomeKind.CANCELED, child)
            assert isinstance(charger.result, Outcome) and charger.result.kind is OutcomeKind.COMPLETED
            assert charger.result.id != child
            assert robot.finish().wait(10.0).kind is OutcomeKind.COMPLETED  # the run is not left open
    finally:
        py_trees.blackboard.Blackboard.clear()
        serve.stop()
    assert f"cancel: child {child}" in serve.output, serve.output
    assert "client judgement: 4 goal(s) judged, no finding(s)" in serve.output, serve.output
