"""A deliberately broken implementation behind the driver protocol (a test double).

It is dynevent's own driver with one rmf_ros2 defect put back: a CANCEL goal
that starts frees the robot at once.  Instead of waiting for the child to end
(docs/spec.md R9.3), both the running goal and the CANCEL are answered in the
same step, as if the child had already ended canceled, and the robot is
WAITING again while the child is still winding down.

``dynevent vectors --impl "python tests/support/broken_driver.py"`` must fail on the
vectors that check R9.3, with a diff naming the vector and the step.
"""

from __future__ import annotations

import json
import sys
from typing import Any

from dynevent.conformance.vectors.driver import Driver


class BrokenDriver(Driver):
    """Answers a started CANCEL's goals immediately (rmf_ros2's idle-after-CANCEL defect)."""

    def handle(self, request: object) -> dict[str, Any]:
        answer = super().handle(request)
        if isinstance(request, dict) and request.get("op") == "hello":
            answer["implementation"] = "broken_driver (started CANCEL frees the robot at once)"
        if not (isinstance(request, dict) and request.get("op") == "apply" and answer.get("ok")):
            return answer
        event = request.get("input")
        if not isinstance(event, dict) or event.get("type") != "goal_started":
            return answer
        state = self.snapshot()
        if event.get("goal_uuid") in (state or {}).get("cancels", []):
            # the CANCEL now waits for the child: pretend the child already ended
            ended = super().handle(
                {
                    "op": "apply",
                    "input": {"type": "child_finished", "status": "canceled", "now": event["now"]},
                }
            )
            answer["outputs"] = answer["outputs"] + ended["outputs"]
            answer["view"] = ended["view"]
        return answer


def main() -> int:
    driver = BrokenDriver()
    for line in sys.stdin:
        if not line.strip():
            continue
        try:
            request = json.loads(line)
        except ValueError as exc:
            answer: dict[str, Any] = {"ok": False, "error": f"request is not JSON: {exc}"}
        else:
            answer = driver.handle(request)
        sys.stdout.write(json.dumps(answer) + "\n")
        sys.stdout.flush()
    return 0


if __name__ == "__main__":
    sys.exit(main())
