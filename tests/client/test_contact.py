"""The client's contact with the robot's server processes, without ROS: a new process (R21.4) and a
process lost and found again (R21.5) each make the client ask again for every open goal's result,
and so does a status that shows a goal answered whose answer has not come (R21.6)."""

from __future__ import annotations

import itertools

import attrs
import pytest

from dynevent import client
from dynevent.client import (
    ANSWER_GRACE,
    ASK_AGAIN_LONGEST,
    ASK_AGAIN_PERIOD,
    LOST_AFTER_ASKS,
    SECOND,
    AskResult,
    BackInContact,
    BeginReceived,
    ContactLost,
    ContactMade,
    FeedbackReceived,
    GoalResponse,
    Ignored,
    Outcome,
    OutOfContact,
    SendGoal,
    StatusReceived,
    Tick,
)
from dynevent.wire.messages import Feedback
from dynevent.wire.vocab import GoalStatus
from support.client_scenario import RUNNING, WAITING, answer, begin, feed, status, waiting


def _sent(state: client.ClientState) -> tuple[client.ClientState, str]:
    transition = client.request_next(state, "go_to_place", '"a"', now=0)
    (send,) = transition.outputs
    assert isinstance(send, SendGoal)
    return transition.state, send.goal_uuid


def _asked(outputs: list[client.ClientOutput]) -> list[str]:
    return [output.goal_uuid for output in outputs if isinstance(output, AskResult)]


@pytest.mark.spec("R21.4")
def test_a_server_process_that_comes_into_contact_is_asked_for_every_open_goals_result() -> None:
    state, first = _sent(waiting())
    state, _ = feed(state, GoalResponse(goal_uuid=first, accepted=True))
    state, outputs = feed(state, ContactMade(now=5 * SECOND))
    assert outputs == [AskResult(goal_uuid=first)]  # no contact was lost: nothing more to say
    (goal,) = state.goals
    assert goal.ask_at == 5 * SECOND + ASK_AGAIN_PERIOD and goal.asks == 1
    assert client.next_deadline(state) == 5 * SECOND + ASK_AGAIN_PERIOD


@pytest.mark.spec("R21.4")
def test_results_are_asked_for_again_each_wait_twice_the_last_until_answered() -> None:
    state, uuid = _sent(waiting())
    state, _ = feed(state, ContactMade(now=0))
    asked_at = [0]
    now = 0
    while len(asked_at) < 10:
        deadline = client.next_deadline(state)
        assert deadline is not None
        state, outputs = feed(state, Tick(now=deadline - 1))
        assert _asked(outputs) == []  # not due yet
        state, outputs = feed(state, Tick(now=deadline))
        assert _asked(outputs) == [uuid]
        asked_at.append(deadline)
        now = deadline
    waits = [later - earlier for earlier, later in itertools.pairwise(asked_at)]
    assert waits[:5] == [ASK_AGAIN_PERIOD * 2**n for n in range(5)]
    assert max(waits) == ASK_AGAIN_LONGEST and waits[-1] == ASK_AGAIN_LONGEST
    state, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", id=2))
    assert [type(output) for output in outputs] == [Outcome]
    assert client.next_deadline(state) is None  # answered: nothing more to ask
    state, outputs = feed(state, Tick(now=now + ASK_AGAIN_LONGEST))
    assert outputs == []
    # a second answer (one per request) is ignored: the goal has its one outcome
    state, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", id=2))
    assert [type(output) for output in outputs] == [Ignored]


@pytest.mark.spec("R21.5")
def test_lost_contact_is_said_once_and_its_return_asks_for_the_answers_given_meanwhile() -> None:
    state, first = _sent(waiting())
    state, _ = feed(state, GoalResponse(goal_uuid=first, accepted=True), status(1, RUNNING, 7))
    (second_goal,) = client.request_cancel(state, now=0).outputs  # a CANCEL of the child, unanswered
    assert isinstance(second_goal, SendGoal)
    state, second = client.request_cancel(state, now=0).state, second_goal.goal_uuid
    state, outputs = feed(state, ContactLost(now=10 * SECOND))
    assert outputs == [OutOfContact(since=10 * SECOND)]
    assert state.contact_lost_at == 10 * SECOND
    assert client.next_deadline(state) is None  # nothing to ask while no server can hear it
    state, outputs = feed(state, ContactLost(now=11 * SECOND))
    assert [type(output) for output in outputs] == [Ignored]  # said once
    assert state.contact_lost_at == 10 * SECOND
    state, outputs = feed(state, ContactMade(now=40 * SECOND))
    assert outputs == [
        BackInContact(since=10 * SECOND, now=40 * SECOND),
        AskResult(goal_uuid=first),
        # accepted or not: its request or its response may be lost; its acceptance not heard, an
        # unknown reply to this first request is no answer (it may reach the server before the goal)
        AskResult(goal_uuid=second, contact=False),
    ]
    assert state.contact_lost_at is None
    state, outputs = feed(state, answer(first, GoalStatus.SUCCEEDED, "completed", id=2))
    assert [output.goal_uuid for output in outputs if isinstance(output, Outcome)] == [first]
    state, outputs = feed(state, Tick(now=40 * SECOND + ASK_AGAIN_PERIOD))
    assert _asked(outputs) == [second]  # the answered one is asked for no more


@pytest.mark.spec("R21.4")
def test_a_goal_whose_acceptance_was_not_heard_is_lost_only_once_its_request_had_time_to_come() -> None:
    """A process comes into contact after a goal was sent to it and before its response came: the
    client's first requests for the result may reach the server before the goal's own request (a
    lossy network repairs a lost one at the writer's next heartbeat), and an unknown reply to them is
    no answer; from the fourth on, 7 s after the contact, it is, and the goal is lost then."""
    state, sent = _sent(waiting())
    state, outputs = feed(state, ContactMade(now=5 * SECOND))
    asked = [outputs]
    for _ in range(LOST_AFTER_ASKS):
        deadline = client.next_deadline(state)
        assert deadline is not None
        state, outputs = feed(state, Tick(now=deadline))
        asked.append(outputs)
    assert asked == [*[[AskResult(goal_uuid=sent, contact=False)]] * LOST_AFTER_ASKS,
                     [AskResult(goal_uuid=sent, contact=True)]]  # fmt: skip
    assert client.next_deadline(state) == 5 * SECOND + 15 * SECOND  # waits of 1, 2, 4, then 8 s
    accepted, _ = feed(state, GoalResponse(goal_uuid=sent, accepted=True))
    _, outputs = feed(accepted, ContactMade(now=30 * SECOND))
    assert outputs == [AskResult(goal_uuid=sent, contact=True)]  # accepted: the first unknown is lost


@pytest.mark.spec("R21.5")
def test_goals_sent_after_contact_came_back_are_not_asked_for_again() -> None:
    state, first = _sent(waiting())
    state, _ = feed(state, GoalResponse(goal_uuid=first, accepted=True), status(1, RUNNING, 7))
    state, _ = feed(state, ContactLost(now=1), ContactMade(now=2))
    transition = client.request_cancel(state, now=3)
    state, (send,) = transition
    assert isinstance(send, SendGoal)
    (older, newer) = state.goals
    assert older.ask_at is not None and newer.goal_uuid == send.goal_uuid and newer.ask_at is None
    state, _ = feed(state, answer(first, GoalStatus.SUCCEEDED, "completed", id=7))
    assert client.next_deadline(state) is None


@pytest.mark.spec("R21.5")
def test_contact_with_no_goal_open_asks_for_nothing() -> None:
    state, outputs = feed(waiting(), ContactLost(now=1), ContactMade(now=2), ContactMade(now=3))
    assert outputs == [OutOfContact(since=1), BackInContact(since=1, now=2)]
    assert client.next_deadline(state) is None


@pytest.mark.spec("R21.4")
def test_asking_again_runs_beside_a_timeout_and_ticks_at_the_earlier() -> None:
    transition = client.request_next(waiting(), "go_to_place", '"a"', timeout=5.0, now=0)
    state = transition.state
    assert client.next_deadline(state) == 5 * SECOND
    state, _ = feed(state, ContactMade(now=SECOND))
    assert client.next_deadline(state) == SECOND + ASK_AGAIN_PERIOD


def _kinds(outputs: list[client.ClientOutput]) -> list[client.OutcomeKind]:
    return [output.kind for output in outputs if isinstance(output, Outcome)]


def _at(event: StatusReceived | BeginReceived, now: int) -> StatusReceived | BeginReceived:
    """``event`` as a binding gives it: with the instant it arrived (R21.6)."""
    return attrs.evolve(event, now=now)


@pytest.mark.spec("R21.6")
def test_a_status_that_shows_a_nexts_child_ended_asks_for_its_answer_after_the_grace() -> None:
    state, uuid = _sent(waiting())
    state, _ = feed(state, GoalResponse(goal_uuid=uuid, accepted=True), _at(status(1, RUNNING, 6), 0))
    state, _ = feed(state, FeedbackReceived(goal_uuid=uuid, feedback=Feedback(status="underway", id=6)))
    assert client.next_deadline(state) is None  # the child runs: its answer is not due
    state, outputs = feed(state, _at(status(1, WAITING, 6), 10 * SECOND))
    assert _asked(outputs) == []  # the answer comes on a channel of its own: given time
    assert client.next_deadline(state) == 10 * SECOND + ANSWER_GRACE
    state, outputs = feed(state, Tick(now=10 * SECOND + ANSWER_GRACE))
    assert outputs == [AskResult(goal_uuid=uuid, contact=False)]
    state, outputs = feed(state, Tick(now=10 * SECOND + ANSWER_GRACE + ASK_AGAIN_PERIOD))
    assert outputs == [AskResult(goal_uuid=uuid, contact=False)]  # and again, each wait twice the last
    assert client.next_deadline(state) == 10 * SECOND + ANSWER_GRACE + 3 * ASK_AGAIN_PERIOD
    state, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", id=6))
    assert _kinds(outputs) == [client.OutcomeKind.COMPLETED]
    assert client.next_deadline(state) is None


@pytest.mark.spec("R21.6")
def test_an_answer_that_comes_within_the_grace_is_not_asked_for() -> None:
    state, uuid = _sent(waiting())
    state, _ = feed(state, GoalResponse(goal_uuid=uuid, accepted=True))
    state, _ = feed(state, FeedbackReceived(goal_uuid=uuid, feedback=Feedback(status="underway", id=6)))
    state, _ = feed(state, _at(status(1, RUNNING, 7), SECOND))  # a later child: the NEXT's has ended
    assert client.next_deadline(state) == SECOND + ANSWER_GRACE
    state, _ = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", id=6))
    state, outputs = feed(state, Tick(now=SECOND + ANSWER_GRACE))
    assert _asked(outputs) == [] and client.next_deadline(state) is None


@pytest.mark.spec("R21.6")
def test_a_newer_run_asks_for_the_answer_of_a_finished_whose_response_never_came() -> None:
    transition = client.request_finish(waiting(), now=0)
    state, (send,) = transition
    assert isinstance(send, SendGoal)
    state, outputs = feed(state, _at(begin(2), 5 * SECOND))  # the response was lost on the way
    assert client.next_deadline(state) == 5 * SECOND + ANSWER_GRACE
    state, outputs = feed(state, Tick(now=5 * SECOND + ANSWER_GRACE))
    assert outputs == [AskResult(goal_uuid=send.goal_uuid, contact=False)]
    state, outputs = feed(state, answer(send.goal_uuid, GoalStatus.SUCCEEDED, "completed", id=5))
    assert _kinds(outputs) == [client.OutcomeKind.COMPLETED]


@pytest.mark.spec("R21.6")
def test_a_next_whose_response_and_feedback_were_lost_is_asked_for_once_the_robot_waits_at_its_id() -> None:
    """Found at 30% loss across hosts: the server ran a NEXT and answered it, and the client heard
    neither the response nor any feedback, only the statuses.  The NEXT names its child by its own
    id: the robot waiting at that id shows it answered."""
    state, uuid = _sent(waiting())
    (goal,) = state.goals
    assert goal.goal.id == 6 and goal.child_id is None
    state, _ = feed(state, _at(status(1, RUNNING, 6), SECOND))
    assert client.next_deadline(state) is None  # its child runs
    state, _ = feed(state, _at(status(1, WAITING, 6), 7 * SECOND))
    assert client.next_deadline(state) == 7 * SECOND + ANSWER_GRACE
    state, outputs = feed(state, Tick(now=7 * SECOND + ANSWER_GRACE))
    assert outputs == [AskResult(goal_uuid=uuid, contact=False)]
    state, outputs = feed(state, answer(uuid, GoalStatus.SUCCEEDED, "completed", id=6))
    assert _kinds(outputs) == [client.OutcomeKind.COMPLETED]


@pytest.mark.spec("R21.6")
def test_what_no_status_shows_answered_waits_for_its_answer() -> None:
    state, uuid = _sent(waiting())  # a NEXT whose child no feedback named yet: its own id, 6
    state, _ = feed(state, GoalResponse(goal_uuid=uuid, accepted=True), _at(status(1, WAITING, 5), SECOND))
    state, _ = feed(state, _at(status(1, RUNNING, 6), 2 * SECOND))
    assert client.next_deadline(state) is None  # the child it names still runs
    cancel = client.request_cancel(feed(waiting(), _at(status(1, RUNNING, 6), 0))[0], now=0)
    state, (send,) = cancel
    assert isinstance(send, SendGoal)
    state, _ = feed(state, _at(status(1, RUNNING, 6, "underway"), SECOND))
    assert client.next_deadline(state) is None  # the child it names still runs
    state, _ = feed(state, _at(status(1, WAITING, 6), 2 * SECOND))
    assert client.next_deadline(state) == 2 * SECOND + ANSWER_GRACE  # and now it has ended


@pytest.mark.spec("R21.6", "R21.4")
def test_contact_made_asks_as_r21_4_says_whatever_a_status_showed() -> None:
    state, uuid = _sent(waiting())
    state, _ = feed(state, GoalResponse(goal_uuid=uuid, accepted=True))
    state, _ = feed(state, FeedbackReceived(goal_uuid=uuid, feedback=Feedback(status="underway", id=6)))
    state, _ = feed(state, _at(status(1, WAITING, 6), SECOND))
    state, outputs = feed(state, ContactMade(now=2 * SECOND))
    assert outputs == [AskResult(goal_uuid=uuid)]  # a server that does not know it has lost it
    assert AskResult(goal_uuid=uuid).contact


def test_a_status_or_begin_arrived_at_no_instant_is_refused_naming_the_field() -> None:
    from dynevent.errors import InvalidValue

    for event in (status(1, WAITING, 5), begin(1)):
        with pytest.raises(InvalidValue, match=r"\.now: expected integer nanoseconds \(got 'soon'\)"):
            attrs.evolve(event, now="soon")
