"""How the tests run the stateful kit of dynevent.testing, and the input sequences they draw: shared by
the kit's own tests (tests/testing) and the machine's properties (tests/spec/test_19_invariants.py)."""

from __future__ import annotations

import os
from typing import Any

from hypothesis import settings

from dynevent.conformance.records import config_from_json
from dynevent.testing import DEFAULT_CONFIG, input_sequences

PROFILE = os.environ.get("DYNEVENT_HYPOTHESIS_PROFILE", "ci")
#: Steps per stateful run: short in ci, the profile's own count (200 in deep) otherwise.
STEPS = 40 if PROFILE == "ci" else settings.default.stateful_step_count

#: The kit's configuration in rmf_ros2's mode (the adapter numbers the children).
RMF_ROS2_CONFIG: dict[str, Any] = {**DEFAULT_CONFIG, "compatibility": "rmf_ros2", "id_policy": "adapter"}
#: The machine's configuration in each mode, by name.
CONFIGS = {
    "standard": config_from_json(dict(DEFAULT_CONFIG)),
    "rmf_ros2": config_from_json(RMF_ROS2_CONFIG),
}
#: Lists of up to 40 inputs over the kit's categories.
SEQUENCES = input_sequences(tuple(DEFAULT_CONFIG["categories"]), max_size=40)
