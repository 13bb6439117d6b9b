"""The machine's tables and the shortcuts for speed derived from them (#54 item 1).

The request checks' rules are written once, in ``REQUEST_CHECKS``; the walks ``accept`` runs are
compiled from it.  These tests hold the compiled walks to the table walked one check at a time.
"""

from __future__ import annotations

import ast
import itertools
import re
import typing
from pathlib import Path
from typing import Any

import attrs
import pytest

from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import RunningGoal, ServerConfig, State, any_description
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType

STANDARD = ServerConfig(categories={"go_to_place": any_description})
RMF_ROS2 = ServerConfig.rmf_ros2(categories={"go_to_place": any_description})


def _states() -> list[State]:
    fresh = State.new("f", "r")
    waiting = attrs.evolve(fresh, seq=3, active=True, description="{}", status="standby", last_id=7)
    child = Goal(dynamic_event_seq=3, event_type=EventType.NEXT, category="go_to_place", id=8)
    running = attrs.evolve(
        waiting,
        last_id=8,
        status="underway",
        running=RunningGoal(
            goal_uuid="a" * 32, goal=child, child_id=8, child_status="underway", started=True
        ),
    )
    states = [fresh, waiting, running]
    return states + [attrs.evolve(state, shutdown=True) for state in states]


def _goals() -> list[Goal]:
    goals = []
    for event_type, seq, goal_id, description in itertools.product(
        (0, 1, 2, 3, 9), (2, 3), (0, 7, 8, 9), ('"pantry"', "{", "")
    ):
        for category in ("go_to_place", "clean"):
            goals.append(
                Goal(
                    dynamic_event_seq=seq,
                    event_type=event_type,
                    category=category,
                    description=description,
                    id=goal_id,
                )
            )
    return goals


def _walked_one_by_one(state: State, goal: Goal, config: ServerConfig) -> tuple[Any, Any]:
    kind = min(goal.event_type, 4)
    found: list[Any] = [None]
    for check in machine._walk(config.compatibility.value == "standard", kind):
        problem = check.check(state, goal, config, found)
        if problem is not None:
            return problem, None
    return None, found[0]


@pytest.mark.parametrize("config", [STANDARD, RMF_ROS2], ids=["standard", "rmf_ros2"])
def test_the_compiled_walks_refuse_as_the_table_walked_one_check_at_a_time(config: ServerConfig) -> None:
    walks = machine._STANDARD_WALKS if config is STANDARD else machine._RMF_ROS2_WALKS
    for state, goal in itertools.product(_states(), _goals()):
        found: list[Any] = [None]
        problem = walks[min(goal.event_type, 4)](state, goal, config, found)
        assert (problem, None if problem else found[0]) == _walked_one_by_one(state, goal, config), (
            state,
            goal,
        )


@pytest.mark.spec("R4.1", "R4.2", "R4.3", "R4.6")
def test_a_check_of_one_condition_passes_exactly_when_its_condition_holds() -> None:
    one_condition = [check for check in machine.REQUEST_CHECKS if check.passes]
    assert [check.rule for check in one_condition] == ["R4.1", "R4.2", "R4.3", "R4.6"]
    for check, state, goal in itertools.product(one_condition, _states(), _goals()):
        holds = eval(check.passes, {}, {"state": state, "goal": goal, "config": STANDARD})
        problem = check.check(state, goal, STANDARD, [None])
        assert (problem is None) == bool(holds), (check.rule, state, goal)
        assert problem is None or (isinstance(problem, outs.Rejected) and problem.rule == check.rule)


def test_the_table_names_a_handler_for_every_input_and_every_handler_is_in_it() -> None:
    kinds = {cls.KIND for cls in typing.get_args(ins.Input)}
    assert set(machine._HANDLER_NAMES) == kinds
    for kind, name in machine._HANDLER_NAMES.items():
        handler = machine.HANDLERS[kind]
        assert handler.__name__ == name and handler.__module__ == machine.__name__, (kind, name)
    handlers = {name for name, value in vars(machine).items() if name.startswith("_on_") and callable(value)}
    assert handlers == set(machine._HANDLER_NAMES.values())


def test_the_module_opens_with_its_table_and_its_handlers_follow_in_the_spec_s_order() -> None:
    source = Path(machine.__file__).read_text(encoding="utf-8")
    tree = ast.parse(source)
    lines = {
        node.name if isinstance(node, ast.FunctionDef) else ast.unparse(node.targets[0]): node.lineno
        for node in tree.body
        if isinstance(node, ast.FunctionDef) or (isinstance(node, ast.Assign) and len(node.targets) == 1)
    }
    annotated = {
        ast.unparse(node.target): node.lineno for node in tree.body if isinstance(node, ast.AnnAssign)
    }
    first_rule = min(line for name, line in lines.items() if name.startswith("_on_"))
    assert annotated["_HANDLER_NAMES"] < annotated["TRANSITIONS"] < lines["step"] < first_rule
    sections = [int(number) for number in re.findall(r"^# -+ §(\d+) ", source, re.MULTILINE)]
    assert sections == sorted(sections) and {3, 4, 5, 21} <= set(sections)
    # the handlers appear in the order the table names them, the table's in the order of the spec
    order = list(dict.fromkeys(machine._HANDLER_NAMES.values()))
    assert sorted(order, key=lambda name: lines[name]) == order
