"""serve's rmf_ros2 mode against the deployed server's recordings (tests/data/rmf_ros2/).

Each recording's client goals, in their order, drive the machine configured as ``dynevent serve
--compatibility rmf_ros2`` serves the lab's site (its places), the site's own events read back
from what the adapter published (:mod:`dynevent.conformance.judge.replay`).  What the machine says is set
beside what the adapter said, point by point: each goal's response and answer, the status
sequence, each goal's feedback and log tiers.  Every point where they part is listed here with the
D-number that explains it, and the ids the site's children took from the task's counter are
listed too.  A change to the machine's rmf_ros2 mode at any point the recordings show changes a
list below, and fails here.
"""

from __future__ import annotations

import collections
import json
import re
from pathlib import Path

import pytest

pytest.importorskip("rosbags", reason="the bags extra (rosbags) reads the recordings")

from dynevent.bags.reader import bag_records
from dynevent.conformance.judge.divergences import label_difference
from dynevent.conformance.judge.replay import Comparison, compare_recording
from dynevent.conformance.judge.trace import read_trace, step_records
from dynevent.errors import TraceError
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server.machine import ServerConfig, State, any_description
from dynevent.sim.config import ServeConfig, machine_config
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import Compatibility, IdPolicy

DATA = Path(__file__).resolve().parents[2] / "data" / "rmf_ros2"
DOC = Path(__file__).resolve().parents[3] / "docs" / "divergences.md"
PLACES = ("dock", "hall", "pantry", "lounge", "lobby")  # lab/rmf_ros2/site/navgraph.yaml


def served_as(compatibility: str) -> ServerConfig:
    """The machine's configuration of ``dynevent serve --compatibility`` for the lab's site."""
    return machine_config(ServeConfig(places=PLACES, compatibility=compatibility))


def compared(name: str, compatibility: str = "rmf_ros2") -> Comparison:
    ((key, records),) = bag_records(DATA / name).items()
    return compare_recording(records, served_as(compatibility), fleet=key[0], robot=key[1])


def labels(comparison: Comparison) -> collections.Counter[tuple[str, str]]:
    return collections.Counter(
        (name, item.channel) for item in comparison.differences for name in label_difference(item)
    )


#: Where serve's rmf_ros2 mode parts from the adapter, per recording: {(D-number, channel): count}.
EXPECTED = {
    "send": {("D26", "statuses"): 3},
    "probe": {
        ("D1", "answers"): 1,
        ("D1", "statuses"): 1,
        ("D26", "statuses"): 2,
    },
    "stubborn": {("D26", "statuses"): 1, ("D11", "feedback"): 1},
}

#: The ids the site's children took, where the machine would have numbered them one above the last:
#: a go_to_place child draws a second id from the task's counter for its own plan (D10).
COUNTER = {
    "send": ("run 1: child 3 (the machine's next: 2)", "run 1: child 5 (the machine's next: 4)"),
    "stubborn": (),
}


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_serve_in_rmf_ros2_mode_parts_from_the_adapter_only_where_the_page_says(name: str) -> None:
    comparison = compared(name)
    found = labels(comparison)
    assert all(name != "?" for name, _ in found), [str(d) for d in comparison.differences]
    assert dict(found) == EXPECTED[name]
    # every goal of the recording was replayed (probe's first two lost their requests: it starts after)
    assert comparison.goals == {"send": 7, "probe": 31, "stubborn": 1}[name]


@pytest.mark.parametrize("name", sorted(COUNTER))
def test_the_site_numbers_a_go_to_place_child_two_ids_on(name: str) -> None:
    assert compared(name).counter == COUNTER[name]


def test_the_probe_recording_replays_from_its_first_goal_with_its_ids_two_apart() -> None:
    comparison = compared("probe")
    assert comparison.start == 27
    # a child the adapter answered at once (the robot already there) takes one id: 11 then 12
    children = [int(re.search(r"child (\d+)", line).group(1)) for line in comparison.counter]  # type: ignore[union-attr]
    assert children[:6] == [4, 6, 8, 10, 12, 14]
    assert children[6:] == [3, 5, 7, 9, 11, 14, 16]


def test_the_standard_mode_parts_from_the_adapter_far_more() -> None:
    """The comparison sees what rmf_ros2 mode reproduces: in standard mode the RUNNING status after
    a child's end (D2) and the CANCELs naming the adapter's ids (D10) part too."""
    standard = compared("send", "standard")
    channels = collections.Counter(item.channel for item in standard.differences)
    assert channels["ids"] == 1 and channels["responses"] == 2 and channels["answers"] == 2
    assert any("RUNNING completed" in " ".join(item.recorded) for item in standard.differences)
    assert len(standard.differences) > len(compared("send").differences)


def test_a_change_to_the_rmf_ros2_mode_shows() -> None:
    """An emulation that honoured the NEXT's id (D10) would part from the adapter where the
    recordings show its numbering."""
    ((key, records),) = bag_records(DATA / "send").items()
    goal_ids = ServerConfig(
        categories=served_as("rmf_ros2").categories,
        id_policy=IdPolicy.GOAL,
        compatibility=Compatibility.RMF_ROS2,
    )
    changed = compare_recording(records, goal_ids, fleet=key[0], robot=key[1])
    assert any(item.channel == "ids" for item in changed.differences)
    assert changed.counter == ()


def test_a_recording_without_goals_cannot_be_replayed() -> None:
    """rmf_demos' client has no introspection: its recording holds topics only (check judges it as a
    partial view)."""
    ((key, records),) = bag_records(DATA / "demos").items()
    with pytest.raises(TraceError, match="holds no goal"):
        compare_recording(records, served_as("rmf_ros2"), fleet=key[0], robot=key[1])


def test_every_label_is_a_d_number_whose_section_names_the_replay() -> None:
    text = DOC.read_text(encoding="utf-8")
    sections = dict(re.findall(r"^## (D\d+)\.(.*?)(?=^## |\Z)", text, flags=re.MULTILINE | re.DOTALL))
    for counts in EXPECTED.values():
        for label_, _ in counts:
            assert label_ in sections, f"{label_} is no section of docs/divergences.md"
            assert "**Replayed**" in sections[label_], f"{label_} does not say what the replay shows"


# --- the replay itself, on the machine's own traces ----------------------------------------------------


def _own_trace(config: ServerConfig) -> list[str]:
    """A server's trace: a run with a completed child, a cancelled child, a refused NEXT, a FINISHED;
    then a run ended by its task's cancel while a child runs."""
    state = State.new("fleet", "robot")
    lines: list[str] = []
    second = 1_000_000_000

    def goal(n: int, seq: int, event_type: int, t: int, **fields: object) -> list[ins.Input]:
        uuid = f"{n:032x}"
        made = Goal(dynamic_event_seq=seq, event_type=event_type, **fields)  # type: ignore[arg-type]
        return [ins.GoalRequested(goal_uuid=uuid, goal=made, now=t), ins.GoalStarted(goal_uuid=uuid, now=t)]

    place = {"category": "go_to_place", "description": '"hall"'}
    script: list[ins.Input] = [
        ins.Begin(description="{}", event_id=0, now=1 * second),
        *goal(1, 1, 1, 2 * second, id=1, **place),
        ins.ChildProgress(status="underway", log_text="moving", now=3 * second),
        ins.ChildFinished(status="completed", now=4 * second),
        *goal(2, 1, 1, 5 * second, id=2, **place),
        *goal(3, 1, 1, 6 * second, id=3, **place),  # busy: refused
        *goal(4, 1, 2, 7 * second, id=2),
        ins.ChildFinished(status="canceled", now=8 * second),
        *goal(5, 1, 3, 9 * second),
        ins.Begin(description="{}", event_id=0, now=10 * second),
        *goal(6, 2, 1, 11 * second, id=1, **place),
        ins.TaskCancel(now=12 * second),
        ins.ChildFinished(status="canceled", now=12 * second),
    ]
    for event in script:
        if isinstance(event, ins.GoalStarted) and not any(
            queued.goal_uuid == event.goal_uuid for queued in state.queued
        ):
            continue  # refused: nothing to start
        transition = machine.step(state, event, config)
        state = transition.state
        lines.extend(json.dumps(row) for row in step_records(event, transition.outputs))
    return lines


@pytest.mark.parametrize("compatibility", ["standard", "rmf_ros2"])
def test_a_server_replays_to_itself(compatibility: str) -> None:
    """The machine's own trace, replayed under the same configuration, parts nowhere: the site's
    events are read back as the inputs that made them."""
    config = ServerConfig(
        categories={"go_to_place": any_description},
        compatibility=compatibility,
        id_policy=IdPolicy.ADAPTER if compatibility == "rmf_ros2" else IdPolicy.GOAL,
    )
    _, records = read_trace(_own_trace(config))
    comparison = compare_recording(records, config, fleet="fleet", robot="robot")
    assert comparison.goals == 6
    assert comparison.differences == ()
    assert comparison.counter == ()


def test_a_server_replayed_under_another_mode_parts() -> None:
    standard = ServerConfig(categories={"go_to_place": any_description})
    _, records = read_trace(_own_trace(standard))
    other = ServerConfig.rmf_ros2({"go_to_place": any_description})
    comparison = compare_recording(records, other, fleet="fleet", robot="robot")
    assert {item.channel for item in comparison.differences} >= {"statuses"}
