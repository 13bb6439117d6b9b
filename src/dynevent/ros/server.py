"""One robot's Dynamic Event server on an rclpy node: the machine behind a real action server.

How rclpy's callbacks meet the machine (docs/ros.md has the whole story):

- ``goal_callback`` gets the goal without its UUID, so it only asks
  :func:`dynevent.server.machine.accept` and answers ACCEPT or REJECT (the refusal's
  reason goes to the node's log: ROS actions carry none).
- ``handle_accepted_callback`` has the goal handle: the goal is submitted to
  the machine with its UUID (:class:`~dynevent.server.inputs.GoalSubmitted`, R5.3),
  request and start in one step under the server's lock.  Between the two
  callbacks other threads may have changed the state; a goal that lost that
  race is still answered (aborted, ``race condition``).
- ``cancel_callback`` steps :class:`~dynevent.server.inputs.CancelRequested` and
  answers with the machine's :class:`~dynevent.server.outputs.CancelResponse`.
- Every other output goes to an outbox, carried out in order by a guard
  condition's callback.  The guard condition wakes the executor from any
  thread (an adapter's own threads report progress), and it shares a
  mutually exclusive callback group with the action server, so it never runs
  while rclpy is inside a goal or cancel request: an answer ``canceled`` that
  the machine gives inside the cancel callback is carried out only after
  rclpy has moved the goal to CANCELING, where ``canceled()`` is legal.
- The execute callback of each goal awaits the machine's answer (an rclpy
  future completed by the outbox) and ends the goal with it.
- Every goal's answer is kept 15 minutes (:mod:`dynevent.server.answers`) for a
  client that asks after rclpy forgot the goal (it keeps a result 10 s), and
  would answer ``STATUS_UNKNOWN``: one the network cut off (R21.5), or one of
  the process before a restart (R21.4, answers kept by ``on_answers``).

Time comes from the node's clock, so simulated time works.
"""

from __future__ import annotations

import collections
import contextlib
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

from action_msgs.msg import GoalStatus as RosGoalStatus
from rclpy.action import ActionServer, CancelResponse, GoalResponse
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.task import Future

from dynevent.errors import InvalidMessage, InvalidValue
from dynevent.ros import convert
from dynevent.ros.convert import DynamicEvent, RosDescription, RosStatus
from dynevent.ros.qos import introspect, latched, latched_publisher
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.adapter import (
    AdapterInputs,
    ChildEvents,
    ChildExecution,
    RunningChildren,
    StubbornHolds,
    carry_out_stubbornness,
)
from dynevent.server.answers import KeptAnswers
from dynevent.server.inputs import NOW_RANGE
from dynevent.server.machine import ServerConfig, State
from dynevent.wire import names
from dynevent.wire.messages import Goal
from dynevent.wire.names import (
    BEGIN_TOPIC,
    BEGIN_TOPIC_DEPTH,
    EVENTS_KEPT,
    ROBOT_BEGIN_TOPIC_DEPTH,
    STATUS_TOPIC_DEPTH,
    action_name,
    begin_topic,
    status_topic,
)
from dynevent.wire.vocab import GoalStatus, Tier

__all__ = ["ChildEvents", "ChildExecution", "DynamicEventServer", "StubbornHolds", "latched"]


_ROS_GOAL_STATUS = {
    GoalStatus.SUCCEEDED: RosGoalStatus.STATUS_SUCCEEDED,
    GoalStatus.CANCELED: RosGoalStatus.STATUS_CANCELED,
    GoalStatus.ABORTED: RosGoalStatus.STATUS_ABORTED,
}


class _RecoveringActionServer(ActionServer):  # type: ignore[misc]  # rclpy is untyped here
    """rclpy's action server, which also answers a result request for a goal it no longer knows with
    the answer kept for it (R21.4, R21.5: a goal of the process before a restart, or one whose result
    rclpy kept only 10 s), where rclpy alone would answer ``STATUS_UNKNOWN``."""

    def __init__(self, *args: Any, owed: Callable[[str], outs.AnswerGoal | None], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._owed = owed
        #: The UUID of the goal request whose goal callback runs (rclpy gives the callback the goal
        #: alone); None outside it.
        self.requested_uuid: str | None = None

    async def _execute_goal_request(self, request_header_and_message: Any) -> None:
        self.requested_uuid = convert.uuid_from_ros(convert.quiet_uuid(request_header_and_message[1].goal_id))
        try:
            await super()._execute_goal_request(request_header_and_message)
        finally:
            self.requested_uuid = None

    async def _execute_get_result_request(self, request_header_and_message: Any) -> None:
        request_header, request = request_header_and_message
        uuid = bytes(convert.quiet_uuid(request.goal_id).uuid)
        answer = None if uuid in self._goal_handles else self._owed(uuid.hex())
        if answer is None:
            await super()._execute_get_result_request(request_header_and_message)
            return
        response = self._action_type.Impl.GetResultService.Response()
        response.status = _ROS_GOAL_STATUS[answer.status]
        response.result = convert.result_to_ros(answer.result)
        with getattr(self, "_lock", None) or contextlib.nullcontext():  # Jazzy's rclpy has no such lock
            self._handle.send_result_response(request_header, response)


class _Entities:
    """One robot's ROS 2 entities on a node: its status and begin topics, its action server, the
    wake-up guard condition, the stubborn-refresh timer while a stubbornness holds (an idle robot has
    no timer: every timer costs CPU at every executor wake-up) and, when asked for, the description
    service.  Every callback runs in one mutually exclusive group: the server's steps never overlap."""

    def __init__(
        self,
        server: DynamicEventServer,
        node: Any,
        fleet: str,
        robot: str,
        begin_publisher: Any | None,
        description_service: Any | None,
    ) -> None:
        group = MutuallyExclusiveCallbackGroup()
        self.node, self.group, self.server = node, group, server
        self.status = latched_publisher(node, RosStatus, status_topic(fleet, robot), STATUS_TOPIC_DEPTH)
        self.begin = latched_publisher(
            node, RosDescription, begin_topic(fleet, robot), ROBOT_BEGIN_TOPIC_DEPTH
        )
        self.fleet_begin = (
            begin_publisher if begin_publisher is not None else server.fleet_begin_publisher(node)
        )
        self.wake = node.create_guard_condition(server._drain, callback_group=group)
        self.action = _RecoveringActionServer(
            node,
            DynamicEvent,
            action_name(fleet, robot),
            execute_callback=server._execute,
            goal_callback=server._goal_callback,
            handle_accepted_callback=server._handle_accepted,
            cancel_callback=server._cancel_callback,
            callback_group=group,
            owed=lambda uuid: server._owed.get(uuid, time.monotonic()),
        )
        self.timer: Any = None
        self.service = None
        self.introspection: Any = None
        self.follower: Any = None
        self.action_name = action_name(fleet, robot)
        if description_service is not None:
            self.service = node.create_service(
                description_service,
                names.description_service(fleet, robot),
                server._describe,
                callback_group=group,
            )

    def refresh(self, on: bool) -> None:
        """Start or stop the stubborn-refresh timer."""
        if on and self.timer is None:
            period = self.server.config.stubborn_refresh
            self.timer = self.node.create_timer(period, self.server._refresh, callback_group=self.group)
        elif not on and self.timer is not None:
            self.node.destroy_timer(self.timer)
            self.timer = None

    def destroy(self, node: Any) -> None:
        if self.introspection is not None:
            self.follower.destroy_subscription(self.introspection)
        self.action.destroy()
        self.refresh(False)
        node.destroy_publisher(self.status)
        node.destroy_publisher(self.begin)
        node.destroy_guard_condition(self.wake)
        if self.service is not None:
            node.destroy_service(self.service)


class DynamicEventServer(AdapterInputs):
    """One robot's Dynamic Event server on ``node`` (several may share a node: a fleet).

    ``children`` runs child events; ``stubbornness`` holds the robot's place
    (without one, stubbornness is only logged); ``on_finished(status)`` is
    called when the dynamic event ends and the task may move on,
    ``on_interrupt_confirmed()`` when an interruption took effect.
    ``begin_publisher`` shares one fleet-wide begin publisher between the
    robots of a node (:meth:`fleet_begin_publisher`).  ``description_service``
    is a service type with the proposal's fields (R16): given one, the server
    answers ``rmf_dynamic_event/description/<fleet>/<robot>`` with it.
    ``state`` starts the server from a restored state (then call
    :meth:`restart`); ``on_state(state)`` is called, under the server's lock,
    after every step that changed the state (to store it);
    ``on_answers(answers)`` before it, with the step's goal answers (to keep
    them, :meth:`dynevent.server.store.StateStore.keep_answers`); ``answers``
    are the answers kept before a restart, given to clients that ask for
    their goals' results again (R21.4); ``observer`` sees
    every output as it is carried out and every refusal of a goal request; ``on_step(input,
    outputs)`` every step of the machine, as it is taken (a trace, a judge of the clients).  The
    node must be spun by an executor (single- or multi-threaded); every method may be called from
    any thread.
    """

    def __init__(
        self,
        node: Any,
        fleet: str,
        robot: str,
        config: ServerConfig,
        children: ChildEvents,
        *,
        stubbornness: StubbornHolds | None = None,
        on_finished: Callable[[str], None] | None = None,
        on_interrupt_confirmed: Callable[[], None] | None = None,
        begin_publisher: Any | None = None,
        description_service: Any | None = None,
        state: State | None = None,
        on_state: Callable[[State], None] | None = None,
        on_answers: Callable[[tuple[outs.AnswerGoal, ...]], None] | None = None,
        answers: Mapping[str, outs.AnswerGoal] | None = None,
        observer: Callable[[outs.Output | outs.Rejected], None] | None = None,
        on_step: Callable[[ins.Input, tuple[outs.Output, ...]], None] | None = None,
    ) -> None:
        self._node = node
        self._on_step = on_step
        self._config = config
        self._children = RunningChildren(self, children, self.now)
        self._stubbornness = stubbornness
        self._on_finished = on_finished
        self._on_interrupt_confirmed = on_interrupt_confirmed
        self._on_state = on_state
        self._on_answers = on_answers
        #: every goal's answer, for a client that asks after rclpy forgot the goal or after a restart
        self._owed = KeptAnswers(answers, now=time.monotonic())
        self._observer = observer
        self._state = state if state is not None else State.new(fleet, robot)
        if (self._state.fleet, self._state.robot) != (fleet, robot):
            why = f"the state belongs to another robot than {fleet}/{robot}"
            raise InvalidValue("DynamicEventServer", "state", f"{self._state.fleet}/{self._state.robot}", why)
        self._lock = threading.Lock()
        self._outbox: collections.deque[outs.Output] = collections.deque()
        self._answers: dict[str, Any] = {}
        self._handles: dict[str, Any] = {}
        self._position: tuple[str, float, float] | None = None
        self._converted: tuple[Any, Any] = (None, None)  # the goal callback's (request, goal)
        self._draining: int | None = None  # the thread that drains the outbox, while it does
        self._log = node.get_logger().get_child(f"{fleet}.{robot}")
        self._ros = _Entities(self, node, fleet, robot, begin_publisher, description_service)
        self._ros.refresh(self._state.stubborn is not None)
        self._announce = True  # the status at the first drain, unless a step already queued one
        self._ros.wake.trigger()

    # ---------------------------------------------------------------- plumbing

    @staticmethod
    def fleet_begin_publisher(node: Any) -> Any:
        """A publisher of the fleet-wide begin topic, to share between the robots of ``node``."""
        return latched_publisher(node, RosDescription, BEGIN_TOPIC, BEGIN_TOPIC_DEPTH)

    @property
    def state(self) -> State:
        """The machine's current state (a frozen value)."""
        with self._lock:
            return self._state

    @property
    def config(self) -> ServerConfig:
        """The configuration."""
        return self._config

    def now(self) -> int:
        """The node's clock (ROS time), in integer nanoseconds within what the machine accepts."""
        nanoseconds: int = self._node.get_clock().now().nanoseconds
        return min(max(nanoseconds, NOW_RANGE[0]), NOW_RANGE[1])

    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        """Apply ``event`` under the lock; its outputs are carried out in order, on the executor."""
        with self._lock:
            outputs = self._step(event)
        if self._draining != threading.get_ident():  # a drain on this thread carries them out itself
            self._ros.wake.trigger()
        return outputs

    def _step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        transition = machine.step(self._state, event, self._config)
        if self._on_step is not None:  # under the lock: steps are seen in the order they were taken
            self._on_step(event, transition.outputs)
        self._keep(transition.state, transition.outputs)
        for output in transition.outputs:  # a goal of the process before a restart (R21.1)
            if isinstance(output, outs.AnswerGoal) and output.goal_uuid not in self._answers:
                # its answer is given to a client that asks from now on (R21.4), not from the drain
                # that carries the step out: a result request the executor takes first would find none
                self._owed.keep(output, time.monotonic())
        self._outbox.extend(transition.outputs)
        return transition.outputs

    def _keep(self, state: State, outputs: tuple[outs.Output, ...]) -> None:
        if self._on_answers is not None:  # before the state: a state kept without its answer loses it
            answers = tuple(output for output in outputs if isinstance(output, outs.AnswerGoal))
            if answers:
                self._on_answers(answers)
        changed = state is not self._state
        self._state = state
        if changed and self._on_state is not None:
            self._on_state(state)

    # ---------------------------------------------------------------- the adapter's inputs

    def update_position(self, map_name: str, x: float, y: float) -> None:
        """Where the robot is; stubbornness refreshes from the last position given (R12.3)."""
        self._position = (map_name, x, y)
        self.step(ins.Tick(now=self.now(), map_name=map_name, x=x, y=y))

    def destroy(self) -> None:
        """Release the action server, publishers, timer and guard condition (after :meth:`shutdown`)."""
        self._ros.destroy(self._node)

    def introspect(self, on_goal: Callable[[Any], None] | None = None, follower: Any = None) -> bool:
        """Turn on the introspection of this robot's action server (its service events, with their
        contents, for a recording) and, with ``on_goal``, follow its ``send_goal`` events at once
        (:meth:`follow`).  False where rclpy cannot introspect an action."""
        if not introspect(self._ros.action, self._node, latched(EVENTS_KEPT)):  # kept for a late follower
            return False
        if on_goal is not None:
            self.follow(on_goal, follower)
        return True

    def follow(self, on_goal: Callable[[Any], None], follower: Any = None) -> None:
        """Follow the ``send_goal`` service events of this robot's action server (introspected):
        ``on_goal(event)`` for each, the last few published before included, on ``follower`` (a
        node; this robot's when None).  In a process whose participants ignore their own endpoints
        (:mod:`dynevent.ros.participant`) the follower is a node of another context.  How a server
        learns which client sent a goal (R22.1)."""
        ros = self._ros
        if ros.introspection is not None:
            return
        own = follower is None
        ros.follower = self._node if own else follower
        ros.introspection = ros.follower.create_subscription(
            DynamicEvent.Impl.SendGoalService.Event, f"{ros.action_name}/_action/send_goal/_service_event",
            on_goal, latched(EVENTS_KEPT), callback_group=ros.group if own else None,
        )  # fmt: skip

    def _describe(self, request: Any, response: Any) -> Any:
        with self._lock:  # a query: its one output is the answer, not an effect for the outbox (R16)
            outputs = machine.step(self._state, ins.DescriptionQuery(now=self.now()), self._config).outputs
        answer = next((output for output in outputs if isinstance(output, outs.DescriptionAnswer)), None)
        if answer is None:  # a machine with R16.1 switched off: an exception would end the lane's thread
            return response
        response.running = answer.response.running
        response.status = answer.response.status
        response.description = answer.response.description
        response.id = answer.response.id
        return response

    def _refresh(self) -> None:
        position = self._position
        if position is not None and self.state.stubborn is not None:
            self.step(ins.Tick(now=self.now(), map_name=position[0], x=position[1], y=position[2]))

    # ---------------------------------------------------------------- rclpy's callbacks

    def _goal_callback(self, request: Any) -> GoalResponse:
        try:
            goal = convert.goal_from_ros(request)
        except InvalidMessage as exc:
            self._log.warning(f"goal refused: {exc}")
            return GoalResponse.REJECT
        with self._lock:
            refusal = self._refusal(goal)
        # rclpy hands the same request object to the accepted callback right after this one, in the
        # same callback of the group: its conversion is kept for it rather than done twice
        self._converted = (request, goal)
        if refusal is not None:
            self._log.info(f"goal refused: {refusal.reason.value}: {refusal.text}")
            if self._observer is not None:
                self._observer(refusal)
            return GoalResponse.REJECT
        return GoalResponse.ACCEPT

    def _refusal(self, goal: Goal) -> outs.Rejected | None:
        """Why ``goal`` is refused, or None to accept it (under the lock).  Where ``on_step`` watches
        and the request's UUID is known, a refusal is the machine's step of the request (R4.15), which
        ``on_step`` sees; that step changes nothing, and an accepted goal is stepped when it is
        submitted (R5.3)."""
        uuid = self._ros.action.requested_uuid
        if self._on_step is None or uuid is None:
            decision = machine.accept(self._state, goal, self._config)
            return decision if isinstance(decision, outs.Rejected) else None
        requested = ins.GoalRequested(goal_uuid=uuid, goal=goal, now=self.now())
        outputs = machine.step(self._state, requested, self._config).outputs
        refused = next((output for output in outputs if isinstance(output, outs.GoalRejected)), None)
        if refused is not None:
            self._on_step(requested, outputs)
            return refused.rejection
        return None

    def _handle_accepted(self, goal_handle: Any) -> None:
        uuid = convert.uuid_from_ros(goal_handle.goal_id)
        request, goal = self._converted
        if request is not goal_handle.request:  # another path to the accepted callback: convert it
            goal = convert.goal_from_ros(goal_handle.request)  # it passed the goal callback's check
        self._converted = (None, goal)
        with self._lock:
            submitted = ins.GoalSubmitted(goal_uuid=uuid, goal=goal, now=self.now())
            transition = machine.step(self._state, submitted, self._config)
            if self._on_step is not None:
                self._on_step(submitted, transition.outputs)
            first = transition.outputs[0]
            if isinstance(first, outs.Ignored):  # R18.2: a UUID still open in a restored state
                self._log.error(f"goal {uuid}: {first.why}; aborted")
                goal_handle.execute(_abort_at_once(first.why))
                return
            self._keep(transition.state, transition.outputs)
            self._answers[uuid] = Future()
            self._handles[uuid] = goal_handle
            goal_handle.execute()  # ExecuteGoal, R5.1: from EXECUTING every answer is legal
            self._outbox.extend(transition.outputs[1:])
        # carried out here, in the group's own callback, not one executor wake-up later: the goal is
        # EXECUTING already, and no other drain can run beside this one (the group is exclusive)
        self._drain()

    def _cancel_callback(self, goal_handle: Any) -> CancelResponse:
        uuid = convert.uuid_from_ros(goal_handle.goal_id)
        with self._lock:
            outputs = self._step(ins.CancelRequested(goal_uuid=uuid, now=self.now()))
        self._ros.wake.trigger()  # carried out after rclpy has moved the goal to CANCELING (same group)
        response = next((output for output in outputs if isinstance(output, outs.CancelResponse)), None)
        return CancelResponse.ACCEPT if response is not None and response.accepted else CancelResponse.REJECT

    async def _execute(self, goal_handle: Any) -> Any:
        uuid = convert.uuid_from_ros(goal_handle.goal_id)
        answer: outs.AnswerGoal = await self._answers[uuid]
        del self._answers[uuid]
        _TERMINAL_CALLS.get(answer.status, _TERMINAL_CALLS[GoalStatus.ABORTED])(goal_handle)
        return convert.result_to_ros(answer.result)

    # ---------------------------------------------------------------- carrying out the outputs

    def _drain(self) -> None:
        # one drain at a time: the guard condition's group is mutually exclusive; outputs of steps
        # that the adapter takes from inside a callback join the outbox and are carried out here too,
        # without waking the executor for another drain
        self._draining = threading.get_ident()
        try:
            while (output := self._next_output()) is not None:
                self._carry_out(output)
        finally:
            self._draining = None

    def _next_output(self) -> outs.Output | None:
        with self._lock:
            if self._announce:
                # the current status at start (the topic keeps it for late joiners); a server begun
                # before it spins says WAITING first, never a passing INACTIVE a client would act on
                self._announce = False
                if not any(isinstance(output, outs.PublishStatus) for output in self._outbox):
                    status = machine.status_message(self._state, self.now())
                    self._outbox.appendleft(outs.PublishStatus(message=status))
            return self._outbox.popleft() if self._outbox else None

    def _carry_out(self, output: outs.Output) -> None:
        if self._observer is not None:
            self._observer(output)
        if self._children.carry_out(output):  # (and a child that ended is forgotten, whatever the output)
            return
        if isinstance(output, outs.PublishStatus):
            self._ros.status.publish(convert.status_to_ros(output.message))
        elif isinstance(output, outs.PublishFeedback):
            handle = self._handles.get(output.goal_uuid)
            if handle is not None:
                handle.publish_feedback(convert.feedback_to_ros(output.feedback))
        elif isinstance(output, outs.AnswerGoal):
            self._handles.pop(output.goal_uuid, None)
            self._owed.keep(output, time.monotonic())  # for a client that asks after rclpy forgot it
            future = self._answers.get(output.goal_uuid)  # the goal's execute callback takes it
            if future is not None:
                future.set_result(output)
        elif isinstance(output, outs.PublishBegin):
            message = convert.begin_to_ros(output.message)
            self._ros.begin.publish(message)
            self._ros.fleet_begin.publish(message)
        else:
            _carry_out_effect(self, output)


def _carry_out_effect(server: DynamicEventServer, output: outs.Output) -> None:
    """Carry out an output that is neither an answer, a publication nor a child's: stubbornness, the
    run's end, an interruption confirmed, a log line, a notice."""
    if isinstance(output, outs.StubbornBegin):
        server._log.info(f"stubborn for {output.period:g} s")
    if isinstance(output, (outs.StubbornBegin, outs.StubbornEnd)):
        server._ros.refresh(isinstance(output, outs.StubbornBegin))
    if carry_out_stubbornness(server._stubbornness, output):
        return
    if isinstance(output, outs.DynamicEventFinished):
        server._log.info(f"dynamic event finished: {output.status}")
        if server._on_finished is not None:
            server._on_finished(output.status)
    elif isinstance(output, outs.InterruptConfirmed):
        if server._on_interrupt_confirmed is not None:
            server._on_interrupt_confirmed()
    elif isinstance(output, outs.Log):
        _LOG_CALLS[output.entry.tier](server._log, output.entry.text)
    elif isinstance(output, outs.StubbornClamped):
        server._log.warning(f"stubborn_period {output.requested:g} s clamped to {output.applied:g} s")
    elif isinstance(output, (outs.SeqWrapped, outs.Ignored)):
        server._log.debug(repr(output))


def _abort_at_once(why: str) -> Callable[[Any], Any]:
    def execute(goal_handle: Any) -> Any:
        goal_handle.abort()
        return DynamicEvent.Result(execution_failure=why)

    return execute


#: How a goal handle moves its goal to each terminal status an answer may have.
_TERMINAL_CALLS: dict[GoalStatus, Callable[[Any], Any]] = {
    GoalStatus.SUCCEEDED: lambda handle: handle.succeed(),
    GoalStatus.CANCELED: lambda handle: handle.canceled(),
    GoalStatus.ABORTED: lambda handle: handle.abort(),
}
_LOG_CALLS: dict[str, Callable[[Any, str], Any]] = {
    Tier.UNINITIALIZED.value: lambda log, text: log.info(text),
    Tier.INFO.value: lambda log, text: log.info(text),
    Tier.WARNING.value: lambda log, text: log.warning(text),
    Tier.ERROR.value: lambda log, text: log.error(text),
}
