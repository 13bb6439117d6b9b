"""An asyncio service that drives two robots at once, each through a run of its own.

Run it beside ``dynevent serve --robot tinyRobot1 --robot tinyRobot2`` (docs/serve.md), with ROS 2
sourced: ``python docs/examples/two_robots.py pantry lounge``.  Each robot goes to the places in
turn, then its dynamic event is finished; the two runs go on side by side in one event loop, and a
robot's progress is printed as it comes.  Exit status 0 when every goal succeeded.
"""

from __future__ import annotations

import asyncio
import json
import sys

from dynevent.client import Outcome, OutcomeKind, Progress
from dynevent.ros import AsyncRobotClient


async def drive(robot_name: str, places: list[str]) -> bool:
    """One robot: each place in turn, then FINISHED; True when every goal succeeded."""

    def report(progress: Progress) -> None:
        print(f"{robot_name}: [id {progress.id}] {progress.status}", flush=True)

    async with AsyncRobotClient("tinyRobot", robot_name, node_name=f"driver_{robot_name}") as robot:
        await robot.ready(15.0)
        for place in places:
            outcome = await robot.next("go_to_place", json.dumps(place), on_progress=report)
            print(f"{robot_name}: {place}: {outcome.kind.value}", flush=True)
            if not isinstance(outcome, Outcome) or outcome.kind is not OutcomeKind.COMPLETED:
                return False
        finished = await robot.finish()
        print(f"{robot_name}: finished: {finished.kind.value}", flush=True)
        return isinstance(finished, Outcome) and finished.kind is OutcomeKind.COMPLETED


async def main(places: list[str]) -> int:
    results = await asyncio.gather(drive("tinyRobot1", places), drive("tinyRobot2", places[::-1]))
    return 0 if all(results) else 1


if __name__ == "__main__":
    sys.exit(asyncio.run(main(sys.argv[1:] or ["pantry", "lounge"])))
