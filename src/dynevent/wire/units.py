"""Time in dynevent: one convention, at every door.

- **An instant is integer nanoseconds** since the Unix epoch (or since the
  start of a simulated clock): every ``now``, as a ROS clock gives it
  (``node.get_clock().now().nanoseconds``).  A float is refused, so a
  ``time.time()`` in seconds cannot slip in.
- **A duration is seconds**, an int or a float, as ROS message fields
  (``stubborn_period``) and rclpy (``timeout_sec``) have them: a client's
  ``timeout``, a simulated session's delays and scripts, a server's settings, serve's
  configuration, every command line option.  A duration above
  :data:`MAX_DURATION` is refused as the likely nanoseconds it is
  (``timeout=60 * SECOND`` is 60 billion seconds).

:data:`SECOND` and :data:`MILLISECOND` are for arithmetic on instants
(``now + 5 * SECOND``); :func:`to_nanoseconds` turns a duration into the
nanoseconds an instant is counted in.
"""

from __future__ import annotations

import math
from typing import Any

from dynevent.errors import InvalidValue
from dynevent.wire._fields import SECOND

__all__ = ["MAX_DURATION", "MILLISECOND", "SECOND", "to_nanoseconds"]

#: A millisecond, in nanoseconds (the unit of instants).
MILLISECOND = SECOND // 1000
#: The longest duration dynevent takes, in seconds (a week): a larger number is taken for a
#: duration given in nanoseconds by mistake, and refused.
MAX_DURATION = 7 * 86_400


def to_nanoseconds(owner: str, field: str, seconds: Any, *, zero: bool = True) -> int:
    """A duration in seconds (int or float, finite, from 0 (above 0 without ``zero``) to
    :data:`MAX_DURATION`) as integer nanoseconds; :class:`~dynevent.errors.InvalidValue` naming
    ``owner.field`` otherwise."""
    if isinstance(seconds, bool) or not isinstance(seconds, (int, float)):
        raise InvalidValue(owner, field, seconds, "expected a duration in seconds (an int or a float)")
    # an int is finite, and isfinite cannot take one too large for a float
    if (
        (isinstance(seconds, float) and not math.isfinite(seconds))
        or seconds < 0
        or (seconds == 0 and not zero)
    ):
        bound = "0 or more" if zero else "above 0"
        raise InvalidValue(owner, field, seconds, f"expected a finite duration in seconds, {bound}")
    if seconds > MAX_DURATION:
        raise InvalidValue(
            owner,
            field,
            seconds,
            f"durations are in seconds, at most {MAX_DURATION} (a week): is this nanoseconds?",
        )
    return round(seconds * SECOND)
