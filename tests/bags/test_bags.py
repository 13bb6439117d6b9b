"""The bag reader (``dynevent check BAG`` without ROS): rosbag2 recordings written by rosbags' own
writer (tests/support/recordings.py), in both storage formats, judged per robot at the bag time of each
message.  (What the command prints of them is tests/tools/check's.)

(The messages are built from the type store the reader uses; tests/ros/test_ros_bags.py writes them
with ROS's own serialisation instead, which holds the reader's message definitions to ROS's.)
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import sqlite3
from collections.abc import Callable
from pathlib import Path
from typing import Any

import attrs
import pytest
from rosbags.rosbag2 import StoragePlugin, Writer

from dynevent.bags.reader import HOLD, BagReport, check_bag
from dynevent.conformance.judge.divergences import label
from dynevent.errors import BagError
from support.recordings import (
    ABORTED,
    ACCEPTED,
    ACTION,
    BEGIN_TOPIC,
    CANCELED,
    CANCELING,
    EXECUTING,
    FLEET,
    ROBOT,
    SECOND,
    STATUS_TOPIC,
    STORAGES,
    STORE,
    SUCCEEDED,
    T0,
    UNHASHED,
    Conversation,
    check_command,
    clean_run,
    partial_clean_run,
    ros_time,
    ros_type,
    ros_uuid,
    topics_alone,
)


def _robot(report: BagReport) -> Any:
    assert [robot.name for robot in report.robots] == [f"{FLEET}/{ROBOT}"]
    return report.robots[0]


@pytest.mark.parametrize("storage", STORAGES, ids=["mcap", "sqlite3"])
def test_a_clean_recording_is_clean_in_both_storage_formats(tmp_path: Path, storage: StoragePlugin) -> None:
    report = check_bag(clean_run().write(tmp_path / "bag", storage))
    robot = _robot(report)
    assert report.clean and robot.report is not None and robot.report.records == 12
    assert robot.absent == ()
    assert report.messages == 14 and report.other == 0


@pytest.mark.spec("R4.2", "R2.2", "R19.1")
@pytest.mark.parametrize("storage", STORAGES, ids=["mcap", "sqlite3"])
def test_each_broken_conversation_is_found_at_its_bag_time_and_rule(
    tmp_path: Path, storage: StoragePlugin
) -> None:
    stale = Conversation().begin().status(1, 1, "standby", 0).goal(1, seq=0, event_type=3)
    at_stale = stale.now  # the response that accepted it
    stale_running = Conversation().begin().status(1, 1, "standby", 0)
    stale_running.goal(1, goal_id=1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
    stale_running.result(1, SUCCEEDED, "completed", 1).status(1, 2, "underway", 1)  # after its answer
    at_running = stale_running.now

    def unanswered(tail: int) -> Conversation:
        missing = Conversation().begin().status(1, 1, "standby", 0)
        missing.goal(1, goal_id=1).ask(1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
        missing.status(1, 1, "standby", 1)  # the child ended: its NEXT's answer, asked for, never came
        missing.now += tail  # and the recording goes on
        return missing.at("/chatter", "builtin_interfaces/msg/Time", ros_time(5))

    missing = unanswered(HOLD + SECOND)  # longer than a lossy link may take to deliver the answer
    at_unanswered = missing.now - HOLD - SECOND - SECOND // 10
    cases = {
        "stale": (stale, at_stale, "R4.2"),
        "running": (stale_running, at_running, "R2.2"),
        # the WAITING status shows the child's end; its NEXT's answer, owed there, never came
        "missing": (missing, at_unanswered, "R19.1"),
    }
    for name, (conversation, at, rule) in cases.items():
        report = check_bag(conversation.write(tmp_path / name, storage))
        robot = _robot(report)
        assert robot.report is not None and not report.clean, name
        first = robot.report.findings[0]
        assert (first.line, first.rule) == (at, rule), (name, robot.report.findings)
        assert len(robot.report.findings) == 1, (name, robot.report.findings)
    # a recording that stopped sooner: the answer may have been on its way
    assert check_bag(unanswered(HOLD - SECOND).write(tmp_path / "stopped", storage)).clean


@pytest.mark.spec("R19.1", "R11.1")
def test_an_answer_no_client_asked_for_is_not_missing_and_a_goal_status_shows_an_answer(
    tmp_path: Path,
) -> None:
    """A bag holds an answer only where a client asked for it (a get_result call): an answer no
    client asked for is not judged missing, a goal status that shows the goal's end shows an answer
    the bag lacks (the response event lost), and one owed within a second of the recording's end
    may have been on its way.  Asked for, and none of these, it is missing (the broken
    conversations above)."""
    never_asked = Conversation().begin().status(1, 1, "standby", 0)
    never_asked.goal(1, goal_id=1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
    never_asked.status(1, 1, "standby", 1)
    assert check_bag(never_asked.write(tmp_path / "never", StoragePlugin.MCAP)).clean
    shown = Conversation().begin().status(1, 1, "standby", 0)
    shown.goal(1, goal_id=1).ask(1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
    shown.goal_statuses((1, SUCCEEDED)).status(1, 1, "standby", 1)  # the get_result response was lost
    shown.now += 2 * SECOND
    shown.at("/chatter", "builtin_interfaces/msg/Time", ros_time(5))
    assert check_bag(shown.write(tmp_path / "shown", StoragePlugin.MCAP)).clean
    stopped = Conversation().begin().status(1, 1, "standby", 0)
    stopped.goal(1, goal_id=1).ask(1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
    stopped.status(1, 1, "standby", 1)  # the recording stops here: the answer may have been on its way
    assert check_bag(stopped.write(tmp_path / "stopped", StoragePlugin.MCAP)).clean


@pytest.mark.spec("R2.2", "R19.1")
def test_a_goal_whose_request_the_bag_lost_begins_the_judgement_anew(tmp_path: Path) -> None:
    """A recorder that had not yet matched a new client's introspection publisher lost its first goal:
    the status shows a child no goal explains.  The robot is judged anew from there (the goal named
    in ``lost``), with no finding the loss caused, and a fault after it is still found."""

    def run() -> Conversation:
        lost = Conversation().begin().status(1, 1, "standby", 0)
        lost.goal(1, goal_id=1).ask(1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
        lost.result(1, SUCCEEDED, "completed", 1).status(1, 1, "standby", 1)
        lost.goal(2, goal_id=2).ask(2).feedback(2, "underway", 2).status(1, 2, "underway", 2)
        return lost.result(2, SUCCEEDED, "completed", 2)

    def without_goal_2(conversation: Conversation) -> Conversation:
        goals = [(time, message) for topic, _, time, message in conversation.messages if "send_goal" in topic]
        at = next(time for time, message in goals if message.info.sequence_number == 2)
        conversation.messages = [
            item
            for item in conversation.messages
            if not (item[0].endswith("send_goal/_service_event") and item[2] >= at)
        ]
        return conversation

    clean = without_goal_2(run().status(1, 1, "standby", 2))
    robot = _robot(check_bag(clean.write(tmp_path / "clean", StoragePlugin.MCAP)))
    assert robot.report.clean and not robot.partial, robot.report.findings
    first_feedback = next(
        time for topic, _, time, m in clean.messages if topic.endswith("feedback") and m.feedback.id == 2
    )
    assert robot.lost == ((first_feedback, "02" * 16),)
    done = check_command("--json", str(tmp_path / "clean"))
    rows = [json.loads(line) for line in done.stdout.splitlines()]
    assert done.returncode == 0 and [row for row in rows if row["type"] == "lost_request"] == [
        {"type": "lost_request", "file": str(tmp_path / "clean"), "robot": f"{FLEET}/{ROBOT}",
         "time": f"{first_feedback // SECOND}.{first_feedback % SECOND:09d}", "goal_uuid": "02" * 16}
    ], rows  # fmt: skip
    whole = run().status(1, 1, "standby", 2)
    assert _robot(check_bag(whole.write(tmp_path / "whole", StoragePlugin.MCAP))).lost == ()
    broken = without_goal_2(run().status(1, 2, "underway", 2))  # RUNNING after its answer
    at = broken.now
    robot = _robot(check_bag(broken.write(tmp_path / "broken", StoragePlugin.MCAP)))
    assert [(f.line, f.rule) for f in robot.report.findings] == [(at, "R2.2")], robot.report.findings


def test_a_goal_whose_response_the_bag_lost_is_read_as_accepted_from_its_feedback(tmp_path: Path) -> None:
    """A recorder on a lossy link lost a goal's response event (a writer's short history let it go
    before it was sent again), but holds the goal's request and its feedback and answer: a server
    feeds back and answers only a goal it accepted, so the goal is read as accepted there (said in
    ``unheard``), and nothing is found that the loss caused; a rejected goal's feedback still is."""

    def run(response: bool = True) -> Conversation:
        talk = Conversation().begin().status(1, 1, "standby", 0)
        if response:
            talk.goal(1, goal_id=1)
        else:  # the request event alone
            request = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Request")(
                goal_id=ros_uuid(1),
                goal=ros_type("rmf_task_msgs/action/DynamicEvent_Goal")(
                    dynamic_event_seq=1,
                    event_type=1,
                    category="go_to_place",
                    description='"pantry"',
                    id=1,
                    stubborn_period=0.0,
                ),
            )
            talk._event("send_goal", 1, 1, request=request)
        talk.ask(1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
        return talk.result(1, SUCCEEDED, "completed", 1).status(1, 1, "standby", 1)

    lossy = run(response=False)
    request = next(time for topic, _, time, _ in lossy.messages if "send_goal" in topic)
    robot = _robot(check_bag(lossy.write(tmp_path / "lossy", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    # accepted as it came (its feedback, within the records held, says so)
    assert robot.unheard == ((request, "01" * 16),) and robot.lost == ()
    assert _robot(check_bag(run().write(tmp_path / "whole", StoragePlugin.MCAP))).unheard == ()
    done = check_command(str(tmp_path / "lossy"))
    assert done.returncode == 0 and f"the bag lacks the response to goal {'01' * 16}" in done.stdout
    refused = Conversation().begin().status(1, 1, "standby", 0).goal(1, accepted=False, goal_id=1)
    robot = _robot(
        check_bag(refused.feedback(1, "underway", 1).write(tmp_path / "refused", StoragePlugin.MCAP))
    )
    assert [finding.code for finding in robot.report.findings] == ["feedback_not_running"]


def _request_alone(talk: Conversation, n: int, goal_id: int) -> Conversation:
    """Goal ``n``'s request event, its response event lost on the way to the recorder."""
    request = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Request")(
        goal_id=ros_uuid(n),
        goal=ros_type("rmf_task_msgs/action/DynamicEvent_Goal")(
            dynamic_event_seq=1, event_type=1, category="go_to_place", description='"pantry"', id=goal_id,
            stubborn_period=0.0,
        ),
    )  # fmt: skip
    return talk._event("send_goal", 1, n, request=request)


@pytest.mark.spec("R2.2", "R6.2")
def test_a_goal_whose_response_the_bag_lost_is_read_as_accepted_from_the_status_that_runs_its_child(
    tmp_path: Path,
) -> None:
    """The status that shows a child running can come before the feedback: a server runs only the
    child of a NEXT it accepted, so a goal whose response the bag lost is read as accepted there, where
    the bag holds the server's records of its goals.  A RUNNING status no pending goal explains is
    still found."""
    talk = _request_alone(Conversation().begin().status(1, 1, "standby", 0), 1, 1).status(1, 2, "underway", 1)
    running = talk.now
    talk.now += 11 * SECOND  # its feedback comes later than the records held: the status alone tells
    talk.ask(1).feedback(1, "underway", 1).result(1, SUCCEEDED, "completed", 1).status(1, 1, "standby", 1)
    robot = _robot(check_bag(talk.write(tmp_path / "lossy", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    assert robot.unheard == ((running, "01" * 16),)
    other = _request_alone(Conversation().begin().status(1, 1, "standby", 0), 1, 1)
    other.status(1, 2, "underway", 7)
    robot = _robot(check_bag(other.write(tmp_path / "other", StoragePlugin.MCAP)))
    assert [finding.code for finding in robot.report.findings] == ["status_mismatch"], robot.report.findings


@pytest.mark.spec("R4.6", "R2.2")
def test_the_goal_statuses_published_on_a_goals_acceptance_show_what_had_ended_by_then(
    tmp_path: Path,
) -> None:
    """The status of child 1's end and the goal statuses published with its answer lost (each topic
    keeps one message, and the next replaced it): the goal statuses the server published as it
    accepted the next NEXT, just after that NEXT's response, show goal 1 succeeded, so child 1 had
    ended before that acceptance; so do those that show the NEXT executing, sent before any feedback
    of it (a binding that starts a goal as it accepts it sends both arrays at once, and the
    second replaced the first: found leaving a status out of a 30% run's bag).  Where they show goal
    1 still executing, or come after the NEXT's feedback, the NEXT was accepted while its child ran
    (R4.6)."""

    def talk(first: int, second: int = ACCEPTED, *, late: bool = False, fed: bool = True) -> Conversation:
        run = Conversation().begin().status(1, 1, "standby", 0)
        run.goal(1, goal_id=1).goal_statuses((1, EXECUTING)).status(1, 2, "underway", 1)
        run.feedback(1, "underway", 1)
        run.now += 6 * SECOND  # child 1 ends here: its status and goal statuses never reach the bag
        run.goal(2, goal_id=2)
        if not late:
            run.goal_statuses((1, first), (2, second))
        run.status(1, 2, "underway", 2)
        if fed:  # else its feedback lost too
            run.feedback(2, "underway", 2)
        return run.goal_statuses((1, first), (2, second)) if late else run

    ended = {"ended": talk(SUCCEEDED), "started": talk(SUCCEEDED, EXECUTING)}
    ended["started, unheard"] = talk(SUCCEEDED, EXECUTING, fed=False)
    for name, run in ended.items():
        robot = _robot(check_bag(run.write(tmp_path / name, StoragePlugin.MCAP)))
        assert robot.report.clean, (name, robot.report.findings)
    busy = {"busy": talk(EXECUTING), "later": talk(SUCCEEDED, EXECUTING, late=True)}
    for name, run in busy.items():
        robot = _robot(check_bag(run.write(tmp_path / name, StoragePlugin.MCAP)))
        found = {(finding.rule, finding.code) for finding in robot.report.findings}
        assert ("R4.6", "accepted_busy") in found, (name, found)


@pytest.mark.spec("R10.5", "R10.3")
@pytest.mark.parametrize(
    ("shown", "return_code", "clean"),
    [(True, 1, True), (False, 3, True), (False, 1, False)],
    ids=["goal-statuses", "goal-terminated", "rejected"],
)
def test_a_cancel_the_server_showed_came_after_its_goals_end_is_a_cancel_of_an_answered_goal(
    tmp_path: Path, shown: bool, return_code: int, clean: bool
) -> None:
    """Found at 10% loss: child 1 ended and its goal was answered, but the status of that end and the
    answer never reached the bag in time; a client then cancelled goal 1 through the action, and the
    server refused it.  The server shows that child 1 had ended before the cancel came, by goal
    statuses sent before it that list goal 1 succeeded, or by the refusal's return code
    (``ERROR_GOAL_TERMINATED``: rcl_action found the goal terminated): the cancel is rightly refused
    (R10.5), and the answer the bag lacks is not owed.  Refused as an open goal's cancel
    (``ERROR_REJECTED``) with nothing showing the end, the refusal is the server's: R10.3."""
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.goal(1, goal_id=1).goal_statuses((1, EXECUTING)).status(1, 2, "underway", 1)
    run.ask(1).feedback(1, "underway", 1)
    run.now += 6 * SECOND  # child 1 ends here: its status and answer never reach the bag
    if shown:
        run.goal_statuses((1, SUCCEEDED))
    run.cancel(1, 1).cancel(1, 2, return_code=return_code)
    run.goal(2, goal_id=2).goal_statuses((1, SUCCEEDED), (2, ACCEPTED)).status(1, 2, "underway", 2)
    robot = _robot(check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP)))
    found = {(finding.rule, finding.code) for finding in robot.report.findings}
    assert found == (set() if clean else {("R10.3", "cancel_response")}), found


@pytest.mark.spec("R2.2", "R3.4")
@pytest.mark.parametrize("listed", [ACCEPTED, SUCCEEDED], ids=["accepted", "first-listed-ended"])
def test_goal_statuses_that_list_a_goal_the_bag_lacks_just_accepted_begin_the_judgement_anew(
    tmp_path: Path, listed: int
) -> None:
    """Found at 30% loss: child 1 ended and the status of that end was lost; the FINISHED that ended
    the run reached the recorder 12 s late, request and response (after the run's INACTIVE and the
    next run's begin: not judged).  Its only timely record was the goal statuses, listing goal 1
    succeeded and the FINISHED accepted.  Those goal statuses list a goal the bag lacks, just
    accepted: what it did comes after them, and the judgement begins anew at the next status (the
    INACTIVE), not with child 1 still held running (R2.2, then R3.4 at the next begin).  So do goal
    statuses that list it first ended (those of its acceptance replaced on the way: found leaving
    them out of a 30% run's bag, where they came 0.2 ms before the next)."""
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.goal(1, goal_id=1).goal_statuses((1, EXECUTING)).status(1, 2, "underway", 1)
    run.ask(1).feedback(1, "underway", 1)
    run.now += 6 * SECOND  # child 1 ends: the status of its end and its answer never reach the bag
    first = len(run.messages)
    run.goal(2, event_type=3)
    finished = run.messages[first:]  # the FINISHED's request and response, received 12 s late
    del run.messages[first:]
    run.goal_statuses((1, SUCCEEDED), (2, listed)).status(1, 0, "uninitialized", 0)
    run.now += SECOND // 2
    run.begin(seq=2).status(2, 1, "standby", 0)
    run.now += 12 * SECOND
    for topic, msgtype, sent, message in finished:
        run.at(topic, msgtype, message).sent_at(sent)
    run.status(2, 1, "standby", 0)
    for _, _, time, message in run.messages:  # the rest sent as they came (a recorder's publish times)
        run.sent.setdefault(id(message), time - 1_000_000)
    robot = _robot(check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    assert [channel for _, channel, _ in robot.late] == ["send_goal", "send_goal"]
    assert robot.lost == ((robot.lost[0][0], "02" * 16),)


def test_a_goal_the_goal_statuses_listed_and_its_feedback_then_named_begins_the_judgement_anew_once(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Goal statuses list goal 9 just accepted, a goal the bag lacks; its feedback comes before any
    status, and begins the judgement anew there.  The statuses that follow are no new beginning, even
    once the reader's books of the goals it has judged (the latest ``_CALLS``) let goal 9 go."""
    from dynevent.bags import reader

    monkeypatch.setattr(reader, "_CALLS", 3)
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.goal_statuses((9, ACCEPTED)).feedback(9, "underway", 1).status(1, 2, "underway", 1)
    run.result(9, SUCCEEDED, "completed", 1).status(1, 1, "standby", 1)
    for n in range(2, 7):
        run.goal(n, goal_id=n).status(1, 2, "underway", n).feedback(n, "underway", n)
        run.result(n, SUCCEEDED, "completed", n).status(1, 1, "standby", n)
    robot = _robot(check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP)))
    assert [uuid for _, uuid in robot.lost] == ["09" * 16], robot.lost


@pytest.mark.spec("R2.2")
def test_a_status_a_lossy_link_delivered_seconds_late_goes_by_the_servers_stamp(tmp_path: Path) -> None:
    """A recorder on a lossy link received the status that showed the child running seconds late, in
    one burst with the status of the child's end, which the server stamped before that burst came: the
    server stamps a status as it publishes it (R2.2), so each is judged where its stamp puts it (up to
    ``HOLD`` back), and the child's RUNNING is not read after its end."""

    def status(phase: int, text: str, stamp: int) -> Any:
        return ros_type("rmf_task_msgs/msg/DynamicEventStatus")(
            dynamic_event_seq=1, dynamic_state=phase, status=text, id=1, time=ros_time(stamp)
        )

    talk = Conversation().begin().status(1, 1, "standby", 0).goal(1, goal_id=1)
    started = talk.now
    talk.ask(1).feedback(1, "underway", 1)
    talk.now += 5 * SECOND  # the child runs; the status that showed it is on its way again
    burst = talk.now + SECOND // 10
    talk.at(STATUS_TOPIC, "rmf_task_msgs/msg/DynamicEventStatus", status(2, "underway", started))
    talk.at(STATUS_TOPIC, "rmf_task_msgs/msg/DynamicEventStatus", status(1, "standby", burst - SECOND // 20))
    talk.result(1, SUCCEEDED, "completed", 1)
    robot = _robot(check_bag(talk.write(tmp_path / "late", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings


@pytest.mark.spec("R11.1", "R5.2")
def test_a_finished_whose_answer_came_after_the_next_runs_begin_ended_its_run(tmp_path: Path) -> None:
    """A recorder on a lossy link received the answers of a run's last NEXT and of its FINISHED after
    the next run's begin (the client's records of them, stamped as they came): the INACTIVE status
    is the FINISHED's doing, which a binding starts as it accepts it, not a task cancel that left the
    FINISHED queued to lose the race at the next begin."""
    talk = Conversation().begin(seq=1).status(1, 1, "standby", 1)
    talk.goal(1, goal_id=2).status(1, 2, "underway", 2).ask(1).feedback(1, "underway", 2)
    talk.now += 5 * SECOND
    talk.status(1, 1, "standby", 2).goal(2, event_type=3).ask(2).status(1, 0, "uninitialized", 0)
    talk.now += SECOND // 2
    talk.begin(seq=2).status(2, 1, "standby", 1)
    talk.now += 2 * SECOND
    talk.result(1, SUCCEEDED, "completed", 2).result(2, SUCCEEDED, "completed", 1)
    robot = _robot(check_bag(talk.write(tmp_path / "late", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings


@pytest.mark.spec("R3.4", "R11.1")
def test_a_finished_whose_inactive_status_the_next_run_took_over_ended_its_run(tmp_path: Path) -> None:
    """The status topic keeps one message: a run's INACTIVE lost on the way to a recorder on a lossy
    link is taken over by the next run's status before it is sent again.  A begin that comes while a
    FINISHED of the active run is accepted and unanswered is read as after that FINISHED ended the
    run; without such a FINISHED, a begin while the run is active is still found (R3.4)."""

    def run(finished: bool) -> Conversation:
        talk = Conversation().begin(seq=1).status(1, 1, "standby", 1)
        talk.goal(1, goal_id=2).status(1, 2, "underway", 2).ask(1).feedback(1, "underway", 2)
        talk.result(1, SUCCEEDED, "completed", 2).status(1, 1, "standby", 2)
        if finished:
            talk.goal(2, event_type=3).ask(2)  # its INACTIVE never came
        talk.now += SECOND // 2
        talk.begin(seq=2).status(2, 1, "standby", 1)
        talk.now += 2 * SECOND
        return talk.result(2, SUCCEEDED, "completed", 1) if finished else talk

    robot = _robot(check_bag(run(True).write(tmp_path / "lost", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    robot = _robot(check_bag(run(False).write(tmp_path / "active", StoragePlugin.MCAP)))
    found = [finding.code for finding in robot.report.findings]
    assert found == ["begin_while_active"], robot.report.findings


@pytest.mark.spec("R19.1", "R8.2")
def test_feedback_sent_again_late_goes_before_its_answer_and_the_feedback_logged_after_it(
    tmp_path: Path,
) -> None:
    """A lossy link delivered a child's feedback again after the child's answer and after the next
    child's feedback, which the server logged later: it goes before both, by the earlier of the two
    places (read after the next child's feedback, it was feedback after its goal's answer)."""
    talk = Conversation().begin().status(1, 1, "standby", 1)
    talk.goal(1, goal_id=2).status(1, 2, "underway", 2).ask(1).feedback(1, "underway", 2, logs=(1,))
    sent = talk.now  # the feedback the link loses, and sends again later
    talk.status(1, 1, "standby", 2).result(1, SUCCEEDED, "completed", 2)
    talk.goal(2, goal_id=3).status(1, 2, "underway", 3).ask(2).feedback(2, "underway", 3, logs=(3,))
    talk.feedback(1, "underway", 2, logs=(2,))
    late = talk.messages[-1][3].feedback.logs[0]
    late.unix_millis_time = (sent + SECOND // 20) // 1_000_000  # logged before the child's end
    robot = _robot(check_bag(talk.write(tmp_path / "late", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings


def test_a_second_different_answer_is_found_and_the_same_answer_twice_is_not(tmp_path: Path) -> None:
    """A client that asks twice for a result gets the same answer twice: one answer.  A different
    second answer to the same goal is a double answer."""
    same = clean_run(lambda run: run.result(1, SUCCEEDED, "completed", 1))
    assert check_bag(same.write(tmp_path / "same", StoragePlugin.MCAP)).clean
    double = clean_run(lambda run: run.result(1, ABORTED, "failed", 1))
    report = check_bag(double.write(tmp_path / "double", StoragePlugin.MCAP))
    findings = _robot(report).report.findings
    assert findings and findings[0].rule == "R19.1", findings


@pytest.mark.spec("R2.2", "R19.3", "R6.2", "R3.1", "R7.1", "R7.3", "R19.1", "R19.2")
@pytest.mark.parametrize("storage", STORAGES, ids=["mcap", "sqlite3"])
def test_a_recording_without_goals_is_judged_from_its_topics_alone(
    tmp_path: Path, storage: StoragePlugin
) -> None:
    """Only the topics (begin, status, feedback, the goal statuses): the robot is a partial view,
    the absent channels named, and what the topics show by themselves judged; never a false finding."""
    report = check_bag(topics_alone(partial_clean_run()).write(tmp_path / "bag", storage))
    robot = _robot(report)
    assert robot.partial and report.clean, robot.report.findings
    assert robot.report.records == len(topics_alone(partial_clean_run()).messages)
    assert robot.absent == (
        "goals and their responses (send_goal introspection)", "answers (get_result introspection)"
    )  # fmt: skip
    statuses = clean_run()
    statuses.messages = [item for item in statuses.messages if item[0] == STATUS_TOPIC]
    robot = _robot(check_bag(statuses.write(tmp_path / "statuses", storage)))
    assert robot.partial and robot.report.clean and robot.channels == ("status",)


def _partial_cases() -> dict[str, tuple[Conversation, int, str, str]]:
    """Broken conversations as their topics show them: each (the conversation, the bag time and the
    rule and code of its one finding)."""
    cases = {}

    def case(name: str, run: Conversation, at: int, violation: tuple[str, str]) -> None:
        cases[name] = (topics_alone(run), at, *violation)

    def running(child: int = 1) -> Conversation:
        run = Conversation().begin().status(1, 1, "standby", 0).goal_statuses((1, EXECUTING))
        return run.feedback(1, "underway", child).status(1, 2, "underway", child)

    stale = running().status(1, 2, "completed", 1).goal_statuses((1, SUCCEEDED))
    at = stale.now
    stale.now += 2 * SECOND
    case(
        "stale_running", stale.goal_statuses((1, SUCCEEDED), (2, EXECUTING)), at, ("R2.2", "status_mismatch")
    )
    late = running().goal_statuses((1, SUCCEEDED)).status(1, 1, "standby", 1)
    late.now += 2 * SECOND
    case(
        "feedback_after_answer",
        late.feedback(1, "completed", 1),
        late.now,
        ("R19.1", "after_answer"),
    )
    two = running().goal_statuses((1, EXECUTING), (2, EXECUTING)).feedback(2, "underway", 2)
    case("two_children", two.feedback(1, "underway", 1), two.now, ("R19.2", "one_child"))
    again = running().goal_statuses((1, SUCCEEDED))
    case(
        "second_answer",
        again.goal_statuses((1, ABORTED)),
        again.now,
        ("R19.1", "goal_transition"),
    )
    logs = running().feedback(1, "underway", 1, logs=(1,))
    case("log_seq", logs.feedback(1, "underway", 1, logs=(1,)), logs.now, ("R7.3", "log_seq"))
    skips = running().feedback(1, "underway", 1, logs=(1,))  # within one child: one up (R7.3)
    case("log_seq_skips", skips.feedback(1, "underway", 1, logs=(3,)), skips.now, ("R7.3", "log_seq"))
    other = running()
    case("feedback_id", other.feedback(1, "underway", 2), other.now, ("R7.1", "feedback_id"))
    back = running(5)
    case("status_id", back.status(1, 1, "standby", 3), back.now, ("R6.2", "status_id"))
    ended = Conversation().begin().status(1, 1, "standby", 0).status(1, 0, "uninitialized", 0)
    case("reopened", ended.status(1, 1, "standby", 0), ended.now, ("R19.3", "status_seq"))
    older = Conversation().begin(2).status(2, 1, "standby", 0).status(2, 0, "uninitialized", 0)
    case("seq_backwards", older.status(1, 1, "standby", 0), older.now, ("R19.3", "status_seq"))
    rebegun = Conversation().begin(2).status(2, 1, "standby", 0).status(2, 0, "uninitialized", 0)
    case("begin_seq", rebegun.begin(2), rebegun.now, ("R3.1", "begin_seq"))
    inactive = Conversation().status(0, 0, "standby", 4)
    case("inactive", inactive, inactive.now, ("R2.2", "status_mismatch"))
    return cases


@pytest.mark.spec("R2.2", "R19.3", "R6.2", "R3.1", "R7.1", "R7.3", "R19.1", "R19.2")
@pytest.mark.parametrize("name", sorted(_partial_cases()))
def test_each_broken_conversation_a_partial_view_shows_is_found_at_its_bag_time_and_rule(
    tmp_path: Path, name: str
) -> None:
    run, at, rule, code = _partial_cases()[name]
    robot = _robot(check_bag(run.write(tmp_path / name, StoragePlugin.MCAP)))
    assert robot.partial
    assert [(finding.line, finding.rule, finding.code) for finding in robot.report.findings] == [
        (at, rule, code)
    ], robot.report.findings


def test_a_status_still_running_after_its_answer_is_labelled_as_d2_from_its_values(tmp_path: Path) -> None:
    """The status a partial view finds still showing an answered goal's child is D2 of
    docs/divergences.md, read from the finding's values: its words may change."""
    run, _, _, _ = _partial_cases()["stale_running"]
    (finding,) = _robot(check_bag(run.write(tmp_path / "stale", StoragePlugin.MCAP))).report.findings
    assert finding.detail == "answered" and label(finding) == "D2"
    assert label(attrs.evolve(finding, message="", expected="")) == "D2"


def test_what_a_partial_view_cannot_tell_is_no_finding(tmp_path: Path) -> None:
    """Statuses lost on the way (a topic keeps one message: a recorder may miss one overwritten at
    once), whole runs unseen, old begins a latched fleet-wide topic replays, a goal still EXECUTING
    when the bag ends, and a stale RUNNING the bag ends on: none is a finding."""
    run = Conversation()
    for seq in (1, 2, 3):  # the fleet-wide topic's latched begins, published long before
        message = Conversation().begin(seq, topic="/rmf/dynamic_event/begin").messages[0]
        replayed = message[3]
        replayed.start_time = ros_time(T0 - (10 - seq) * 60 * SECOND)
        run.at(message[0], message[1], replayed)
    run.status(3, 1, "standby", 0)  # its latched status
    run.goal_statuses((1, EXECUTING)).feedback(1, "underway", 4, logs=(3,)).status(3, 2, "underway", 4)
    run.goal_statuses((1, SUCCEEDED)).status(3, 0, "uninitialized", 0)  # the WAITING status was lost
    run.begin(5, topic="/rmf/dynamic_event/begin").status(5, 2, "underway", 9)  # run 4 unseen, a WAITING lost
    # between children the log seq may skip: entries made while no child runs are on no feedback (R7.3)
    run.goal_statuses((2, EXECUTING)).feedback(2, "underway", 9, logs=(20,)).feedback(
        2, "underway", 9, logs=(21,)
    )
    run.status(5, 2, "completed", 9).goal_statuses((2, SUCCEEDED))  # and the bag ends
    report = check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP))
    robot = _robot(report)
    assert robot.partial and report.clean, robot.report.findings


def test_the_fleet_wide_begin_topic_stands_for_a_robots_own(tmp_path: Path) -> None:
    run = clean_run()
    fleet_wide = Conversation().begin(topic="/rmf/dynamic_event/begin")
    run.messages[0] = (fleet_wide.messages[0][0], *run.messages[0][1:])
    report = check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP))
    assert report.clean and _robot(report).report.records == 12
    both = clean_run()
    both.messages.insert(1, (fleet_wide.messages[0][0], *both.messages[0][1:]))  # the same begin twice
    assert check_bag(both.write(tmp_path / "both", StoragePlugin.MCAP)).clean


@pytest.mark.spec("R3.3", "R2.2")
def test_a_run_whose_begin_the_bag_lacks_is_read_as_begun_from_its_first_status(tmp_path: Path) -> None:
    """Found at 10% loss across hosts: both copies of a run's begin (the robot's own topic's and the
    fleet's) lost for good on the way to the recorder.  The run's WAITING status, after the last run's
    INACTIVE one, is read as its begin's: the run is judged from there, said in ``unbegun`` and by
    ``check``.  A status no begin explains otherwise (a run skipped, another id) is still R2.2; a
    begin that comes after all is read, not judged again."""

    def second_run(first: int, status: str = "standby", event_id: int = 5) -> Conversation:
        run = clean_run()
        run.status(first, 1, status, event_id)  # its begin lost
        run.goal(3, seq=2, goal_id=6).feedback(3, "underway", 6).status(2, 2, "underway", 6)
        run.result(3, SUCCEEDED, "completed", 6).status(2, 1, "standby", 6)
        return run.goal(4, seq=2, event_type=3).result(4, SUCCEEDED, "completed", 5)

    run = second_run(2).status(2, 0, "uninitialized", 0)
    at = run.messages[next(i for i, item in enumerate(run.messages) if item[2] > clean_run().now)][2]
    robot = _robot(check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    assert robot.unbegun == ((at, 2),)
    done = check_command(str(tmp_path / "bag"))
    assert done.returncode == 0, done.stdout
    said = f"@ {at // SECOND}.{at % SECOND:09d}: the bag lacks the begin of run 2: read as begun"
    assert said in done.stdout
    rows = [json.loads(line) for line in check_command("--json", str(tmp_path / "bag")).stdout.splitlines()]
    assert [row for row in rows if row["type"] == "lost_begin"] == [
        {"type": "lost_begin", "file": str(tmp_path / "bag"), "robot": f"{FLEET}/{ROBOT}",
         "time": f"{at // SECOND}.{at % SECOND:09d}", "seq": 2}
    ]  # fmt: skip
    for name, broken in {"skipped": second_run(3), "running": second_run(2, "underway")}.items():
        robot = _robot(check_bag(broken.write(tmp_path / name, StoragePlugin.MCAP)))
        assert robot.unbegun == () and ("R2.2", at) in [(f.rule, f.line) for f in robot.report.findings]
    late = second_run(2)
    late.begin(2)  # received after the run's first goal had been judged
    late.status(2, 0, "uninitialized", 0)
    robot = _robot(check_bag(late.write(tmp_path / "late", StoragePlugin.MCAP)))
    assert robot.report.clean and robot.unbegun == ((at, 2),), robot.report.findings
    whole = clean_run().begin(2)
    whole.status(2, 1, "standby", 5)
    assert _robot(check_bag(whole.write(tmp_path / "whole", StoragePlugin.MCAP))).unbegun == ()


def test_bags_that_cannot_be_read_are_said_in_one_line(tmp_path: Path) -> None:
    with pytest.raises(BagError, match=r"nowhere: cannot read"):
        check_bag(tmp_path / "nowhere")
    (tmp_path / "empty").mkdir()
    with pytest.raises(
        BagError, match=r"empty: not a rosbag2 recording: a bag directory holds a metadata.yaml$"
    ):
        check_bag(tmp_path / "empty")
    garbage = tmp_path / "garbage.mcap"
    garbage.write_bytes(b"\x89MCAP0\r\n" + b"\x00" * 64)
    with pytest.raises(BagError, match=r"garbage.mcap: not a readable rosbag2 recording"):
        check_bag(garbage)
    whole = clean_run().write(tmp_path / "whole", StoragePlugin.MCAP)
    data = next(whole.glob("*.mcap")).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: len(data) // 2])
    with pytest.raises(BagError, match=r"cut.mcap: "):
        check_bag(cut)


def test_a_bag_of_yaml_aliases_is_refused_before_it_is_composed(tmp_path: Path) -> None:
    bag = clean_run().write(tmp_path / "laughs", StoragePlugin.MCAP)
    metadata = (bag / "metadata.yaml").read_text(encoding="utf-8")
    laughs = "\n".join(
        [f"a0: &a0 [{', '.join(['lol'] * 10)}]"]
        + [f"a{n}: &a{n} [{', '.join([f'*a{n - 1}'] * 10)}]" for n in range(1, 10)]
    )  # composed, ten to the tenth strings
    (bag / "metadata.yaml").write_text(laughs + "\n" + metadata, encoding="utf-8")
    with pytest.raises(
        BagError, match=r"laughs: metadata.yaml uses a YAML alias, which no rosbag2 recording does$"
    ):
        check_bag(bag)
    (bag / "metadata.yaml").write_text("x: " + "[" * 100 + "]" * 100 + "\n" + metadata, encoding="utf-8")
    with pytest.raises(BagError, match=r"metadata.yaml is nested deeper than 64 levels"):
        check_bag(bag)


@pytest.mark.parametrize("storage", STORAGES, ids=["mcap", "sqlite3"])
def test_a_bag_whose_files_are_not_regular_is_refused_without_reading(
    tmp_path: Path, storage: StoragePlugin
) -> None:
    bag = clean_run().write(tmp_path / "bag", storage)
    stored = next(path for path in bag.iterdir() if path.name != "metadata.yaml")
    stored.unlink()
    os.mkfifo(stored)  # a reader that opened it would wait for a writer for ever
    with pytest.raises(BagError, match=rf"{stored.name}: a FIFO, not a bag's storage file$"):
        check_bag(bag)
    (bag / "metadata.yaml").unlink()
    os.mkfifo(bag / "metadata.yaml")
    with pytest.raises(BagError, match=r"metadata.yaml .*is a FIFO, not a regular file$"):
        check_bag(bag)
    with pytest.raises(BagError, match=r"not a rosbag2 recording: a FIFO, not a bag's file$"):
        check_bag(stored)
    with pytest.raises(BagError, match=r"cannot read: File name too long$"):
        check_bag(tmp_path / ("x" * 5_000))


def test_a_db3_whose_time_is_text_is_a_located_error(tmp_path: Path) -> None:
    bag = clean_run().write(tmp_path / "bag", StoragePlugin.SQLITE3)
    database = next(bag.glob("*.db3"))
    with contextlib.closing(sqlite3.connect(database)) as connection:
        connection.execute("UPDATE messages SET timestamp = 'soon' WHERE id = 2")
        connection.commit()
    with pytest.raises(BagError, match=r"a message's time is 'soon', not nanoseconds$"):
        check_bag(bag)


def _correct_but_unusual() -> dict[str, Conversation]:
    """What a correct server may be recorded doing that an unwary judge would flag."""
    cases = {}
    # a NEXT's own id far above the run's (id policy goal: any id above the last, R4.12, R6.2)
    huge = Conversation().begin().status(1, 1, "standby", 5).goal_statuses((1, EXECUTING))
    cases["huge_id"] = huge.feedback(1, "underway", 2**64 - 1).status(1, 2, "underway", 2**64 - 1)
    # the next run's first child takes the id of the last run's, all within a second
    rerun = Conversation().begin(1).status(1, 1, "standby", 0).goal_statuses((1, EXECUTING))
    rerun.feedback(1, "underway", 1).status(1, 2, "underway", 1).goal_statuses((1, SUCCEEDED))
    rerun.status(1, 1, "standby", 1).goal_statuses((1, SUCCEEDED), (2, SUCCEEDED)).status(
        1, 0, "uninitialized", 0
    )
    rerun.begin(2).status(2, 1, "standby", 0).goal_statuses((1, SUCCEEDED), (2, SUCCEEDED), (3, EXECUTING))
    rerun.feedback(3, "underway", 1).status(2, 2, "underway", 1)
    rerun.now += SECOND // 2
    cases["next_run_same_child_id"] = rerun.feedback(3, "underway", 1)
    # a goal UUID taken again once the server let its result go (rclpy: after 15 minutes)
    reuse = Conversation().begin(1).status(1, 1, "standby", 0).goal_statuses((1, EXECUTING))
    reuse.feedback(1, "underway", 1).status(1, 2, "underway", 1).goal_statuses((1, SUCCEEDED))
    reuse.status(1, 1, "standby", 1)
    reuse.now += 901 * SECOND
    reuse.goal_statuses().goal_statuses((1, EXECUTING)).feedback(1, "underway", 2)
    cases["uuid_reuse"] = reuse.status(1, 2, "underway", 2)
    # a client on another host (its clock 0.9 s ahead) cancels the running goal through the action
    skewed = Conversation().begin().status(1, 1, "standby", 0).goal_statuses((1, EXECUTING))
    skewed.feedback(1, "underway", 1).status(1, 2, "underway", 1)
    skewed.cancel(1, 0, clock=9 * SECOND // 10).cancel(1, 3, clock=9 * SECOND // 10)
    skewed.goal_statuses((1, CANCELING)).feedback(1, "canceled", 1)
    skewed.goal_statuses((1, CANCELED)).status(1, 1, "standby", 1)
    skewed.goal_statuses((1, CANCELED), (2, EXECUTING)).feedback(2, "underway", 2).status(1, 2, "underway", 2)
    skewed.now += 3 * SECOND
    cases["skewed_cancel"] = skewed.feedback(2, "underway", 2)
    return cases


@pytest.mark.spec("R6.2", "R2.2", "R19.1", "R18.2")
@pytest.mark.parametrize("name", sorted(_correct_but_unusual()))
def test_what_a_correct_server_may_be_recorded_doing_is_no_finding(tmp_path: Path, name: str) -> None:
    run = _correct_but_unusual()[name]  # the topics, and a client's action-level cancel events
    robot = _robot(check_bag(run.write(tmp_path / name, StoragePlugin.MCAP)))
    assert robot.partial and robot.report.clean, robot.report.findings


def test_a_lost_request_keeps_the_goals_whose_responses_are_to_come(tmp_path: Path) -> None:
    """Client 1's NEXT A is lost to the recorder; client 2's NEXT B, sent as A starts, is refused busy
    after the loss is noticed: B's response finds its goal in the judgement begun anew."""
    goal = ros_type("rmf_task_msgs/action/DynamicEvent_Goal")(
        dynamic_event_seq=1,
        event_type=1,
        category="go_to_place",
        description='"pantry"',
        id=2,
        stubborn_period=0.0,
    )
    run = Conversation().begin().status(1, 1, "standby", 0)
    request = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Request")(goal_id=ros_uuid(2), goal=goal)
    run._event("send_goal", 0, 2, request=request)  # B sent (client 2's introspection)
    run.status(1, 2, "underway", 1).feedback(1, "underway", 1)  # A runs: its request was lost
    response = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Response")(
        accepted=False, stamp=ros_time(0)
    )
    run._event("send_goal", 3, 2, response=response)  # B refused
    run.now += 2 * SECOND
    robot = _robot(check_bag(run.status(1, 2, "underway", 1).write(tmp_path / "bag", StoragePlugin.MCAP)))
    assert robot.report.clean and [uuid for _, uuid in robot.lost] == ["01" * 16], robot


@pytest.mark.spec("R2.2")
def test_a_lost_request_whose_last_status_names_an_ended_child_is_judged_anew_from_the_next(
    tmp_path: Path,
) -> None:
    """Found at 30% loss across hosts: the recorder lost the status of child 13's end, NEXT 13's answer
    and the request of the NEXT that ran child 14.  Child 14's feedback shows the loss; the status
    before it shows child 13 running, which had ended: judged anew from it, every status of child 14
    read as wrong (R2.2).  The judgement begins anew at the next status instead (child 14's).  No loss
    of one or two of the run's messages is a finding either."""

    def run() -> Conversation:
        conversation = Conversation().begin().status(1, 1, "standby", 0)
        conversation.goal(1, goal_id=13).goal_statuses((1, EXECUTING)).ask(1)
        conversation.feedback(1, "underway", 13).status(1, 2, "underway", 13).feedback(1, "underway", 13)
        conversation.status(1, 1, "standby", 13).goal_statuses((1, SUCCEEDED))
        conversation.result(1, SUCCEEDED, "completed", 13)
        conversation.goal(2, goal_id=14).goal_statuses((1, SUCCEEDED), (2, EXECUTING)).ask(2)
        conversation.feedback(2, "underway", 14).status(1, 2, "underway", 14).feedback(2, "underway", 14)
        conversation.status(1, 1, "standby", 14).goal_statuses((1, SUCCEEDED), (2, SUCCEEDED))
        return conversation.result(2, SUCCEEDED, "completed", 14).status(1, 1, "standby", 14)

    def lost(topic: str, message: Any) -> bool:
        if topic == STATUS_TOPIC:
            return (message.id, message.status) == (13, "standby")  # child 13's end
        if topic.endswith("get_result/_service_event"):
            return bool(message.response) and message.response[0].result.id == 13  # its answer
        request = topic.endswith("send_goal/_service_event") and message.info.event_type == 1
        return request and message.info.sequence_number == 2  # NEXT 14's request

    whole = run()
    assert _robot(check_bag(whole.write(tmp_path / "whole", StoragePlugin.MCAP))).report.clean
    # every loss of one or two of its messages (the begin and the first status kept) is no finding
    for count in (1, 2):
        for lost_ones in itertools.combinations(range(2, len(whole.messages)), count):
            some = run()
            some.messages = [item for at, item in enumerate(some.messages) if at not in lost_ones]
            name = "-".join(map(str, lost_ones))
            robot = _robot(check_bag(some.write(tmp_path / name, StoragePlugin.MCAP)))
            assert robot.report.clean, (lost_ones, robot.report.findings)
    lossy = run()
    lossy.messages = [item for item in lossy.messages if not lost(item[0], item[3])]
    assert len(lossy.messages) == len(whole.messages) - 3
    robot = _robot(check_bag(lossy.write(tmp_path / "lossy", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    assert [uuid for _, uuid in robot.lost] == ["02" * 16], robot.lost


@pytest.mark.spec("R10.3", "R10.1", "R2.2")
def test_a_cancelled_next_whose_start_was_lost_is_read_as_started_from_the_status_naming_its_child(
    tmp_path: Path,
) -> None:
    """Found leaving out a message of a 30% run's bag that a status topic's next message replaces: an
    action-level cancel of a NEXT sent as soon as it is accepted; the server had started it, and its
    start's feedback and RUNNING status were lost, its answer came many records late.  The WAITING
    status of its child's end names the child (id 1, above every id used): the NEXT had started when
    the cancel came (R10.3), not queued (R10.1).  A WAITING status naming no new child still leaves
    it queued: the answer must then say it never ran."""

    def run(child: int, final: str) -> Conversation:
        talk = Conversation().begin().status(1, 1, "standby", 0).goal(1, goal_id=1)
        talk.cancel(1, 1).cancel(1, 2)  # its start's feedback and RUNNING status lost
        talk.status(1, 1, "standby", child)
        talk.goal(2, event_type=3)  # FINISHED, accepted: two records before the NEXT's late answer
        talk.result(1, CANCELED, final, child).result(2, SUCCEEDED, "completed", 0)
        return talk.status(1, 0, "uninitialized", 0)

    robot = _robot(check_bag(run(1, "canceled").write(tmp_path / "started", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings
    robot = _robot(check_bag(run(0, "canceled").write(tmp_path / "queued", StoragePlugin.MCAP)))
    assert "R10.1" in [finding.rule for finding in robot.report.findings], robot.report.findings


@pytest.mark.spec("R4.11")
def test_a_refused_goal_whose_response_was_lost_is_not_read_as_the_listed_goal_a_status_runs(
    tmp_path: Path,
) -> None:
    """Found by dropping messages of a 30% run's bag: a NEXT refused for its NaN stubborn period, its
    response lost, and a later NEXT naming the same id, its response still to come, whose child the
    status shows running.  The server lists only goals it accepted: the later one, which the goal
    statuses hold, is the goal the status shows started, not the refused one (read as accepted, R4.11)."""

    def next_goal(run: Conversation, n: int, stubborn: float, accepted: bool | None) -> None:
        goal = ros_type("rmf_task_msgs/action/DynamicEvent_Goal")(
            dynamic_event_seq=1, event_type=1, category="go_to_place", description='"pantry"', id=2,
            stubborn_period=stubborn,
        )  # fmt: skip
        request = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Request")(
            goal_id=ros_uuid(n), goal=goal
        )
        run._event("send_goal", 1, n, request=request)
        if accepted is not None:
            response = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Response")(
                accepted=accepted, stamp=ros_time(0)
            )
            run._event("send_goal", 2, n, response=response)

    for lost in (False, True):
        run = Conversation().begin().status(1, 1, "standby", 0)
        next_goal(run, 1, float("nan"), None if lost else False)
        run.now += 9 * SECOND
        next_goal(run, 2, 0.0, None)  # its response comes after its child's start
        run.goal_statuses((2, ACCEPTED)).status(1, 2, "underway", 2).goal_statuses((2, EXECUTING))
        run.feedback(2, "underway", 2)
        response = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Response")(
            accepted=True, stamp=ros_time(0)
        )
        run._event("send_goal", 2, 2, response=response)
        run.ask(2).status(1, 1, "standby", 2).goal_statuses((2, SUCCEEDED))
        run.result(2, SUCCEEDED, "completed", 2)
        run.now += 2 * SECOND
        robot = _robot(
            check_bag(run.status(1, 1, "standby", 2).write(tmp_path / str(lost), StoragePlugin.MCAP))
        )
        assert robot.report.clean, (lost, robot.report.findings)


def test_introspection_without_contents_is_a_partial_view(tmp_path: Path) -> None:
    """send_goal introspection in METADATA mode records events without the goals: a partial view."""
    run = topics_alone(partial_clean_run())
    for call in (1, 2):
        run._event("send_goal", 1, call)
    robot = _robot(check_bag(run.write(tmp_path / "bag", StoragePlugin.MCAP)))
    assert robot.partial and robot.report.clean and robot.lost == (), robot
    assert (
        robot.absent[0]
        == "goals and their responses (send_goal introspection): recorded without contents (METADATA)"
    )


def test_other_readers_decode_a_bag_from_the_definitions_it_holds(tmp_path: Path) -> None:
    """The definitions dynevent writes beside each topic (what ``dynevent record`` writes) are enough
    for a reader that has never seen the interface files: rosbags decodes every topic from them
    alone, and Foxglove's ROS 2 decoder (ROS's own parser) every topic whose type a ``.msg`` can
    name, to the same values."""
    from dynevent.bags.reader import message_definition
    from support.bag_readers import read_with_foxglove, read_with_rosbags

    run = topics_alone(partial_clean_run())
    run.goal(9, goal_id=9).result(9, SUCCEEDED, "completed", 9)
    bag = tmp_path / "bag"
    with Writer(bag, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        connections: dict[str, Any] = {}
        for topic, msgtype, time, message in run.messages:
            if topic not in connections:
                definition = message_definition(msgtype)
                connections[topic] = writer.add_connection(topic, msgtype, msgdef=definition, rihs01=UNHASHED)
            writer.write(connections[topic], time, STORE.serialize_cdr(message, msgtype))
    sent: dict[str, list[Any]] = {}
    for topic, _, _, message in run.messages:
        sent.setdefault(topic, []).append(message)
    by_rosbags = read_with_rosbags(bag)
    assert {topic: len(items) for topic, items in by_rosbags.items()} == {t: len(m) for t, m in sent.items()}
    assert [m.id for m in by_rosbags[STATUS_TOPIC]] == [m.id for m in sent[STATUS_TOPIC]]
    by_foxglove, skipped = read_with_foxglove(bag)
    assert set(by_foxglove) == {STATUS_TOPIC, BEGIN_TOPIC, f"{ACTION}/_action/status"}, set(by_foxglove)
    assert sum(skipped.values()) + sum(map(len, by_foxglove.values())) == len(run.messages)
    for topic, items in by_foxglove.items():
        assert len(items) == len(sent[topic]), topic
    assert [(m.dynamic_event_seq, m.dynamic_state, m.status, m.id) for m in by_foxglove[STATUS_TOPIC]] == [
        (m.dynamic_event_seq, m.dynamic_state, m.status, m.id) for m in sent[STATUS_TOPIC]
    ]
    statuses = by_foxglove[f"{ACTION}/_action/status"]
    assert [[bytes(item.goal_info.goal_id.uuid) for item in m.status_list] for m in statuses] == [
        [bytes(item.goal_info.goal_id.uuid) for item in m.status_list]
        for m in sent[f"{ACTION}/_action/status"]
    ]


def test_a_bag_of_other_topics_has_no_robot(tmp_path: Path) -> None:
    other = Conversation()
    other.at("/chatter", "builtin_interfaces/msg/Time", ros_time(5))
    report = check_bag(other.write(tmp_path / "bag", StoragePlugin.MCAP))
    assert report.robots == () and report.messages == 0 and report.other == 1


def _received(run: Conversation, order: list[int]) -> None:
    """The messages ``order`` names, received in that order: each takes the bag time of the place it
    lands in, and keeps the stamps the server put on it."""
    times = [run.messages[index][2] for index in sorted(order)]
    moved = [run.messages[index] for index in order]
    for place, (topic, msgtype, _, message), time in zip(sorted(order), moved, times, strict=True):
        run.messages[place] = (topic, msgtype, time, message)


def _passed(monkeypatch: pytest.MonkeyPatch, path: Path) -> list[str]:
    """The kinds of the records check_bag passes to the observer, in order."""
    from dynevent.bags import reader as bags

    kinds: list[str] = []
    push = bags.Checker.push
    monkeypatch.setattr(
        bags.Checker, "push", lambda self, record: (kinds.append(record.kind), push(self, record))
    )
    check_bag(path)
    return kinds


def test_the_servers_stamps_order_what_a_recorder_received_out_of_order(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A recorder receives each topic in order, not the topics in order with one another: here the
    INACTIVE status that FINISHED's start published comes before FINISHED's request, response and
    answer events.  The stamps the server put on them (within ``SKEW`` of the bag time) give back its
    order; stamps of another clock (simulated time) are not used, and the bag's order stands."""
    run = clean_run()
    _received(run, [*range(9), 13, 9, 10, 11, 12])
    tail = ["goal", "goal_response", "result", "status"]
    assert _passed(monkeypatch, run.write(tmp_path / "bag", StoragePlugin.MCAP))[-4:] == tail
    assert check_bag(tmp_path / "bag").clean
    run.messages[9][3].time = ros_time(5 * SECOND)  # the INACTIVE status, stamped by another clock
    passed = _passed(monkeypatch, run.write(tmp_path / "unstamped", StoragePlugin.MCAP))
    assert passed[-4:] == ["goal", "status", "goal_response", "result"]  # the status at its bag time


def test_a_goal_goes_before_what_names_it_and_a_response_needs_its_goal(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Two hosts' clocks: the NEXT's request event is stamped after its response and the feedback;
    the goal goes first, then its response by its own stamp, as the server sent them.  A response
    whose request the bag lost is left out, never unreadable."""
    run = clean_run()
    _received(run, [0, 1, 2, 4, 3, 5])  # the request's stamp after the feedback's
    run.messages[2][3].info.stamp = ros_time(run.messages[3][2] + SECOND // 20)
    passed = _passed(monkeypatch, run.write(tmp_path / "skewed", StoragePlugin.MCAP))
    assert passed[:5] == ["begin", "status", "goal", "goal_response", "feedback"], passed
    lost = clean_run()
    del lost.messages[2]  # the NEXT's request event
    report = check_bag(lost.write(tmp_path / "lost", StoragePlugin.MCAP))
    assert _robot(report).report is not None  # judged: a finding where its child is unexplained


def test_a_goal_received_after_its_starts_status_and_feedback_goes_before_them(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Seen over DDS under load: the NEXT's request and response events reach the recorder after the
    RUNNING status and the feedback its start published.  The request goes by its own stamp, before
    the status, though a record naming it (the feedback) was received first."""
    run = clean_run()
    _received(run, [0, 1, 5, 4, 2, 3])  # the status, the feedback, then the request and response
    at = run.messages[2][2]  # the status's bag time: the server stamped the three just before it
    run.messages[4][3].info.stamp, run.messages[5][3].info.stamp = (
        ros_time(at - 3_000_000),
        ros_time(at - 2_000_000),
    )
    run.messages[2][3].time = ros_time(at - 1_000_000)
    passed = _passed(monkeypatch, run.write(tmp_path / "bag", StoragePlugin.MCAP))
    assert passed[:3] == ["begin", "status", "goal"], passed
    assert check_bag(tmp_path / "bag").clean


def test_a_goal_whose_servers_records_a_lossy_link_delivered_seconds_late_goes_by_the_servers_stamps(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Seen across hosts at 10% loss: the server's own records of a NEXT's request and response (its
    introspection) reached the recorder three seconds late, after the RUNNING status and the feedback
    the goal's start published.  The server stamps them as it sends them, as it stamps a status: each
    goes by its stamp, up to ``HOLD`` back, and the status is not read as a child no goal started."""
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.now += 5 * SECOND
    run.goal(1, goal_id=1).ask(1).status(1, 2, "underway", 1).feedback(1, "underway", 1)
    run.now += 2 * SECOND
    run.feedback(1, "underway", 1).status(1, 1, "standby", 1).result(1, SUCCEEDED, "completed", 1)
    late = 3 * SECOND
    goal_events = run.messages[2:4]  # the request and the response, as the server stamped them
    rest = run.messages[4:7]
    run.messages[2:7] = [
        *rest,
        *[(topic, kind, time + late, event) for topic, kind, time, event in goal_events],
    ]
    passed = _passed(monkeypatch, run.write(tmp_path / "bag", StoragePlugin.MCAP))
    assert passed[:4] == ["begin", "status", "goal", "goal_response"], passed
    assert check_bag(tmp_path / "bag").clean, _robot(check_bag(tmp_path / "bag")).report.findings


def test_feedback_received_between_its_childs_end_and_its_answer_is_read_as_sent_before_both(
    tmp_path: Path,
) -> None:
    """Seen over DDS under load: the child's last feedback reached the recorder after the WAITING
    status of the child's end and before the answer, which the server sent before that status.  It
    was sent before both: read so, no finding."""
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.goal(1, goal_id=1).ask(1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
    run.status(1, 1, "standby", 1)
    ended = run.now  # the step that answered the goal and published this status
    run.feedback(1, "underway", 1).result(1, SUCCEEDED, "completed", 1)
    run.messages[-1][3].info.stamp = ros_time(ended + 1_000_000)  # the answer, sent in that step
    run.now += 2 * SECOND
    robot = _robot(check_bag(run.status(1, 1, "standby", 1).write(tmp_path / "bag", StoragePlugin.MCAP)))
    assert robot.report.clean, robot.report.findings


def test_feedback_received_after_its_goals_answer_is_read_as_sent_before_it(tmp_path: Path) -> None:
    """The feedback topic and the result service are two channels: a recorder may receive a goal's
    last feedback after its answer, and cannot tell that from late sending; within ``HOLD`` (a lossy
    link sends a lost message again seconds later) it is read as sent before the answer.  Longer
    after the answer it is a finding (R19.1)."""
    late = clean_run(lambda run: run.feedback(1, "underway", 1))
    assert check_bag(late.write(tmp_path / "late", StoragePlugin.MCAP)).clean
    lossy = clean_run(lambda run: (setattr(run, "now", run.now + 3 * SECOND), run.feedback(1, "underway", 1)))
    assert check_bag(lossy.write(tmp_path / "lossy", StoragePlugin.MCAP)).clean
    later = clean_run(
        lambda run: (setattr(run, "now", run.now + HOLD + 2 * SECOND), run.feedback(1, "underway", 1))
    )
    findings = _robot(check_bag(later.write(tmp_path / "later", StoragePlugin.MCAP))).report.findings
    assert [(finding.rule, finding.code) for finding in findings][:1] == [("R19.1", "after_answer")], findings


def test_feedback_a_lossy_link_delivered_out_of_order_goes_by_its_logs_time(tmp_path: Path) -> None:
    """A recorder on a lossy link received a child's feedback out of the order it was sent (one lost,
    then sent again seconds later, after the next): the time of its log entries, the server's, puts it
    back, and the robot's log seqs go up as they did."""

    def run() -> Conversation:
        talk = Conversation().begin().status(1, 1, "standby", 0)
        talk.goal(1, goal_id=1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
        talk.feedback(1, "underway", 1, logs=(1,)).feedback(1, "underway", 1, logs=(2,))
        talk.feedback(1, "underway", 1, logs=(3,))
        talk.result(1, SUCCEEDED, "completed", 1).status(1, 1, "standby", 1)
        return talk

    assert check_bag(run().write(tmp_path / "clean", StoragePlugin.MCAP)).clean
    lossy = run()
    _received(lossy, [*range(6), 7, 8, 6, *range(9, len(lossy.messages))])  # log 1 came after log 3
    assert check_bag(lossy.write(tmp_path / "lossy", StoragePlugin.MCAP)).clean


@pytest.mark.spec("R7.3")
def test_a_log_seq_that_skips_where_the_feedback_writers_numbers_show_a_feedback_lost_is_no_finding(
    tmp_path: Path,
) -> None:
    """Found at 30% loss across hosts: a feedback that carried log seq 33 never reached the recorder
    (a reliable topic keeps its last messages only), so seq 34 came after 32.  ``dynevent record``
    writes each message's publication number (MCAP's sequence): the feedback writer's numbers show
    a message lost between the two, and the skip is no finding.  Where the numbers run on without a
    gap (the server skipped), or the bag holds none, it is still one (R7.3)."""

    def run(numbers: tuple[int, ...]) -> Conversation:
        talk = Conversation().begin().status(1, 1, "standby", 0)
        talk.goal(1, goal_id=1).feedback(1, "underway", 1).numbered(numbers[0])
        talk.status(1, 2, "underway", 1)
        for logs, number in zip(((1,), (2,), (4,)), numbers[1:], strict=True):
            talk.feedback(1, "underway", 1, logs=logs)
            if number:
                talk.numbered(number)
        talk.result(1, SUCCEEDED, "completed", 1).status(1, 1, "standby", 1)
        return talk

    lost = run((7, 8, 9, 11))  # number 10, which carried log 3, never came
    assert check_bag(lost.write(tmp_path / "lost", StoragePlugin.MCAP)).clean
    for name, numbers in (("skipped", (7, 8, 9, 10)), ("unnumbered", (0, 0, 0, 0))):
        findings = _robot(check_bag(run(numbers).write(tmp_path / name, StoragePlugin.MCAP))).report.findings
        assert [(finding.rule, finding.code) for finding in findings] == [("R7.3", "log_seq")], (
            name,
            findings,
        )


#: A bag recorded across hosts at 10% loss (tests/data/lossy/README.md): a child's start feedback and
#: its last log's feedback, lost on the recorder's link, came again after the status of the child's end.
LATE_FEEDBACK = Path(__file__).resolve().parents[1] / "data" / "lossy" / "late_feedback"


def _copy(source: Path, target: Path, sent_at: Callable[[str, int, int | None], int | None]) -> Path:
    """The bag at ``source`` written again at ``target`` by the recorder's writer, each message's
    publish time ``sent_at(topic, bag time, its publish time)``."""
    from rosbags.rosbag2 import Reader

    from dynevent.bags.sent import open_writer, publish_times

    sent = publish_times(str(source), sorted(source.glob("*.mcap")))
    with Reader(source) as reader, open_writer(target) as writer:
        added = {
            item.id: writer.add_connection(
                item.topic, item.msgtype, msgdef=item.msgdef.data, rihs01=item.digest or UNHASHED
            )
            for item in reader.connections
        }
        for connection, time, raw in reader.messages():
            was = sent.get((connection.topic, time, hash(raw)))
            then = sent_at(connection.topic, time, None if was is None else was.time)
            writer.write_sent(added[connection.id], time, then, raw)
    return target


@pytest.mark.spec("R8.2")
def test_feedback_a_lossy_link_delivered_after_its_childs_end_goes_by_when_sent(tmp_path: Path) -> None:
    """A bag from ``dynevent record`` holds when each message was sent (MCAP's publish time): the
    feedback a lossy link delivered after its child's end (and after the goal status that showed the
    goal succeeded) is read where it was sent, and no finding.  The same bag without publish times
    cannot tell it from feedback sent after the end (R8.2); feedback sent after the end is found."""
    assert check_bag(LATE_FEEDBACK).clean
    unknown = check_bag(_copy(LATE_FEEDBACK, tmp_path / "unknown", lambda topic, time, sent: None))
    late = _copy(LATE_FEEDBACK, tmp_path / "late", lambda topic, time, sent: None if sent is None else time)
    for report in (unknown, check_bag(late)):
        robot = next(robot for robot in report.robots if robot.robot == "probed")
        findings = [(finding.rule, finding.code) for finding in robot.report.findings]
        assert findings == [("R8.2", "feedback_not_running")] * 2, robot.report.findings


@pytest.mark.spec("R8.2")
def test_a_message_sent_further_back_than_the_reader_holds_is_said_late_not_judged(tmp_path: Path) -> None:
    """The two feedback messages of the lossy bag, had the link delivered them 13 s after they were
    sent (more than HOLD: a loaded host, as a busy machine's loss run showed), came after the
    records the server sent later had been judged: neither is judged in place (two R8.2 findings
    were), and each is said, with its bag time and how late it came.  The same messages 6 s late
    (within HOLD) are judged where they were sent, and none is late."""
    from dynevent.bags.reader import HOLD
    from dynevent.tools.check import bag_records, format_bag

    late_by = HOLD + 3_000_000_000

    def sent_at(topic: str, time: int, sent: int | None) -> int | None:
        """The two late feedback messages 13 s before their bag time; every other message but feedback
        a millisecond (the other feedback messages keep none: a lossy link delayed some of them, by
        how much the bag does not say)."""
        if sent is not None:
            return time - late_by
        return None if topic.endswith("/_action/feedback") else time - 1_000_000

    bag = _copy(LATE_FEEDBACK, tmp_path / "later", sent_at)
    report = check_bag(bag)
    robot = next(robot for robot in report.robots if robot.robot == "probed")
    assert report.clean, robot.report.findings
    assert [(channel, time - sent) for time, channel, sent in robot.late] == [("feedback", late_by)] * 2
    assert format_bag(report).count("a feedback message sent 13.0 s before it was received") == 2
    rows = [row for row in bag_records(report) if row["type"] == "late"]
    assert [(row["robot"], row["channel"]) for row in rows] == [("tinyRobot/probed", "feedback")] * 2
    assert not next(robot for robot in check_bag(LATE_FEEDBACK).robots if robot.robot == "probed").late


#: A bag recorded across hosts at 10% loss with a busy loop on one core (tests/data/lossy/README.md).
LOADED = LATE_FEEDBACK.parent / "loaded"


@pytest.mark.spec("R4.13", "R9.1")
def test_a_response_received_before_its_request_is_read_with_it() -> None:
    """A CANCEL whose response event the recorder received before its request's (a lossy link
    delivered the request 12 ms late), and whose next record is its answer, seconds later, after
    the status of the cancelled child's end: the response is paired with its request when that
    comes, and read where it was sent, while the child ran (dropped, the goal was read as accepted
    only at its answer, where no child runs: R4.13 and R9.1 findings).  The bag's one message of the
    server's received more than HOLD after it was sent is said, not judged."""
    from dynevent.bags.reader import bag_records

    report = check_bag(LOADED)
    robot = next(robot for robot in report.robots if robot.robot == "probed")
    assert report.clean, robot.report.findings
    assert robot.unheard == ()
    records = bag_records(str(LOADED))[("tinyRobot", "probed")]
    cancel = "0457dd7075b4d1aa8e11102da160678f"
    kinds = [(record.kind, record.time) for record in records if record.goal_uuid == cancel]
    assert kinds == [
        ("goal", 1795877466405981199),
        ("goal_response", 1795877466394982832),
        ("result", 1795877469381464175),
    ]
    assert [(time, channel) for time, channel, _ in robot.late] == [(1795877397189648399, "get_result")]


@pytest.mark.spec("R7.3", "R4.6", "R2.2", "R5.2")
def test_a_response_whose_request_came_later_is_paired_and_a_skip_the_late_feedback_fills_is_none() -> None:
    """A bag recorded at 30% loss beside a busy loop (tests/data/lossy/README.md): a get_result
    response event received before its request's is paired with it when the request comes, and is
    the answer of its goal, at its own time (the status of that child's end was lost for good); two
    feedback messages received 14 s and 15 s late are said and not judged, and the seq skip they
    explain (entries 76 and 77 came late) is no finding.  Against the correct server: nothing."""
    from dynevent.bags.reader import bag_records

    report = check_bag(LOADED.parent / "thirty")
    robot = next(robot for robot in report.robots if robot.robot == "probed")
    assert report.clean, robot.report.findings
    assert [(channel, round((time - sent) / 1e9)) for time, channel, sent in robot.late] == [
        ("feedback", 14),
        ("feedback", 15),
    ]
    records = bag_records(str(LOADED.parent / "thirty"))[("tinyRobot", "probed")]
    answers = [
        record for record in records if record.kind == "result" and record.goal_uuid.startswith("3041a1")
    ]
    assert [(record.time, record.message.status) for record in answers] == [
        (1795878107247297911, "completed")
    ]


@pytest.mark.spec("R4.6", "R2.2", "R5.2", "R7.3")
@pytest.mark.parametrize(
    "name",
    [
        "late_feedback",
        "loaded",
        "thirty",
        "ended_by_goal_status",
        "delayed",
        "late_begin",
        "late_cancel_request",
        "late_run_begin",
        "answer_after_next",
        "begin_on_one_topic",
        "finished_answered_late",
        "finished_response_late",
        "response_after_cut",
        "cancel_request_late",
        "ended_at_acceptance",
        "cancelled_end_dropped",
        "refused_response_dropped",
        "cancel_at_acceptance",
        "requests_late",
        "replaced_statuses",
    ],
)
def test_every_lossy_recording_of_a_correct_server_is_clean(name: str) -> None:
    """The recordings of tests/data/lossy (each README section says what the link did in it): check
    finds nothing against the correct server.  In ``ended_by_goal_status`` the child's end is read
    from the goal statuses that showed its goal succeeded (its status and answer were lost); in
    ``delayed`` a feedback received 10 s after it was sent goes where it was sent; in ``late_begin``
    a begin received 3 s late goes by when it was sent; in ``late_cancel_request`` a cancel's request
    received 3 s late, after its goal's answer, goes by the server's stamp, before it; in
    ``late_run_begin`` a run's begin received 14 s late is said, and its run's status read without it
    is no finding, and a CANCEL whose events came after its child's end and answer is read before
    them; in ``begin_on_one_topic`` a run's begin that came on the fleet's begin topic alone, the
    robot's own copy lost, opens the run; in ``finished_answered_late`` a FINISHED of a run whose own
    id the judgement did not know (it began anew mid-run) is answered after the next run's begin,
    and its result's id is not held to the new run's; in ``finished_response_late`` a FINISHED whose
    response came 12 s late, after the next run's begin, is read as accepted where the goal statuses
    listed it; in ``response_after_cut`` the judgement begun anew at a goal whose request the bag
    lost takes first the request of a CANCEL whose response it had not judged yet; in
    ``cancel_request_late`` a NEXT answered ``canceled`` by an action-level cancel whose events came
    27 s late is no finding; in ``ended_at_acceptance`` a goal the goal statuses published on the next
    NEXT's acceptance show succeeded (its status and answer lost) ended before that acceptance; in
    ``cancelled_end_dropped`` a child a CANCEL stopped, the status of its end lost, is read as stopped
    by that CANCEL's start; in ``refused_response_dropped`` a NEXT refused, its response lost, is not
    read as accepted from the status of a later NEXT's child of the same id; ``cancel_at_acceptance``,
    ``requests_late`` and ``replaced_statuses`` are as they came (tests/bags/test_losses.py leaves
    messages out of them)."""
    report = check_bag(LOADED.parent / name)
    assert report.clean, [robot.report.findings for robot in report.robots]


def test_every_recording_of_tests_data_lossy_is_judged_and_said_in_its_readme() -> None:
    """A recording added to tests/data/lossy is held to the test above, and its README says what the
    link did in it."""
    folders = sorted(path.name for path in LOADED.parent.iterdir() if path.is_dir())
    marks = test_every_lossy_recording_of_a_correct_server_is_clean.pytestmark  # type: ignore[attr-defined]
    judged = next(mark.args[1] for mark in marks if mark.name == "parametrize")
    assert sorted(judged) == folders
    readme = (LOADED.parent / "README.md").read_text()
    assert [name for name in folders if f"`{name}/`" not in readme and f"## {name}" not in readme] == []


def test_the_recorders_writer_keeps_each_messages_publish_time_beside_its_log_time(tmp_path: Path) -> None:
    """What ``dynevent record`` writes: an MCAP bag whose message records hold the publish time given
    (across chunks: more than one chunk's worth of messages) and the publication number given as the
    record's sequence, saying so in its metadata, which rosbags and other readers still read as a
    bag, and whose messages without a publish time hold the log time twice.  The numbers are read
    only where asked (the metadata says so)."""
    from rosbags.rosbag2 import Reader

    from dynevent.bags.sent import SEQUENCE_KEY, SEQUENCE_VALUE, Sent, publish_times

    run = Conversation()
    for seq in range(3000):  # over 1 MiB: more than one chunk
        run.status(1, 1, "standby " + "x" * 400, seq % 5)
        if seq % 2:
            run.sent_at(run.now - 1000 - seq)
        if seq % 3 == 0:
            run.numbered(seq + 1)
    bag = run.write(tmp_path / "bag", StoragePlugin.MCAP)
    files = sorted(bag.glob("*.mcap"))
    with Reader(bag) as reader:
        stored = [(connection.topic, time, hash(raw)) for connection, time, raw in reader.messages()]
    assert len(stored) == 3000
    assert f"{SEQUENCE_KEY}: {SEQUENCE_VALUE}" in (bag / "metadata.yaml").read_text("utf-8")
    assert publish_times(str(bag), files) == {
        key: Sent(key[1] - 1000 - seq, 0) for seq, key in enumerate(stored) if seq % 2
    }
    assert publish_times(str(bag), files, numbered=True) == {
        key: Sent(key[1] - 1000 - seq if seq % 2 else None, seq + 1 if seq % 3 == 0 else 0)
        for seq, key in enumerate(stored)
        if seq % 2 or seq % 3 == 0
    }


def test_each_topic_is_read_as_its_robot_and_channel_and_no_other_is() -> None:
    """One reading of a topic's name, for the bag reader and the recorder: a robot's status and begin
    topics, the action's hidden topics, the fleet-wide begin topic; not the action's own name, a hidden
    suffix on a topic's name, the description service (no topic), or another name."""
    from dynevent.bags.reader import Channel, channel_of

    action = "/rmf/dynamic_event/command/tinyRobot/r1"
    assert channel_of("/rmf/dynamic_event/status/tinyRobot/r1") == Channel("tinyRobot", "r1", "status")
    assert channel_of("rmf/dynamic_event/begin/tinyRobot/r1") == Channel("tinyRobot", "r1", "begin")
    assert channel_of("/rmf/dynamic_event/begin") == Channel("", "", "begin")
    assert channel_of(action + "/_action/feedback") == Channel("tinyRobot", "r1", "feedback")
    assert channel_of(action + "/_action/cancel_goal/_service_event") == Channel(
        "tinyRobot", "r1", "cancel_goal"
    )
    for other in (
        action,
        "/rmf/dynamic_event/status/tinyRobot/r1/_action/feedback",
        "/rmf_dynamic_event/description/tinyRobot/r1",
        "/chatter",
        "/rmf/dynamic_event/status/a b/r",
    ):
        assert channel_of(other) is None, other
