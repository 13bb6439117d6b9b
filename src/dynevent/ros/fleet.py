"""A fleet of simulated robots on ROS 2: what ``dynevent serve`` (:mod:`dynevent.tools.live.serve`)
serves, each robot a :class:`~dynevent.ros.server.DynamicEventServer` whose children are simulated
doing what their descriptions say (:class:`~dynevent.sim.children.SimulatedChild` on the node's
timers), the robots in lanes of :data:`LANE` (a node and an executor thread each).

The robots' action servers can be introspected, and a robot's ``send_goal`` service events followed
(:class:`GoalEvent`, naming the client that sent each goal) by a node in a context of its own:
the fleet's participants match none of their own endpoints (:mod:`dynevent.ros.participant`).
"""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable, Sequence
from typing import Any, NamedTuple

from rcl_interfaces.msg import ParameterDescriptor, SetParametersResult
from rclpy.logging import LoggingSeverity

from dynevent.errors import InvalidMessage
from dynevent.ros import convert
from dynevent.ros.convert import RosDescription, describe_type
from dynevent.ros.qos import latched
from dynevent.ros.server import DynamicEventServer
from dynevent.ros.spinning import CLOSE_BOUND, Session, bounded_close, close_down
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.adapter import ChildExecution
from dynevent.server.machine import ServerConfig, State
from dynevent.server.store import StateStore
from dynevent.sim.children import SimulatedChild, Whereabouts
from dynevent.sim.config import DEFAULT_DESCRIPTION, ServeConfig
from dynevent.wire.messages import Goal

__all__ = [
    "BEGIN_COMMAND_TOPIC",
    "CLOSE_PER_ROBOT",
    "FLEET",
    "INTERRUPTED",
    "LANE",
    "Fleet",
    "GoalEvent",
    "SimulatedChildren",
    "serve_node_name",
]

#: Publish a DynamicEventDescription naming a robot here to begin a dynamic event for it.
BEGIN_COMMAND_TOPIC = "dynevent/serve/begin"

#: A robot's task is interrupted while its parameter ``interrupted.<robot>`` (a bool, on the node of
#: its shard) is true (R14): setting it interrupts or resumes the task, and a run it begins is begun
#: so (R3.1).  A parameter, not a topic: its set is a service call, answered once the server took it.
INTERRUPTED = "interrupted"

#: The fleet a shard serves: a read-only parameter of its node.
FLEET = "fleet"

#: Robots per lane: one node and one executor thread each.  rclpy's executor walks every entity of
#: its nodes at each wake-up, so a wake-up costs in proportion to the robots it serves: 2,000 robots
#: on one executor served 56 goals a second per core, in lanes of 64 several times more
#: (docs/performance.md).  The lanes' threads share the GIL; a lane waits for DDS without it.
LANE = int(os.environ.get("DYNEVENT_SERVE_LANE", "64"))

#: How much longer than :data:`~dynevent.ros.spinning.CLOSE_BOUND` a close-down may take per robot
#: served (seconds): destroying the entities of a fleet costs more the more there are.
CLOSE_PER_ROBOT = 0.1


def serve_node_name(fleet: str, shard: tuple[int, int] = (1, 1)) -> str:
    """The name of the node that holds a serve process's parameters (of its first lane): by fleet and
    shard, so that two processes on one graph never share it."""
    index, count = shard
    return f"dynevent_serve_{fleet}" + ("" if count == 1 else f"_{index}_of_{count}")


class SimulatedChildren:
    """One robot's children, run on the node's timers, doing what their descriptions say (a
    :class:`~dynevent.server.adapter.ChildEvents`)."""

    def __init__(self, node: Any, config: ServeConfig) -> None:
        self._node = node
        self._config = config
        self._robot = Whereabouts()
        self._timers: dict[ChildExecution, Any] = {}  # by execution: each run numbers its children anew
        self._lock = threading.Lock()

    def start(self, execution: ChildExecution) -> None:
        child = SimulatedChild(execution.category, execution.parsed, self._config, self._robot)
        began = time.monotonic()

        def report() -> None:
            if child.report(execution, time.monotonic() - began):
                self._forget(execution)

        with self._lock:
            self._timers[execution] = self._node.create_timer(child.period, report)

    def _forget(self, execution: ChildExecution) -> None:
        with self._lock:
            timer = self._timers.pop(execution, None)
        if timer is not None:
            self._node.destroy_timer(timer)

    def cancel(self, execution: ChildExecution) -> None:
        """The child stops at its next report."""

    def kill(self, execution: ChildExecution) -> None:
        """The child stops at its next report."""

    def interrupt(self, execution: ChildExecution) -> None:
        """Simulated children do not pause."""

    def resume(self, execution: ChildExecution) -> None:
        """Simulated children do not pause."""


class GoalEvent(NamedTuple):
    """A goal request as a robot's action server received it (its ``send_goal`` service event): the
    GID of the client that sent it, the goal's UUID, the goal, and when it arrived (ns)."""

    client_gid: bytes
    goal_uuid: str
    goal: Goal
    arrived: int

    @classmethod
    def from_ros(cls, message: Any) -> GoalEvent | None:
        """The event's goal request, or None for another event or one whose goal is not valid (the
        server refuses it as it stands)."""
        if message.info.event_type != _REQUEST_RECEIVED or not message.request:
            return None
        request = message.request[0]
        try:
            goal = convert.goal_from_ros(request.goal)
            uuid = convert.uuid_from_ros(request.goal_id)
        except (InvalidMessage, ValueError):
            return None
        stamp = message.info.stamp
        return cls(bytes(message.info.client_gid), uuid, goal, stamp.sec * 1_000_000_000 + stamp.nanosec)


#: ``service_msgs/ServiceEventInfo.REQUEST_RECEIVED``.
_REQUEST_RECEIVED = 1


class _Lane(Session):
    """A node of the fleet's robots, with its own single-threaded executor and thread."""

    def __init__(self, name: str, on_fault: Callable[[str, Exception], None] | None) -> None:
        super().__init__(name)  # its thread: the name, dashed
        if on_fault is not None:
            self.spinner.on_fault = lambda fault: on_fault(name, fault)
        self.node.get_logger().set_level(LoggingSeverity.WARN)  # the live log says the rest


class Fleet:
    """The robots of ``config`` one process serves (its shard), on lanes of :data:`LANE`, each from its
    state in ``store`` when it has one; with ``follow``, a node in a context of its own (started with
    ``ros_args``) follows the robots' goal events; ``on_fault`` hears what a callback of a lane raises
    (the lane's name, the exception: the lane spins on).  ROS must be initialised (the default context)."""

    def __init__(
        self,
        config: ServeConfig,
        machine_config: ServerConfig,
        store: StateStore | None,
        *,
        follow: bool = False,
        ros_args: Sequence[str] = (),
        on_fault: Callable[[str, Exception], None] | None = None,
    ) -> None:
        self.config = config
        self.store = store
        self.machine_config = machine_config
        base = serve_node_name(config.fleet, config.shard)
        robots = config.served()
        self.lanes = [
            _Lane(base if start == 0 else f"{base}_lane_{start // LANE}", on_fault)
            for start in range(0, max(len(robots), 1), LANE)
        ]
        self.lane_of = {robot: self.lanes[position // LANE] for position, robot in enumerate(robots)}
        self.follower = Session(f"{base}_judge", ros_args, own_context=True) if follow else None
        if self.follower is not None:
            self.follower.node.get_logger().set_level(LoggingSeverity.WARN)
        self.node = self.lanes[0].node  # the fleet-wide begin publisher and the begin commands
        self.begins = DynamicEventServer.fleet_begin_publisher(self.node)
        self.servers: dict[str, DynamicEventServer] = {}
        self.rebegin_timers: dict[str, Any] = {}
        # the description query (R16) as dynevent offers it; rmf_ros2 has none (D17), nor has a
        # rmf_task_msgs without the project's DescribeDynamicEvent
        self.description_service = describe_type() if config.offers_description else None
        self._timers_lock = threading.Lock()  # begin commands arrive on lane 0's thread
        begun = self._on_begin_command
        self.node.create_subscription(RosDescription, BEGIN_COMMAND_TOPIC, begun, latched(10))
        read_only = ParameterDescriptor(description="the fleet this node serves robots of", read_only=True)
        self.node.declare_parameter(FLEET, config.fleet, read_only)
        self.node.add_on_set_parameters_callback(self._on_parameters)

    def add(
        self,
        robot: str,
        restored: State | None,
        *,
        observer: Callable[[outs.Output | outs.Rejected], None],
        on_step: Callable[[ins.Input, tuple[outs.Output, ...]], None],
        introspection: bool = False,
        on_goal: Callable[[GoalEvent], None] | None = None,
    ) -> bool:
        """Serve ``robot``, from its restored state if any; a robot with no active run begins one.  With
        ``introspection`` (or ``on_goal``) its action server's service events are published, and
        ``on_goal`` hears its goal requests from its first goal on (the events kept include that
        goal's).  True when the goal requests are heard so."""
        fleet, store, lane = self.config.fleet, self.store, self.lane_of[robot]
        following: list[Callable[[], None]] = []
        interrupted = self._declare_interrupted(robot, restored is not None and restored.interrupted)

        def stepped(event: ins.Input, outputs: tuple[outs.Output, ...]) -> None:
            if following and isinstance(event, (ins.GoalRequested, ins.GoalSubmitted)):
                following.pop()()  # 1,000 followers at once would take half a minute to start
            on_step(event, outputs)

        server = DynamicEventServer(
            lane.node, fleet, robot, self.machine_config, SimulatedChildren(lane.node, self.config),
            begin_publisher=self.begins, description_service=self.description_service,
            state=restored or self.config.first_state(robot),
            on_state=store.save if store is not None else None,
            on_answers=(lambda answers: store.keep_answers(fleet, robot, answers)) if store else None,
            answers=store.answers(fleet, robot) if store is not None else None,
            observer=observer, on_finished=lambda status: self._finished(robot), on_step=stepped,
        )  # fmt: skip
        introspected = (introspection or on_goal is not None) and server.introspect()
        told, follower = on_goal, self.follower
        heard = bool(introspected and told is not None and follower is not None)
        if introspected and told is not None and follower is not None:

            def heard_goal(message: Any) -> None:
                event = GoalEvent.from_ros(message)
                if event is not None:
                    told(event)

            following.append(lambda: server.follow(heard_goal, follower.node))
        self.servers[robot] = server
        if restored is not None:
            server.restart()
        if not server.state.active:
            server.begin(DEFAULT_DESCRIPTION, 1, interrupted=interrupted)
        elif server.state.interrupted != interrupted:  # restored, and started with the other value
            (server.interrupt if interrupted else server.resume)()
        return heard

    def _declare_interrupted(self, robot: str, restored: bool) -> bool:
        """``robot``'s :data:`INTERRUPTED` parameter declared, as restored or as ``--ros-args -p`` sets it."""
        descriptor = ParameterDescriptor(description=f"{robot}'s task is interrupted (R14)")
        return bool(self.node.declare_parameter(f"{INTERRUPTED}.{robot}", restored, descriptor).value)

    def _on_parameters(self, parameters: list[Any]) -> SetParametersResult:
        """A robot's :data:`INTERRUPTED` set: its task interrupted or resumed before the set is answered."""
        for parameter in parameters:
            robot = parameter.name.removeprefix(f"{INTERRUPTED}.")
            server = self.servers.get(robot) if parameter.name != robot else None
            value = parameter.value
            if server is not None and isinstance(value, bool) and value != server.state.interrupted:
                (server.interrupt if value else server.resume)()
        return SetParametersResult(successful=True)

    def _finished(self, robot: str) -> None:
        if self.config.rebegin > 0:
            node = self.lane_of[robot].node
            timer = node.create_timer(self.config.rebegin, lambda: self.begin_again(robot))
            with self._timers_lock:
                self.rebegin_timers[robot] = timer

    def begin_again(self, robot: str, description: str = DEFAULT_DESCRIPTION) -> None:
        """Begin a dynamic event for ``robot`` now."""
        with self._timers_lock:
            timer = self.rebegin_timers.pop(robot, None)
        if timer is not None:
            self.lane_of[robot].node.destroy_timer(timer)
        interrupted = bool(self.node.get_parameter(f"{INTERRUPTED}.{robot}").value)
        self.servers[robot].begin(description, 1, interrupted=interrupted)

    def _on_begin_command(self, message: Any) -> None:
        if message.fleet == self.config.fleet and message.robot in self.servers:
            self.begin_again(message.robot, message.description or DEFAULT_DESCRIPTION)

    def start(self) -> None:
        """Spin every lane (and the follower)."""
        for lane in self.lanes:
            lane.start()
        if self.follower is not None:
            self.follower.start()

    def shut_down(self) -> None:
        """Shut every robot down (R15.1, R15.2) and stop spinning, once the answers have gone out."""
        for server in self.servers.values():
            server.shutdown()
        time.sleep(0.2)  # let the shutdown answers go out before the node goes
        with bounded_close():
            for lane in self.lanes:
                lane.spinner.stop()
            if self.follower is not None:
                self.follower.spinner.stop()

    def destroy(self) -> None:
        """Destroy every entity, node and context (after :meth:`shut_down`), bounded in proportion to
        the robots: destroying a fleet's entities takes time in proportion to the square of their
        number (docs/performance.md)."""
        with bounded_close(CLOSE_BOUND + CLOSE_PER_ROBOT * len(self.servers)):
            for server in self.servers.values():
                server.destroy()
            if self.follower is not None:
                close_down([self.follower.node], self.follower.context)
            close_down([lane.node for lane in self.lanes])
