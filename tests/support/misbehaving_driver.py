"""dynevent's own driver, misbehaving on purpose at one request (a test double for the runner).

    python tests/support/misbehaving_driver.py MODE AT [--once FILE]

counts the requests it reads (``hello`` is request 1) and, at request ``AT``:

- ``exit``: exits (status 3) without answering, after a line on standard error;
- ``late``: answers after 1.5 s (late for ``--timeout 1``), then serves on;
- ``hang``: answers nothing, ever, from then on;
- ``garbage``: answers a line that is not JSON, then serves on;
- ``flood``: answers 10,000 lines of noise, then the real answer;
- ``huge``: answers one line of 20 MB (above the runner's limit);
- ``stderr``: writes 50 MB to standard error, then answers;
- ``closed``: closes its standard output and goes on running (an hour), its input still open;
- ``values``: answers one line of 3 million outputs (6 MB, under the byte limit);
- ``endless``: writes 50 MB to standard error as one line with no end, then answers;
- ``surrogate``: answers hello with a name holding a lone surrogate and a control character;
- ``next``: from request ``AT`` on, answers everything but a NEXT's goal request, which it never
  answers (a driver hung in its NEXT: every vector before a NEXT runs well).

With ``--once FILE`` it misbehaves only while FILE does not exist, and
creates it: the restarted driver then serves well, as a driver with a rare
fault would.
"""

from __future__ import annotations

import os
import sys
import time
from pathlib import Path

from dynevent.conformance.vectors.driver import Driver
from dynevent.wire import _json


def main() -> int:
    mode, at = sys.argv[1], int(sys.argv[2])
    once = Path(sys.argv[4]) if len(sys.argv) > 4 and sys.argv[3] == "--once" else None
    misbehave = once is None or not once.exists()
    if once is not None and misbehave:
        once.touch()
    driver = Driver()
    out = sys.stdout
    for count, line in enumerate(sys.stdin, start=1):
        request = _json.parse(line)
        if misbehave and mode == "next" and count >= at and _is_next(request):
            time.sleep(3600)
        answer = _json.dumps(driver.handle(request)) + "\n"
        if misbehave and count == at:
            if mode == "exit":
                sys.stderr.write("misbehaving_driver: giving up here\n")
                return 3
            if mode == "late":
                time.sleep(1.5)
            elif mode == "hang":
                time.sleep(3600)
            elif mode == "garbage":
                out.write("this is not JSON\n")
            elif mode == "flood":
                out.write("noise\n" * 10_000)
            elif mode == "huge":
                out.write("x" * 20_000_000 + "\n")
            elif mode == "closed":
                out.close()
                os.close(1)
                time.sleep(3600)
            elif mode == "values":
                out.write('{"ok": true, "outputs": [' + ", ".join(["{}"] * 3_000_000) + "]}\n")
            elif mode == "endless":
                for _ in range(50):
                    sys.stderr.write("e" * 1_000_000)
                sys.stderr.flush()
            elif mode == "surrogate":
                answer = answer.replace(
                    '"implementation":"dynevent', '"implementation":"\\udc80\\u0007dynevent'
                )
            elif mode == "stderr":
                chunk = "e" * 1_000_000 + "\n"
                for _ in range(50):
                    sys.stderr.write(chunk)
        out.write(answer)
        out.flush()
    return 0


def _is_next(request: object) -> bool:
    """The request applies a goal request of event type NEXT (1)."""
    event = request.get("input") if isinstance(request, dict) else None
    goal = event.get("goal") if isinstance(event, dict) and event.get("type") == "goal_requested" else None
    return isinstance(goal, dict) and goal.get("event_type") == 1


if __name__ == "__main__":
    with open(os.devnull, "w") as sink:  # nothing of Python's own on a closed pipe at exit
        try:
            sys.exit(main())
        except BrokenPipeError:
            os.dup2(sink.fileno(), sys.stdout.fileno())
            sys.exit(141)
