"""A client of one robot that cannot be left unspun: it owns its ROS context, node and spinning thread.

:class:`RobotClient` is the blocking form, a context manager::

    with RobotClient("tinyRobot", "tinyRobot1") as robot:
        robot.ready(10.0)
        outcome = robot.next("go_to_place", '"pantry"').wait(90.0)
        robot.finish().wait(10.0)

:class:`AsyncRobotClient` is the same for an asyncio program: every command is awaitable, rclpy spins
in its own thread, and each answer is handed to the event loop thread-safely, so a coroutine that
waits costs nothing::

    async with AsyncRobotClient("tinyRobot", "tinyRobot1") as robot:
        await robot.ready(10.0)
        outcome = await robot.next("go_to_place", '"pantry"')

Both start ROS 2 in a context of their own (``ros_args`` are ROS 2's command-line arguments: remaps,
``--log-level``...), so that several clients, and a program's own rclpy use, do not meet; each
close-down is bounded.  For many robots in one process, :class:`RobotClients` is one context, node
and spinning thread that their clients share (``hub=``).
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable, Sequence
from typing import Any

from dynevent import client as cl
from dynevent.client.run import loop_future, on_loop
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.errors import LocalError, RobotNotReady
from dynevent.ros.client import DynamicEventClient, GoalRun
from dynevent.ros.graph import no_server_text
from dynevent.ros.spinning import Session, bounded_close

__all__ = ["AsyncRobotClient", "RobotClient", "RobotClients"]

Result = cl.Outcome | cl.Refused


class RobotClients:
    """One ROS context, node and spinning thread that the clients of many robots share: what a
    program that drives many robots (a web back end with a client per robot) opens once.  Each
    :class:`RobotClient` or :class:`AsyncRobotClient` made with ``hub=`` this goes on its node::

        with RobotClients() as hub:
            with RobotClient("tinyRobot", "tinyRobot1", hub=hub) as one, \
                 RobotClient("tinyRobot", "tinyRobot2", hub=hub) as two:
                ...

    A robot's own client costs a context, a DDS participant and a thread; on a hub it costs its
    subscriptions and action client alone (bench/ros_async_idle.py, docs/ros.md)."""

    def __init__(self, *, node_name: str = "dynevent_clients", ros_args: Sequence[str] = ()) -> None:
        self._settings = (node_name, tuple(ros_args))
        self._session: Session | None = None

    def _open(self) -> Session:
        if self._session is None:
            raise LocalError("the hub is not open: use `with RobotClients() as hub` or open()")
        return self._session

    @property
    def node(self) -> Any:
        """The node the hub's clients go on (open)."""
        return self._open().node

    def paused(self) -> contextlib.AbstractContextManager[None]:
        """The hub's spinning paused while a client of it is made or destroyed."""
        return self._open().spinner.paused()

    def open(self) -> RobotClients:
        """Start ROS in a context of the hub's, make its node and spin it."""
        if self._session is None:
            node_name, ros_args = self._settings
            self._session = Session(node_name, ros_args, own_context=True, thread="dynevent-clients")
            self._session.start()
        return self

    def close(self) -> None:
        """Stop spinning and destroy the node and the context (bounded): close its clients first."""
        if self._session is not None:
            self._session.close()
            self._session = None

    def __enter__(self) -> RobotClients:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()


class RobotClient:
    """A :class:`~dynevent.ros.client.DynamicEventClient` of ``fleet``/``robot`` with its own ROS
    context, node (``node_name``) and spinning thread, started by ``with`` (or :meth:`open`) and
    stopped at its end (or :meth:`close`).  The commands return a :class:`~dynevent.ros.GoalRun`.
    ``categories``, ``validators`` and ``trace`` are the client's (see DynamicEventClient); with
    ``hub`` (an open :class:`RobotClients`), the client goes on the hub's node instead."""

    def __init__(
        self,
        fleet: str,
        robot: str,
        *,
        node_name: str = "dynevent_client",
        ros_args: Sequence[str] = (),
        categories: Any = None,
        validators: Any = None,
        trace: TraceWriter | None = None,
        hub: RobotClients | None = None,
    ) -> None:
        self.fleet, self.robot = fleet, robot
        self._settings = (node_name, tuple(ros_args), categories, validators, trace)
        self._hub = hub
        self._client: DynamicEventClient | None = None
        self._session: Session | None = None
        self._node: Any = None  # the node the client is on: its own session's, or the hub's

    # ---------------------------------------------------------------- life

    def open(self) -> RobotClient:
        """Start ROS in a context of this client's, make its node and client, and spin them; or, with
        a ``hub``, make the client on the hub's node, which the hub spins."""
        if self._client is not None:
            return self
        node_name, ros_args, categories, validators, trace = self._settings
        settings = {"categories": categories, "validators": validators, "trace": trace}
        if self._hub is not None:
            self._node = self._hub.node
            with self._hub.paused():  # the hub's executor never meets a half-made client
                self._client = DynamicEventClient(self._node, self.fleet, self.robot, **settings)
            return self
        thread = f"dynevent-{self.fleet}-{self.robot}"
        self._session = Session(node_name, ros_args, own_context=True, thread=thread)
        # the client is made whole before an executor thread can meet it (docs/ros.md)
        self._node = self._session.node
        self._client = DynamicEventClient(self._node, self.fleet, self.robot, **settings)
        self._session.start()
        return self

    def close(self) -> None:
        """Stop spinning and destroy the client, its node and its context (bounded); a hub's client
        only destroys its own entities (the hub closes the rest)."""
        if self._client is None:
            return
        if self._session is not None:
            self._session.close(self._client.destroy)
        else:
            assert self._hub is not None
            with bounded_close(), self._hub.paused():  # nothing destroyed under the hub's spinning thread
                self._client.destroy()
        self._client = self._session = self._node = None

    def __enter__(self) -> RobotClient:
        return self.open()

    def __exit__(self, *exc: object) -> None:
        self.close()

    # ---------------------------------------------------------------- use

    @property
    def client(self) -> DynamicEventClient:
        """The binding's client this one spins (open)."""
        if self._client is None:
            raise LocalError(f"the client of {self.fleet}/{self.robot} is not open: use `with` or open()")
        return self._client

    @property
    def state(self) -> cl.ClientState:
        """The client machine's view of the robot and of the open goals."""
        return self.client.state

    def ready(self, timeout: float = 10.0) -> None:
        """Wait, at most ``timeout`` seconds in all, for the robot's server and its status; raises
        :class:`~dynevent.errors.RobotNotReady` saying which was missing (and which servers the graph
        has)."""
        client = self.client
        if not client.wait_for_server(timeout):
            raise RobotNotReady(no_server_text(self._node, self.fleet, self.robot, timeout))
        if not client.wait_for_status(timeout):
            raise RobotNotReady(f"no status from {self.fleet}/{self.robot} within {timeout:g} s")

    def next(
        self,
        category: str,
        description: str,
        *,
        stubborn_period: float = 0.0,
        timeout: float | None = None,
        on_progress: Callable[[cl.Progress], None] | None = None,
    ) -> GoalRun:
        """A NEXT: run this event (see :meth:`DynamicEventClient.next`)."""
        return self.client.next(
            category, description, stubborn_period=stubborn_period, timeout=timeout, on_progress=on_progress
        )

    def cancel(self, on_progress: Callable[[cl.Progress], None] | None = None) -> GoalRun:
        """A CANCEL naming the running child."""
        return self.client.cancel(on_progress)

    def finish(self) -> GoalRun:
        """FINISHED: the dynamic event is over."""
        return self.client.finish()

    def withdraw(self, run: GoalRun) -> None:
        """No longer want this NEXT: its child is cancelled once it is known to run
        (:meth:`DynamicEventClient.withdraw`)."""
        self.client.withdraw(run)


class AsyncRobotClient:
    """:class:`RobotClient` for asyncio: ``async with``, and every command awaitable on the running
    loop.  ``on_progress`` callbacks are called on the loop's thread."""

    def __init__(self, fleet: str, robot: str, **settings: Any) -> None:
        self._robot = RobotClient(fleet, robot, **settings)
        self._loop: asyncio.AbstractEventLoop | None = None

    async def __aenter__(self) -> AsyncRobotClient:
        self._loop = asyncio.get_running_loop()
        await asyncio.to_thread(self._robot.open)
        return self

    async def __aexit__(self, *exc: object) -> None:
        await asyncio.to_thread(self._robot.close)

    @property
    def state(self) -> cl.ClientState:
        """The client machine's view of the robot and of the open goals."""
        return self._robot.state

    async def ready(self, timeout: float = 10.0) -> None:
        """Wait for the robot's server and status (see :meth:`RobotClient.ready`), off the loop."""
        await asyncio.to_thread(self._robot.ready, timeout)

    def _awaitable(self, run: GoalRun) -> asyncio.Future[Result]:
        return loop_future(self._running_loop(), run)

    def _on_loop(
        self, callback: Callable[[cl.Progress], None] | None
    ) -> Callable[[cl.Progress], None] | None:
        return on_loop(self._running_loop(), callback)

    def _running_loop(self) -> asyncio.AbstractEventLoop:
        if self._loop is None:
            raise LocalError("use `async with AsyncRobotClient(...)` first")
        return self._loop

    def next(
        self,
        category: str,
        description: str,
        *,
        stubborn_period: float = 0.0,
        timeout: float | None = None,
        on_progress: Callable[[cl.Progress], None] | None = None,
    ) -> asyncio.Future[Result]:
        """A NEXT; await it for its :class:`~dynevent.client.Outcome` (or a
        :class:`~dynevent.client.Refused`)."""
        run = self._robot.next(
            category, description, stubborn_period=stubborn_period, timeout=timeout,
            on_progress=self._on_loop(on_progress),
        )  # fmt: skip
        return self._awaitable(run)

    def cancel(self, on_progress: Callable[[cl.Progress], None] | None = None) -> asyncio.Future[Result]:
        """A CANCEL naming the running child; await it for its outcome."""
        return self._awaitable(self._robot.cancel(self._on_loop(on_progress)))

    def finish(self) -> asyncio.Future[Result]:
        """FINISHED; await it for its outcome."""
        return self._awaitable(self._robot.finish())
