"""A behaviour tree that drives one robot through a Dynamic Event: docs/bt.md draws it.

Run it beside ``dynevent serve --robot tinyRobot1`` (docs/serve.md), with ROS 2 sourced:
``python docs/examples/errand_tree.py tinyRobot1 pantry``.  The tree waits for the robot's run,
tries the attic and, when the robot refuses it, goes to the place given on the command line (put on
the blackboard), then to the lounge, and finishes the run.  It prints the tree with each
behaviour's status and message when it is done; exit status 0 when the tree succeeded.
"""

from __future__ import annotations

import sys
import time

import py_trees
from py_trees.common import Status

from dynevent.bt import FinishRun, Robot, RunEvent, WaitForRun, go_to_place


def errand(robot: Robot) -> py_trees.behaviour.Behaviour:
    """Wait for the run; the attic, or else the place on the blackboard's ``/place``; the lounge;
    FINISHED."""
    return py_trees.composites.Sequence(
        "errand",
        memory=True,
        children=[
            WaitForRun("run begun", robot, timeout=15.0, description_key="/estimate"),
            py_trees.composites.Selector(
                "somewhere to go",
                memory=True,
                children=[
                    RunEvent("to the attic", robot, "go_to_place", '{"one_of": ["attic"]}'),
                    RunEvent(
                        "to the place asked for",
                        robot,
                        "go_to_place",
                        go_to_place("/place"),
                        blackboard_keys=("/place",),
                    ),
                ],
            ),
            RunEvent("to the lounge", robot, "go_to_place", '{"one_of": ["lounge"]}'),
            FinishRun("done", robot),
        ],
    )


def run(tree: py_trees.trees.BehaviourTree, bound: float, period: float = 0.05) -> Status:
    """Tick ``tree`` every ``period`` seconds until its root succeeds or fails, at most ``bound``
    seconds (then the tree is stopped, which halts and so cancels what runs, and FAILURE)."""
    deadline = time.monotonic() + bound
    while time.monotonic() < deadline:
        tree.tick()
        if tree.root.status in (Status.SUCCESS, Status.FAILURE):
            return Status(tree.root.status)
        time.sleep(period)
    tree.interrupt()
    return Status.FAILURE


def main(robot_name: str, place: str) -> int:
    from dynevent.ros import RobotClient  # ROS 2 only here: the tree itself is drawn without it

    with RobotClient("tinyRobot", robot_name, node_name="errand_tree") as robot:
        robot.ready(15.0)
        py_trees.blackboard.Blackboard.set("/place", place)
        tree = py_trees.trees.BehaviourTree(errand(robot))
        status = run(tree, 120.0)
        print(py_trees.display.unicode_tree(tree.root, show_status=True))
        print(f"errand: {status.value}")
        return 0 if status is Status.SUCCESS else 1


if __name__ == "__main__":
    sys.exit(main(*(sys.argv[1:3] if len(sys.argv) >= 3 else ("tinyRobot1", "pantry"))))
