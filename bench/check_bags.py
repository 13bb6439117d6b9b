"""``dynevent check`` on a rosbag2 recording against the same conversation as a trace: records per
second and peak memory.

The conversation is bench/traces.py's clean run of child cycles.  It is written
once as a JSON-lines trace and once as a bag in each storage format (MCAP,
SQLite), with rosbags' own writer, each record as the message a recorder with
the server's introspection on receives (a goal as its request and response
events, an answer as its get_result events).  Then ``python -m dynevent check``
runs on each in a child process; the table gives the wall time, the records
per second, the ratio to the trace and the peak resident memory.  The goal:
a bag within 2x of the trace.  ``--write`` records the result as the
``check-bags`` section of bench/results.md.

    python bench/check_bags.py [--cycles 20000] [--write]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script: make `bench` importable
    sys.path.insert(0, str(ROOT))

from bench import results  # noqa: E402
from bench.traces import FLEET, ROBOT, cycle_lines  # noqa: E402

ACTION = f"/rmf/dynamic_event/command/{FLEET}/{ROBOT}"
_TOPICS = {
    "begin": (f"/rmf/dynamic_event/begin/{FLEET}/{ROBOT}", "rmf_task_msgs/msg/DynamicEventDescription"),
    "status": (f"/rmf/dynamic_event/status/{FLEET}/{ROBOT}", "rmf_task_msgs/msg/DynamicEventStatus"),
    "feedback": (f"{ACTION}/_action/feedback", "rmf_task_msgs/action/DynamicEvent_FeedbackMessage"),
    "send_goal": (
        f"{ACTION}/_action/send_goal/_service_event",
        "rmf_task_msgs/action/DynamicEvent_SendGoal_Event",
    ),
    "get_result": (
        f"{ACTION}/_action/get_result/_service_event",
        "rmf_task_msgs/action/DynamicEvent_GetResult_Event",
    ),
}
_GOAL_STATUS = {"succeeded": 4, "canceled": 5, "aborted": 6}
STORAGES = ("mcap", "sqlite3")


def write_bag(path: Path, lines: Iterable[str], storage: str) -> None:
    """The trace's records as a recorder receives them, in a bag at ``path``."""
    import numpy as np
    from rosbags.rosbag2 import StoragePlugin, Writer

    from dynevent.bags.reader import message_definition, typestore

    store = typestore()
    types = store.types

    def stamp(ns: int) -> Any:
        return types["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)

    def uuid(hex_digits: str) -> Any:
        return types["unique_identifier_msgs/msg/UUID"](
            uuid=np.frombuffer(bytes.fromhex(hex_digits), np.uint8)
        )

    def event(
        kind: str, event_type: int, call: int, now: int, request: Any = None, response: Any = None
    ) -> Any:
        info = types["service_msgs/msg/ServiceEventInfo"](
            event_type=event_type, stamp=stamp(now), client_gid=np.zeros(16, np.uint8), sequence_number=call
        )
        return types[_TOPICS[kind][1]](info=info, request=[request] if request else [],
                                        response=[response] if response else [])  # fmt: skip

    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    with Writer(path, version=9, storage_plugin=plugin) as writer:
        connections = {
            kind: writer.add_connection(
                topic, msgtype, msgdef=message_definition(msgtype), rihs01="RIHS01_" + "0" * 64
            )
            for kind, (topic, msgtype) in _TOPICS.items()
        }
        calls: dict[str, int] = {}
        rows = iter(lines)
        next(rows)  # the config line: no message
        for line in rows:
            row = json.loads(line)
            now = round(row["time"] * 10**9)
            kind, uuid_hex = row["type"], row.get("goal_uuid", "")
            call = calls.setdefault(uuid_hex, len(calls) + 1)
            if kind == "begin":
                message = dict(row["message"], start_time=stamp(now))
                written = [("begin", types[_TOPICS["begin"][1]](**message))]
            elif kind == "status":
                message = dict(row["message"], time=stamp(now))
                written = [("status", types[_TOPICS["status"][1]](**message))]
            elif kind == "goal":
                goal = types["rmf_task_msgs/action/DynamicEvent_Goal"](**row["goal"])
                request = types["rmf_task_msgs/action/DynamicEvent_SendGoal_Request"](
                    goal_id=uuid(uuid_hex), goal=goal
                )
                written = [("send_goal", event("send_goal", 1, call, now, request=request))]
            elif kind == "goal_response":
                response = types["rmf_task_msgs/action/DynamicEvent_SendGoal_Response"](
                    accepted=row["accepted"], stamp=stamp(now)
                )
                written = [("send_goal", event("send_goal", 2, call, now, response=response))]
            elif kind == "feedback":
                logs = [types["rmf_task_msgs/msg/LogEntry"](**entry) for entry in row["feedback"]["logs"]]
                feedback = types["rmf_task_msgs/action/DynamicEvent_Feedback"](
                    **dict(row["feedback"], logs=logs)
                )
                written = [
                    ("feedback", types[_TOPICS["feedback"][1]](goal_id=uuid(uuid_hex), feedback=feedback))
                ]
            elif kind == "result":
                request = types["rmf_task_msgs/action/DynamicEvent_GetResult_Request"](goal_id=uuid(uuid_hex))
                result = types["rmf_task_msgs/action/DynamicEvent_Result"](**row["result"])
                response = types["rmf_task_msgs/action/DynamicEvent_GetResult_Response"](
                    status=_GOAL_STATUS[row["status"]], result=result
                )
                written = [("get_result", event("get_result", 1, call, now, request=request)),
                           ("get_result", event("get_result", 2, call, now, response=response))]  # fmt: skip
            else:
                raise ValueError(f"no bag message for a {kind!r} record")
            for topic_kind, message in written:
                msgtype = _TOPICS[topic_kind][1]
                writer.write(connections[topic_kind], now, store.serialize_cdr(message, msgtype))


def run_check(path: Path) -> tuple[float, subprocess.CompletedProcess[str], int]:
    """``dynevent check`` on ``path`` in a child process: wall seconds, what it printed (its exit
    status is in the last line of its output, after ``status``), its peak resident KB."""
    code = (
        "import resource, runpy, sys; sys.argv = ['dynevent', 'check', sys.argv[1]]\n"
        "try:\n    runpy.run_module('dynevent', run_name='__main__')\n"
        "except SystemExit as exit:\n    print('status', exit.code)\n"
        "print('peak', resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)"
    )
    started = time.perf_counter()
    done = subprocess.run(
        [sys.executable, "-c", code, str(path)], capture_output=True, text=True, check=False
    )
    wall = time.perf_counter() - started
    return wall, done, int(done.stdout.strip().splitlines()[-1].split()[1])


def _check(path: Path) -> tuple[float, int, str, int]:
    """``dynevent check`` on ``path`` in a child process: wall seconds, records, the summary, peak KB."""
    wall, done, peak = run_check(path)
    lines = [line for line in done.stdout.strip().splitlines()[:-1] if not line.startswith("status ")]
    summary = lines[-1]
    if "no violations" not in summary:
        raise SystemExit(f"dynevent check did not find {path} clean:\n{done.stdout}{done.stderr}")
    words = summary.replace(",", "").split()
    records = (
        int(words[words.index("records") - 1])
        if "records" in words
        else int(words[words.index("messages") - 1])
    )
    return wall, records, summary, peak


def make(directory: Path, cycles: int, storages: list[str]) -> None:
    """Write the trace and the bags into ``directory``, streamed (a bag of a gigabyte too)."""
    trace = Path(directory, "trace.jsonl")
    with trace.open("w", encoding="utf-8") as out:
        out.writelines(cycle_lines(cycles))
    for storage in storages:
        with trace.open(encoding="utf-8") as lines:
            write_bag(Path(directory, storage), lines, storage)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cycles", type=int, default=20_000, help="child cycles (7 records each)")
    parser.add_argument("--write", action="store_true", help="record the result in bench/results.md")
    parser.add_argument(
        "--storage", choices=STORAGES, action="append", help="only this storage format (default: both)"
    )
    parser.add_argument("--dir", help="write the inputs here (default: a temporary directory)")
    parser.add_argument(
        "--section", default="check-bags", help="the section of bench/results.md --write writes"
    )
    parser.add_argument(
        "--make", metavar="DIR", help=argparse.SUPPRESS
    )  # the inputs, in a process of their own
    args = parser.parse_args(argv)
    storages = args.storage or list(STORAGES)
    if args.make:
        make(Path(args.make), args.cycles, storages)
        return 0
    rows = []
    with tempfile.TemporaryDirectory(dir=args.dir) as directory:
        # made in another process, so that this one (whose children inherit its peak) stays small
        made = [sys.executable, __file__, "--make", directory, "--cycles", str(args.cycles)]
        subprocess.run([*made, *(f"--storage={storage}" for storage in storages)], check=True)
        trace = Path(directory, "trace.jsonl")
        wall, records, _, peak = _check(trace)
        rows.append(("JSON-lines trace", os.path.getsize(trace), wall, records, peak))
        base = records / wall
        for storage in storages:
            bag = Path(directory, storage)
            size = sum(item.stat().st_size for item in bag.iterdir())
            wall, _, _, peak = _check(bag)
            rows.append((f"bag, {storage}", size, wall, records, peak))
    table = ["| input | size | wall | records/s | vs the trace | peak memory |", "|---|---|---|---|---|---|"]
    for name, size, wall, count, peak in rows:
        rate = count / wall
        cells = [name, f"{size / 1e6:.1f} MB", f"{wall:.1f} s", f"{rate:,.0f}", f"{base / rate:.2f}x slower"]
        table.append("| " + " | ".join([*cells, f"{peak / 1024:.0f} MB"]) + " |")
    text = "\n".join(
        [f"{records:,} records ({args.cycles:,} child cycles), one process per input:", "", *table]
    )
    print(text)
    if args.write:
        title = "## dynevent check on a bag and on the same trace"
        if args.section != "check-bags":
            title += f" ({args.section})"
        results.write_section(args.section, [title, "", text])
    return 0


if __name__ == "__main__":
    sys.exit(main())
