"""A simulated child as the adapter's handle sees it: in rmf_ros2 mode a go_to_place that has to move
draws an id for its plan at its first report (R17.8), as rmf_ros2's does; where the robot stands it
draws none, nor when it is stopped before that report, nor for a place it cannot reach, nor in
standard mode, nor for another category."""

from __future__ import annotations

from typing import Any

import pytest

from dynevent.sim.children import SimulatedChild, Whereabouts
from dynevent.sim.config import ServeConfig
from dynevent.wire.vocab import Compatibility, Status

RMF_ROS2 = ServeConfig(compatibility=Compatibility.RMF_ROS2)


class Handle:
    """The adapter's handle on a child, as far as a simulation reports through it."""

    def __init__(self) -> None:
        self.said: list[str] = []
        self.done = False
        self.stopping: str | None = None

    def underway(self, text: str | None = None) -> None:
        self.said.append("underway")

    def error(self, text: str | None = None) -> None:
        self.said.append("error")

    def finished(self, status: Status = Status.COMPLETED) -> None:
        self.said.append(f"finished {status}")
        self.done = True

    def draw_id(self) -> None:
        self.said.append("draw_id")


def _run(child: SimulatedChild, handle: Handle) -> list[str]:
    elapsed = 0.0
    while not child.report(handle, elapsed):
        elapsed += child.period
    return handle.said


@pytest.mark.spec("R17.8")
def test_a_go_to_place_that_moves_draws_its_plan_id_once_and_leaves_the_robot_there() -> None:
    robot = Whereabouts()
    said = _run(SimulatedChild("go_to_place", "pantry", RMF_ROS2, robot), Handle())
    assert said[0] == "draw_id" and said.count("draw_id") == 1 and said[-1] == "finished completed"
    assert robot.place == "pantry"
    again = _run(SimulatedChild("go_to_place", {"one_of": ["pantry"]}, RMF_ROS2, robot), Handle())
    assert "draw_id" not in again  # the robot stands there: no plan
    elsewhere = _run(SimulatedChild("go_to_place", "lounge", RMF_ROS2, robot), Handle())
    assert elsewhere.count("draw_id") == 1 and robot.place == "lounge"


@pytest.mark.parametrize(
    ("category", "description", "config", "stopped"),
    [
        ("go_to_place", "pantry", RMF_ROS2, True),  # stopped before its first report
        ("go_to_place", "nowhere", RMF_ROS2, False),  # a place it cannot reach: no plan found
        ("go_to_place", "pantry", ServeConfig(), False),  # standard mode: the NEXT names the child
        ("perform_action", {"category": "clean", "description": {}}, RMF_ROS2, False),
    ],
)
def test_no_plan_id_is_drawn_where_none_is_made(
    category: str, description: Any, config: ServeConfig, stopped: bool
) -> None:
    handle = Handle()
    handle.stopping = "canceled" if stopped else None
    robot = Whereabouts()
    assert "draw_id" not in _run(SimulatedChild(category, description, config, robot), handle)
    assert robot.place is None


@pytest.mark.spec("R17.8")
def test_the_place_is_the_one_the_robot_goes_to_and_unknown_once_it_stopped_on_its_way() -> None:
    robot = Whereabouts()
    robot.place = "pantry"
    # the simulation goes to the first place it can reach: pantry, where the robot stands
    said = _run(SimulatedChild("go_to_place", {"one_of": ["nowhere", "pantry"]}, RMF_ROS2, robot), Handle())
    assert "draw_id" not in said and robot.place == "pantry"
    moving, handle = SimulatedChild("go_to_place", "lounge", RMF_ROS2, robot), Handle()
    assert not moving.report(handle, 0.0)  # on its way: its plan's id drawn
    handle.stopping = "canceled"
    assert moving.report(handle, moving.period)
    assert handle.said[0] == "draw_id" and robot.place is None  # stopped somewhere between
    onward = _run(
        SimulatedChild("go_to_place", {"one_of": ["hall"], "followed_by": ["lobby"]}, RMF_ROS2, robot),
        Handle(),
    )
    assert onward.count("draw_id") == 1 and robot.place == "lobby"
