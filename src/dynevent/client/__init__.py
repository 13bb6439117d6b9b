"""The remote action client's side of the protocol: a pure machine, as the server's is.

Split as the server is: :mod:`~dynevent.client.inputs` (what the action, the
topics and the clock tell a client), :mod:`~dynevent.client.outputs` (goals to
send, local refusals, outcomes, notices) and :mod:`~dynevent.client.machine`
(the state, the commands and ``step``; its docstring is the model).  Every
public name of the three is importable from here: ``from dynevent.client
import ClientState, request_next, step``.
"""

from __future__ import annotations

from dynevent.client.inputs import (
    BeginReceived,
    ClientInput,
    ContactLost,
    ContactMade,
    FeedbackReceived,
    GoalResponse,
    ResultReceived,
    StatusReceived,
    Tick,
)
from dynevent.client.machine import (
    ANSWER_GRACE,
    ASK_AGAIN_LONGEST,
    ASK_AGAIN_PERIOD,
    LOST_AFTER_ASKS,
    SECOND,
    ClientState,
    ClientTransition,
    OpenGoal,
    next_deadline,
    request_cancel,
    request_finish,
    request_next,
    request_withdraw,
    step,
)
from dynevent.client.outputs import (
    AskResult,
    BackInContact,
    ClientOutput,
    Ignored,
    Outcome,
    OutcomeKind,
    OutOfContact,
    Progress,
    Refused,
    RunBegan,
    SendGoal,
    TimedOut,
    ViewChanged,
)

__all__ = [
    "ANSWER_GRACE",
    "ASK_AGAIN_LONGEST",
    "ASK_AGAIN_PERIOD",
    "LOST_AFTER_ASKS",
    "SECOND",
    "AskResult",
    "BackInContact",
    "BeginReceived",
    "ClientInput",
    "ClientOutput",
    "ClientState",
    "ClientTransition",
    "ContactLost",
    "ContactMade",
    "FeedbackReceived",
    "GoalResponse",
    "Ignored",
    "OpenGoal",
    "OutOfContact",
    "Outcome",
    "OutcomeKind",
    "Progress",
    "Refused",
    "ResultReceived",
    "RunBegan",
    "SendGoal",
    "StatusReceived",
    "Tick",
    "TimedOut",
    "ViewChanged",
    "next_deadline",
    "request_cancel",
    "request_finish",
    "request_next",
    "request_withdraw",
    "step",
]
