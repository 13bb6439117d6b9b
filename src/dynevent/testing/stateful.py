"""A reusable hypothesis state machine that drives any Dynamic Event server and checks §19 of the spec.

The kit has three parts:

- :class:`ServerUnderTest`, the small adapter interface an implementation is
  wrapped in (``reset``, ``apply``, ``view``), with :class:`DyneventServer`
  (dynevent's own machine) and :class:`ImplementationServer` (any program or
  object speaking the conformance driver protocol of :mod:`dynevent.conformance.vectors.driver`);
- :class:`Observer`, a small reference model of the protocol state (phase,
  seq, status, current id, the goals and their ROS 2 lifecycle) that is
  derived only from the inputs sent and the outputs received, never from the
  implementation's internals, and that raises :class:`ProtocolViolation` at
  the first output the invariants of docs/spec.md §19 forbid;
- :class:`ServerStateMachine`, a :class:`~hypothesis.stateful.RuleBasedStateMachine`
  whose rules generate well-typed inputs: begins, goal requests of every type
  (valid ones built from the observed state so that runs go deep, and hostile
  ones: wrong seq, unknown event types, text that is not JSON, descriptions
  that fail their category, non-finite stubborn periods, stale and mismatched
  ids), starts of accepted goals in any order, action-level cancels, child
  progress and ends with any status, ticks that move the robot or not,
  interruptions, task cancels and kills, description queries and, rarely,
  shutdown.

Wrapping another implementation::

    class MyServer:  # satisfies ServerUnderTest
        def reset(self, fleet, robot, config): ...
        def apply(self, event): ...   # dynevent outputs, in order
        def view(self): return None   # or a ServerView

    TestMyServer = server_state_machine(MyServer).TestCase

The invariants checked after every step (rule numbers of docs/spec.md):

- R19.1: every accepted goal gets exactly one terminal answer, allowed by its
  ROS 2 lifecycle (succeed or abort once executing, cancel only after an
  accepted cancel); a rejected goal gets none; no output names a goal after
  its answer.  At teardown the kit shuts the server down and checks that
  every accepted goal was answered.
- R19.2: at most one goal holds the running slot: no ``StartChild`` while a
  started child runs, no NEXT accepted while a goal holds the slot.
- R19.3: the seq of begin and status messages changes only at a begin, by one.
- R19.4: every stubborn period applied (begin, hold, clamp) is at least the
  configured minimum, and a hold begins with ``max(requested, minimum)``.
- R19.5 (and R2.3): a step emits a status message exactly when the status the
  model implies changed, as its last output, equal to that status (R2.2)
  with ``time`` the input's ``now``.
- R19.7: ``apply`` never raises.

and, because they cost little once the model exists: a goal that starts in
another run (or with no run) is aborted (R5.2), a notice ``Ignored`` is the
only output of its step (R18.1), ``LogEntry.seq`` counts entries (R7.3), a
description answer matches the model (R16), and the optional view agrees with
the model (R2.1, R2.2).
"""

from __future__ import annotations

from dynevent.testing.inputs import input_sequences, server_inputs
from dynevent.testing.model import Observer, ProtocolViolation
from dynevent.testing.servers import DyneventServer, ImplementationServer, ServerUnderTest, ServerView
from dynevent.testing.state_machine import DEFAULT_CONFIG, ServerStateMachine, server_state_machine

__all__ = [
    "DEFAULT_CONFIG",
    "DyneventServer",
    "ImplementationServer",
    "Observer",
    "ProtocolViolation",
    "ServerStateMachine",
    "ServerUnderTest",
    "ServerView",
    "input_sequences",
    "server_inputs",
    "server_state_machine",
]
