"""The simulated session's path in 0.1.0 (``from dynevent.tools.loopback import Loopback``), kept for
the code that imports it there.  The session lives beside the demo that runs it now
(:mod:`dynevent.tools.demo.simulated_session`), its class named :class:`SimulatedSession`;
``Loopback`` is that class."""

from __future__ import annotations

from dynevent.tools.demo.simulated_session import (
    Adapter,
    ChildScript,
    Options,
    SimulatedSession,
    TimelineEvent,
    format_timeline,
    timeline_jsonl,
)

Loopback = SimulatedSession

__all__ = [
    "Adapter",
    "ChildScript",
    "Loopback",
    "Options",
    "TimelineEvent",
    "format_timeline",
    "timeline_jsonl",
]
