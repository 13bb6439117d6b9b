"""``dynevent serve`` that kills itself with SIGKILL at a chosen point of a goal's life (a test's tool).

``python crashing_serve.py POINT SERVE-ARGS...``: POINT is ``started`` (the goal accepted and its child
started in the store, nothing of it sent yet) or ``answered`` (the goal's answer kept in the store, not
yet sent).  The kill comes from serve's own observer, which sees each output just before it is carried
out, so the point is exact.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Callable
from typing import Any

from dynevent.server import outputs as outs
from dynevent.tools.cli import main
from dynevent.tools.live import serve

POINTS: dict[str, type[outs.Output]] = {"started": outs.StartChild, "answered": outs.AnswerGoal}


def _crashing(point: type[outs.Output]) -> Callable[..., Any]:
    observer = serve._observer

    def crashing_observer(fleet: str, robot: str, say: Callable[[str], None]) -> Callable[[Any], None]:
        observe = observer(fleet, robot, say)

        def crash(output: Any) -> None:
            observe(output)
            if isinstance(output, point):
                sys.stdout.flush()
                os.kill(os.getpid(), signal.SIGKILL)

        return crash

    return crashing_observer


if __name__ == "__main__":
    serve._observer = _crashing(POINTS[sys.argv[1]])
    sys.exit(main(["serve", *sys.argv[2:]]))
