"""Descriptions real clients send, with the fleet adapter's schema's verdict: shared by the tests of
dynevent.descriptions and of ``dynevent serve`` over DDS."""

from __future__ import annotations

from typing import Any

#: Everyday go_to_place descriptions and what the fleet adapter's schema says of them.
EVERYDAY_GO_TO_PLACE: list[tuple[Any, bool]] = [
    ("A", True),
    (3, True),
    ({"waypoint": "A"}, True),
    ({"waypoint": 3, "orientation": 1.57}, True),
    ({"place": "A"}, True),
    ({"place": {"waypoint": "A", "orientation": 1.5}}, True),
    ({"place": 4}, True),
    ({"one_of": ["A", "B"]}, True),
    ({"one_of": [{"waypoint": 2}]}, True),
    ({"one_of": ["A", 5.5]}, False),
    ({"place": "A", "followed_by": [1.5]}, False),
    ({"place": "A", "start_at_departure": "x"}, False),
]

#: Everyday perform_action descriptions and the fleet adapter's schema's verdict.
EVERYDAY_PERFORM_ACTION: list[tuple[Any, bool]] = [
    ({"category": "wave", "description": {"arm": "left"}}, True),
    ({"category": "wave", "description": None, "unix_millis_action_duration_estimate": 300}, True),
    ({"category": "wave", "description": 1, "use_tool_sink": True, "expected_finish_location": 2}, True),
    ("clean", False),
    ({"category": "wave"}, False),
    ({"category": "wave", "description": {}, "use_tool_sink": "yes"}, False),
]
