"""§21. Restart: the tests of the rules of docs/spec.md §21.

The section's conformance vectors are src/dynevent/conformance/vectors/21-restart.json.

A state restored after its process ended is restarted: nothing the dead process held blocks.
"""

from __future__ import annotations

import pytest
from hypothesis import given

from dynevent.conformance.records import config_from_json
from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server import outputs as outs
from dynevent.server.machine import State
from dynevent.testing import DEFAULT_CONFIG, input_sequences
from dynevent.wire.messages import Result
from dynevent.wire.vocab import DynamicState, GoalStatus
from support.scenario import (
    T0,
    next_goal,
    running,
    u,
    waiting,
)

CONFIG = config_from_json(dict(DEFAULT_CONFIG))
SEQUENCES = input_sequences(tuple(DEFAULT_CONFIG["categories"]), max_size=40)


@pytest.mark.spec("R21.1", "R21.2", "R21.3", "R19.1")
@given(events=SEQUENCES)
def test_a_restart_answers_every_open_goal_once_and_keeps_the_run(events: list[ins.Input]) -> None:
    state = State.new("fleet", "robot")
    for event in events:
        state = machine.step(state, event, CONFIG).state
    restored = snapshot.loads(snapshot.dumps(state))  # what a store gives back after kill -9
    transition = machine.step(restored, ins.Restart(now=T0), CONFIG)
    after = transition.state
    open_goals = [queued.goal_uuid for queued in state.queued] + list(state.cancels)
    if state.running is not None:
        open_goals.append(state.running.goal_uuid)
    answers = [output for output in transition.outputs if isinstance(output, outs.AnswerGoal)]
    assert sorted(answer.goal_uuid for answer in answers) == sorted(open_goals)  # R21.1, once each
    assert all(answer.status is GoalStatus.ABORTED for answer in answers)
    assert {answer.result.execution_failure for answer in answers} <= {"server restarted"}
    assert (after.running, after.queued, after.cancels, after.stubborn) == (None, (), (), None)  # R21.2
    assert not after.shutdown
    assert (after.seq, after.last_id, after.log_seq, after.interrupted) == (
        state.seq,
        state.last_id,
        state.log_seq,
        state.interrupted and not (state.task_signal and state.running is not None),
    )  # R21.3 (a task signal's end clears the interruption, R13.6)
    last = transition.outputs[-1]
    assert isinstance(last, outs.PublishStatus) and last.message == machine.status_message(after, T0)
    if state.active and not (state.task_signal and state.running is not None):
        assert after.phase is DynamicState.WAITING  # the run goes on


@pytest.mark.spec("R21.1", "R21.2")
def test_a_restart_with_a_queued_goal_executes_it_before_its_answer() -> None:
    run = waiting()
    run.request(u(1), next_goal(1, 8))
    outputs = run.step(ins.Restart(now=T0))
    assert outputs[:2] == (
        outs.ExecuteGoal(goal_uuid=u(1)),
        outs.AnswerGoal(
            goal_uuid=u(1), status=GoalStatus.ABORTED, result=Result(execution_failure="server restarted")
        ),
    )
    assert run.state.queued == () and run.state.phase is DynamicState.WAITING


@pytest.mark.spec("R21.2", "R13.6")
def test_a_restart_ends_a_task_signalled_run_and_its_interruption_with_it() -> None:
    """The child of an interrupted, cancelled task ended with the process: the task is over, not paused."""
    run = running()
    run.interrupt()
    run.task_cancel()
    assert (run.state.interrupted, run.state.task_signal) == (True, "canceled")
    outputs = run.step(ins.Restart(now=T0))
    assert (run.state.active, run.state.status, run.state.interrupted) == (False, "canceled", False)
    assert outs.DynamicEventFinished(status="canceled") in outputs
