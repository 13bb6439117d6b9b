"""dynevent.bt without ROS: docs/bt.md's drawing is py_trees' own rendering of the example's tree
(and of the tree the page shows in code), descriptions from the blackboard, and bad input refused
at the edge.  The behaviours driving a robot are tested over DDS in tests/ros/test_ros_bt.py."""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

import py_trees
import pytest

from dynevent import bt
from dynevent.errors import InvalidValue

ROOT = Path(__file__).resolve().parents[2]
DOC = (ROOT / "docs" / "bt.md").read_text(encoding="utf-8")
sys.path.insert(0, str(ROOT / "docs" / "examples"))
import errand_tree  # noqa: E402


def _blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", DOC, flags=re.DOTALL)


def test_the_page_draws_the_examples_tree_as_py_trees_does() -> None:
    drawing = py_trees.display.ascii_tree(errand_tree.errand(None))  # type: ignore[arg-type]
    assert _blocks("text")[0] == drawing


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
