"""dynevent.bt without ROS: docs/bt.md's drawing is py_trees' own rendering of the example's tree
(and of the tree the page shows in code), descriptions from the blackboard, and bad input refused
at the edge.  The behaviours driving a robot are tested over DDS in tests/ros/test_ros_bt.py."""

from __future__ import annotations

import json
import operator
import re
import sys
from pathlib import Path

import py_trees
import pytest
from py_trees.common import Status

from dynevent import bt
from dynevent.client import Outcome, OutcomeKind
from dynevent.errors import InvalidValue
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "bt.md").read_text(encoding="utf-8")
sys.path.insert(0, str(ROOT / "docs" / "examples"))
import errand_tree  # noqa: E402


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", DOC, flags=re.DOTALL)


def test_the_page_draws_the_examples_tree_as_py_trees_does() -> None:
    drawing = py_trees.display.ascii_tree(errand_tree.errand(None))  # type: ignore[arg-type]
    assert _blocks("text")[1] == drawing


def _priority(robot: object) -> py_trees.behaviour.Behaviour:
    """The page's priority pattern (tests/ros/test_ros_bt.py runs it against serve)."""
    stop = py_trees.behaviours.CheckBlackboardVariableValue(
        "asked to stop", check=py_trees.common.ComparisonExpression("/stop", True, operator.eq)
    )
    walk = bt.RunEvent("long walk", robot, "go_to_place", '"hall"')  # type: ignore[arg-type]
    charger = bt.RunEvent("to the charger", robot, "go_to_place", '"pantry"')  # type: ignore[arg-type]
    return py_trees.composites.Selector("unless stopped", memory=False, children=[
        py_trees.composites.Sequence("charge when stopped", memory=True, children=[stop, charger]), walk,
    ])  # fmt: skip


def test_the_page_draws_the_priority_pattern_as_py_trees_does() -> None:
    assert _blocks("text")[0] == py_trees.display.ascii_tree(_priority(None))


def test_the_tree_the_page_shows_in_code_is_the_examples() -> None:
    (code,) = _blocks("python")
    names = {"py_trees": py_trees, "Robot": bt.Robot, **{name: getattr(bt, name) for name in bt.__all__}}
    exec(compile(code, "docs/bt.md", "exec"), names)
    shown = py_trees.display.ascii_tree(names["errand"](None))
    assert shown == py_trees.display.ascii_tree(errand_tree.errand(None))  # type: ignore[arg-type]


class _Board:
    def __init__(self, **values: object) -> None:
        self.values = values

    def get(self, key: str) -> object:
        return self.values[key]


def test_go_to_place_builds_a_description_from_the_blackboard() -> None:
    assert json.loads(bt.go_to_place("/place")(_Board(**{"/place": "pantry"}))) == {"one_of": ["pantry"]}
    both = bt.go_to_place("/places")(_Board(**{"/places": ["pantry", 3]}))
    assert json.loads(both) == {"one_of": ["pantry", 3]}


def test_a_description_that_is_neither_text_nor_a_builder_is_refused_by_name() -> None:
    with pytest.raises(InvalidValue, match="description"):
        bt.RunEvent("walk", None, "go_to_place", {"one_of": ["pantry"]})  # type: ignore[arg-type]


# --------------------------------------------------------------------------- who holds the robot


def _named(root: py_trees.behaviour.Behaviour, name: str) -> bt.RunEvent:
    (found,) = [node for node in root.iterate() if node.name == name]
    assert isinstance(found, bt.RunEvent)
    return found


class _Run:
    """A goal's run as a behaviour reads it (dynevent.ros.GoalRun's face)."""

    def __init__(self, uuid: str) -> None:
        self.goal_uuid, self.progress, self.result = uuid, [], None
        self.withdrawn = False

    def done(self) -> bool:
        return self.result is not None


class _Robot:
    """A robot client whose goals end when the test says (the client machine's face: state.goals)."""

    def __init__(self) -> None:
        self.runs: list[_Run] = []

    @property
    def state(self) -> object:
        return type("State", (), {"goals": [run for run in self.runs if not run.done()]})()

    def next(self, category: str, description: str, **_: object) -> _Run:
        run = _Run(f"{len(self.runs) + 1:032x}")
        self.runs.append(run)
        return run

    def withdraw(self, run: _Run) -> None:
        run.withdrawn = True

    def end(self, run: _Run, kind: OutcomeKind) -> None:
        goal = Goal(dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", id=1)
        run.result = Outcome(goal_uuid=run.goal_uuid, goal=goal, kind=kind, id=1, status=kind.value, text="")


def test_a_priority_waits_for_the_halted_branch_to_end_then_runs() -> None:
    robot = _Robot()
    py_trees.blackboard.Blackboard.set("/stop", False)
    try:
        root = _priority(robot)
        walk, charger = _named(root, "long walk"), _named(root, "to the charger")
        tree = py_trees.trees.BehaviourTree(root)
        tree.tick()
        assert walk.status is Status.RUNNING and len(robot.runs) == 1
        py_trees.blackboard.Blackboard.set("/stop", True)
        tree.tick()  # the charger starts first and waits; the selector then halts the walk
        assert charger.status is Status.RUNNING and walk.status is Status.INVALID
        assert charger.feedback_message == "waiting for 'long walk', which holds the robot, to be halted"
        assert robot.runs[0].withdrawn and len(robot.runs) == 1
        tree.tick()
        assert charger.feedback_message == "waiting for a withdrawn event to end" and len(robot.runs) == 1
        robot.end(robot.runs[0], OutcomeKind.CANCELED)
        tree.tick()
        assert len(robot.runs) == 2 and charger.run is robot.runs[1]  # sent once the walk's child ended
        robot.end(robot.runs[1], OutcomeKind.COMPLETED)
        tree.tick()
        assert root.status is Status.SUCCESS
    finally:
        py_trees.blackboard.Blackboard.clear()


def test_a_second_event_beside_a_running_one_fails_naming_the_holder() -> None:
    robot = _Robot()
    first = bt.RunEvent("first", robot, "go_to_place", '"hall"')  # type: ignore[arg-type]
    second = bt.RunEvent("second", robot, "go_to_place", '"pantry"')  # type: ignore[arg-type]
    both = py_trees.composites.Parallel(
        "both at once", policy=py_trees.common.ParallelPolicy.SuccessOnAll(), children=[first, second]
    )
    tree = py_trees.trees.BehaviourTree(both)
    tree.tick()
    assert second.status is Status.RUNNING  # one tick: a priority above might halt the holder
    tree.tick()
    assert second.status is Status.FAILURE and len(robot.runs) == 1
    assert second.feedback_message == "the robot is held by 'first', which runs on: it was not halted"
