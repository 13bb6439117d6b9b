"""Sphinx configuration of dynevent's API reference (built in CI with warnings as errors)."""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "src"))

import dynevent  # noqa: E402

project = "dynevent"
author = "the dynevent developers"
copyright = "the dynevent developers"
release = dynevent.__version__
version = release

extensions = ["sphinx.ext.autodoc", "sphinx.ext.viewcode"]
autodoc_member_order = "bysource"
autodoc_default_options = {"members": True, "show-inheritance": True}
autodoc_typehints = "description"
autodoc_typehints_format = "short"
# dynevent.ros wraps rclpy; the reference is built without ROS 2
autodoc_mock_imports = [
    "rclpy",
    "rmf_task_msgs",
    "action_msgs",
    "unique_identifier_msgs",
    "builtin_interfaces",
    "rcl_interfaces",
]
nitpicky = False
default_role = "code"
html_theme = "alabaster"
html_title = f"dynevent {release}"
exclude_patterns = ["_build"]
