"""A tiny harness for the client tests (``tests/client/``): builders of inputs and states.

Not a test module: test files import it as ``from support.client_scenario import ...``.
"""

from __future__ import annotations

from typing import Any

from dynevent import client
from dynevent.client import (
    BeginReceived,
    ClientInput,
    ClientOutput,
    ClientState,
    FeedbackReceived,
    GoalResponse,
    Outcome,
    Refused,
    ResultReceived,
    SendGoal,
    StatusReceived,
)
from dynevent.server import machine
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback, Result
from dynevent.wire.vocab import DynamicState, GoalStatus

PREFIX = "00000000000000ab"
U32 = 2**32 - 1
U64 = 2**64 - 1
WAITING, RUNNING, INACTIVE = DynamicState.WAITING, DynamicState.RUNNING, DynamicState.INACTIVE
CONFIG = machine.ServerConfig(categories={"go_to_place": machine.any_description})


def status(seq: int, phase: DynamicState, id: int = 0, text: str = "standby") -> StatusReceived:
    if phase is INACTIVE:
        text = "uninitialized"
    return StatusReceived(
        message=DynamicEventStatus(dynamic_event_seq=seq, dynamic_state=phase, status=text, id=id)
    )


def begin(seq: int, description: str = "{}") -> BeginReceived:
    return BeginReceived(
        message=DynamicEventDescription(fleet="f", robot="r", dynamic_event_seq=seq, description=description)
    )


def answer(
    uuid: str, goal_status: GoalStatus, final: str = "", id: int = 0, failure: str = ""
) -> ResultReceived:
    return ResultReceived(
        goal_uuid=uuid, status=goal_status, result=Result(execution_failure=failure, status=final, id=id)
    )


def feed(state: ClientState, *events: ClientInput) -> tuple[ClientState, list[ClientOutput]]:
    outputs: list[ClientOutput] = []
    for event in events:
        transition = client.step(state, event)
        state = transition.state
        outputs.extend(transition.outputs)
    return state, outputs


def waiting(seq: int = 1, event_id: int = 5, **kwargs: Any) -> ClientState:
    state, _ = feed(ClientState.new(PREFIX, **kwargs), begin(seq), status(seq, WAITING, event_id))
    return state


def sent(transition: client.ClientTransition) -> tuple[ClientState, SendGoal]:
    (output,) = transition.outputs
    assert isinstance(output, SendGoal), output
    return transition.state, output


def refused(transition: client.ClientTransition) -> Refused:
    (output,) = transition.outputs
    assert isinstance(output, Refused), output
    assert transition.state is not None
    return output


def only_outcome(outputs: list[ClientOutput]) -> Outcome:
    found = [output for output in outputs if isinstance(output, Outcome)]
    assert len(found) == 1, outputs
    return found[0]


def running(seq: int = 1, child: int = 6) -> tuple[ClientState, str]:
    """A client whose NEXT (child ``child``) was accepted and is running."""
    state, send = sent(client.request_next(waiting(seq), "go_to_place", '"a"', now=0))
    state, _ = feed(
        state,
        GoalResponse(goal_uuid=send.goal_uuid, accepted=True),
        FeedbackReceived(goal_uuid=send.goal_uuid, feedback=Feedback(status="underway", id=child)),
        status(seq, RUNNING, child, "underway"),
    )
    return state, send.goal_uuid
