"""``dynevent check RECORDING``: what the command prints of a rosbag2 recording, and its exit status (0
clean, 1 a violation, 2 a recording it cannot judge, in one line).  The judgement itself is the bag
reader's (tests/bags) and the judge's (tests/conformance/judge); the command on a trace is in
tests/tools/test_cli.py.
"""

from __future__ import annotations

import json
from pathlib import Path

from rosbags.rosbag2 import StoragePlugin, Writer

from support.recordings import (
    FLEET,
    SECOND,
    STATUS_TOPIC,
    STORAGES,
    UNHASHED,
    Conversation,
    check_command,
    clean_run,
    partial_clean_run,
    ros_time,
    ros_type,
    topics_alone,
)


def test_dynevent_check_reads_a_bag_directory_or_file_and_exits_0_1_or_2(tmp_path: Path) -> None:
    clean = clean_run().write(tmp_path / "clean", StoragePlugin.MCAP)
    done = check_command(str(clean))
    assert done.returncode == 0, done.stderr
    assert (
        done.stdout.splitlines()[-1] == f"{clean}: 1 robot(s), 1 judged in full, 14 messages, no violations"
    )
    stale = Conversation().begin().status(1, 1, "standby", 0).goal(1, seq=0, event_type=3)
    bag = stale.write(tmp_path / "stale", StoragePlugin.SQLITE3)
    storage = next(bag.glob("*.db3"))
    done = check_command(str(storage))
    assert done.returncode == 1
    assert done.stdout.startswith(
        f"{storage}: tinyRobot/r1 @ {stale.now // SECOND}.{stale.now % SECOND:09d}: R4.2 "
    )
    done = check_command("--json", str(bag))
    rows = [json.loads(line) for line in done.stdout.splitlines()]
    assert [row["type"] for row in rows] == ["violation", "partial_view", "summary"]
    assert rows[0]["rule"] == "R4.2" and rows[0]["robot"] == "tinyRobot/r1"
    (tmp_path / "notabag").mkdir()
    done = check_command(str(tmp_path / "notabag"))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.strip().endswith("not a rosbag2 recording: a bag directory holds a metadata.yaml")
    other = Conversation().at("/chatter", "builtin_interfaces/msg/Time", ros_time(5))
    done = check_command(str(other.write(tmp_path / "other", StoragePlugin.MCAP)))
    assert done.returncode == 2 and done.stderr.strip().endswith(
        "nothing to check: no message on a Dynamic Event name (1 other message)"
    ), done.stderr
    for storage in STORAGES:  # an empty bag, and one whose Dynamic Event topics hold no message
        empty = Conversation().write(tmp_path / f"empty-{storage.name}", storage)
        done = check_command(str(empty))
        assert done.returncode == 2 and done.stderr.strip().endswith(
            "nothing to check: no message on a Dynamic Event name (0 other messages)"
        ), done.stderr
        silent = tmp_path / f"silent-{storage.name}"
        with Writer(silent, version=9, storage_plugin=storage) as writer:
            writer.add_connection(
                STATUS_TOPIC, "rmf_task_msgs/msg/DynamicEventStatus", msgdef="", rihs01=UNHASHED
            )
        done = check_command(str(silent))
        assert done.returncode == 2 and "nothing to check: no message on a Dynamic Event name" in done.stderr


def test_a_robot_without_goals_in_an_introspected_recording_is_said_to_have_had_none(tmp_path: Path) -> None:
    """Introspection was on (another robot's goals are in the bag): a robot whose goals the bag does not
    hold had none, and the line says so instead of calling the recording short of introspection."""
    run = clean_run()
    other = f"/rmf/dynamic_event/status/{FLEET}/idle"
    message = ros_type("rmf_task_msgs/msg/DynamicEventStatus")(
        dynamic_event_seq=0, dynamic_state=0, status="uninitialized", id=0, time=ros_time(run.now)
    )
    bag = run.at(other, "rmf_task_msgs/msg/DynamicEventStatus", message).write(
        tmp_path / "two", StoragePlugin.MCAP
    )
    done = check_command(str(bag))
    assert done.returncode == 0, done.stdout + done.stderr
    lines = [line for line in done.stdout.splitlines() if f"{FLEET}/idle" in line]
    assert lines == [
        f"{bag}: {FLEET}/idle: this robot had no goals in the recording (the action's introspection was on): "
        "judged from its topics alone",
        f"{bag}: {FLEET}/idle: 1 records, no violations",
    ], done.stdout
    alone = topics_alone(partial_clean_run()).write(tmp_path / "topics", StoragePlugin.MCAP)
    assert "partial view, judged from its topics alone" in check_command(str(alone)).stdout
