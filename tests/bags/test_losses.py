"""No false verdict where a lossy link lost messages for good: each recording of tests/data/lossy,
all of a correct server, is checked again with messages left out that a reliable writer can lose for
good (tests/support/losses.py: one its writer's history let go before it was sent again, or one that
had not come when the recording stopped), one to three at a time, and ``check`` still finds nothing.

Seeded: each run leaves out the same messages.  ``DYNEVENT_LOSS_VARIANTS`` sets how many copies of
each recording are checked (default 12; the reading found three misreadings at 300 a recording)."""

from __future__ import annotations

import os
import random
from pathlib import Path

import pytest

from dynevent.bags.reader import check_bag
from support.losses import REPAIR, losable, read, without

LOSSY = Path(__file__).resolve().parents[1] / "data" / "lossy"
VARIANTS = int(os.environ.get("DYNEVENT_LOSS_VARIANTS", "12"))
#: The most messages a copy leaves out.
AT_MOST = 3


@pytest.mark.spec("R19.1", "R2.2", "R4.6", "R10.1")
@pytest.mark.parametrize("name", sorted(path.name for path in LOSSY.iterdir() if path.is_dir()))
def test_messages_lost_for_good_make_no_finding_against_a_correct_server(name: str, tmp_path: Path) -> None:
    bag = LOSSY / name
    messages = read(bag)
    candidates = losable(messages)
    assert candidates, "a recording with nothing a lossy link can lose for good"
    rng = random.Random(name)
    for variant in range(VARIANTS):
        left_out = rng.sample(candidates, min(rng.randint(1, AT_MOST), len(candidates)))
        copy = without(bag, messages, {message.log_time for message in left_out}, tmp_path / str(variant))
        report = check_bag(copy)
        findings = [finding for robot in report.robots for finding in robot.report.findings]
        what = [(message.topic, message.log_time) for message in left_out]
        assert not findings, f"left out {what}: {findings}"


def test_the_model_loses_only_what_a_writer_let_go_or_never_sent_again() -> None:
    """A status its robot's next status followed within the repair time may be lost for good (the
    status topic keeps one message); one its robot's next followed later, received long before the
    recording's end, may not (the writer still held it to send again)."""
    messages = read(LOSSY / "thirty")
    candidates = {(message.topic, message.log_time) for message in losable(messages)}
    end = max(message.log_time for message in messages)
    repair = round(REPAIR * 1e9)
    statuses = [message for message in messages if message.topic.startswith("/rmf/dynamic_event/status/")]
    replaced, kept = [], []
    for status in statuses:
        newer = [
            other
            for other in statuses
            if other.topic == status.topic and other.publish_time > status.publish_time
        ]
        if newer and min(other.publish_time for other in newer) <= status.publish_time + repair:
            replaced.append(status)
        elif status.log_time < end - repair:
            kept.append(status)
    assert replaced and kept
    assert all((status.topic, status.log_time) in candidates for status in replaced)
    assert not any((status.topic, status.log_time) in candidates for status in kept)
