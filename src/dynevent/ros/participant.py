"""The DDS participant of a server process: a fleet's entities made in seconds, not minutes.

Fast DDS 3.2 pairs every new reader or writer with every endpoint of its own participant (copying
each one's proxy data), so that making ``n`` endpoints in one process costs in proportion to
``n**2``: 1,000 robots of ``dynevent serve`` (about 13 endpoints each) took 58 s to start, and a bare
rclpy process making only their 1,000 action servers 24 s.  A server process never talks to
itself, so its participants need not match their own endpoints: Fast DDS's participant property
``fastdds.ignore_local_endpoints`` skips that pairing (the same 1,000 action servers: 1.4 s).

:func:`ignore_own_endpoints` sets it for every participant the process makes afterwards, through the
profiles file Fast DDS reads (``FASTDDS_DEFAULT_PROFILES_FILE``, pointed at the one this package
ships), unless the user has a profiles file of their own or another middleware.  What listens to
the process's own topics (serve's judge, which follows its action servers' service events) must then
live in a participant of its own: a context of its own (:class:`dynevent.ros.spinning.Session` with
``own_context``).
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping
from pathlib import Path

__all__ = ["PROFILE", "ignore_own_endpoints"]

#: The Fast DDS profiles file whose default participant ignores its own endpoints.
PROFILE = Path(__file__).resolve().parent / "setup" / "fastdds-serve.xml"

_FAST_DDS = ("rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp")
_PROFILE_VARIABLES = ("FASTDDS_DEFAULT_PROFILES_FILE", "FASTRTPS_DEFAULT_PROFILES_FILE")


def ignore_own_endpoints(environ: MutableMapping[str, str] | None = None) -> str:
    """Before this process's first ``rclpy.init``: have its Fast DDS participants match none of their
    own endpoints.  Returns ``""`` when done, else one line saying why not and what it costs."""
    environ = os.environ if environ is None else environ
    rmw = environ.get("RMW_IMPLEMENTATION") or "rmw_fastrtps_cpp"
    if rmw not in _FAST_DDS:
        return f"DDS: {rmw} pairs a process's own endpoints too: a large fleet starts slowly"
    for name in _PROFILE_VARIABLES:
        if environ.get(name):
            return (
                f"DDS: {name} names your own profiles: give its default participant the property "
                "fastdds.ignore_local_endpoints=true for a large fleet to start fast (docs/serve.md)"
            )
    environ["FASTDDS_DEFAULT_PROFILES_FILE"] = str(PROFILE)
    return ""
