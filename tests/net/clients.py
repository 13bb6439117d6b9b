"""Clients of one robot for the tests across hosts, run as a process on a host:
``python clients.py async ROBOT [TRACE]`` drives it with an AsyncRobotClient (a NEXT, then FINISHED),
writing what it sends and hears to the trace file TRACE where given, and ``python clients.py bt
ROBOT`` with a behaviour tree (a RunEvent, then a FinishRun).  Each prints one line, the outcomes'
kinds, and exits 0 when both completed."""

from __future__ import annotations

import asyncio
import json
import sys
import time

#: The bound on each wait of a client, in seconds.
BOUND = 60.0


async def _drive_async(robot: str, trace_path: str | None = None) -> list[str]:
    from dynevent.conformance.judge.trace import TraceWriter
    from dynevent.ros import AsyncRobotClient

    trace = (
        None if trace_path is None else TraceWriter(trace_path, fleet="tinyRobot", robot=robot, tap="client")
    )
    async with AsyncRobotClient("tinyRobot", robot, node_name=f"async_{robot}", trace=trace) as client:
        await client.ready(BOUND)
        outcome = await asyncio.wait_for(client.next("go_to_place", json.dumps("pantry")), BOUND)
        finished = await asyncio.wait_for(client.finish(), BOUND)
        return [outcome.kind.value, finished.kind.value]


def _drive_tree(robot: str) -> list[str]:
    import py_trees

    from dynevent.bt import FinishRun, RunEvent
    from dynevent.ros import RobotClient

    with RobotClient("tinyRobot", robot, node_name=f"bt_{robot}") as client:
        client.ready(BOUND)
        event = RunEvent("to the pantry", client, "go_to_place", '{"one_of": ["pantry"]}')
        finish = FinishRun("done", client)
        root = py_trees.composites.Sequence("errand", memory=True, children=[event, finish])
        tree = py_trees.trees.BehaviourTree(root)
        deadline = time.monotonic() + 2 * BOUND
        while root.status not in (py_trees.common.Status.SUCCESS, py_trees.common.Status.FAILURE):
            if time.monotonic() > deadline:
                return ["the tree did not end", root.status.value]
            tree.tick()
            time.sleep(0.05)
        return [str(event.result.kind), str(finish.result.kind)]  # type: ignore[union-attr]


def main(argv: list[str]) -> int:
    kind, robot, *trace = argv
    kinds = asyncio.run(_drive_async(robot, *trace)) if kind == "async" else _drive_tree(robot)
    print(kind, " ".join(kinds), flush=True)
    return 0 if kinds == ["completed", "completed"] else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
