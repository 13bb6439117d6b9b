"""Hypothesis strategies and a reusable stateful test for Dynamic Event implementations.

Requires the ``testing`` extra (``pip install 'dynevent[testing]'``), which
pulls in hypothesis.  Nothing in the core imports this package.
"""

from __future__ import annotations

from .strategies import (
    hostile_json_values,
    json_values,
    messages,
    wire_dicts,
)

__all__ = ["hostile_json_values", "json_values", "messages", "wire_dicts"]
