"""An executor on a thread of its own, and a process's ROS 2 closed down to its DDS participant.

Both exist because rclpy's own ways of ending leave things running that a
command line must not leave behind:

- ``Executor.shutdown`` (rclpy 9.1.2) destroys the executor's guard condition
  without waiting for the thread that spins it, which may be building a wait
  set with it at that moment (rclpy issue #968). :class:`Spinner` instead
  stops on a flag, woken by the executor's guard condition, so its thread is
  known to be out of rclpy before anything is destroyed.
- ``destroy_node`` leaves a node's action servers and clients alive, and
  ``rclpy.shutdown`` leaves the context's DDS participant alive, until the
  garbage collector or the interpreter's exit gets to them: a participant
  deleted by a static destructor at exit can hang the process (Fast DDS), and
  until it is deleted other processes still see its endpoints.
  :func:`close_down` destroys all of it, in order, while the process is whole.
"""

from __future__ import annotations

import contextlib
import faulthandler
import threading
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from typing import Any

from rclpy.executors import ExternalShutdownException

from dynevent.errors import LocalError

__all__ = ["CLOSE_BOUND", "Session", "Spinner", "bounded_close", "close_down", "init"]


def init(ros_args: Sequence[str] = (), context: Any = None) -> None:
    """``rclpy.init`` of ``context`` (the default one when None) with the command line's ROS arguments
    (``--ros-args`` and what follows it: remaps, ``__ns:=``, ``--log-level``, ``-p`` parameters), as any
    ROS 2 program takes them.  Arguments rcl refuses are one line,
    :class:`~dynevent.errors.LocalError`, naming them."""
    import rclpy

    try:
        rclpy.init(args=["dynevent", *ros_args], context=context)
    except Exception as exc:  # rcl's parse errors (RCLError, RCLInvalidROSArgsError) are not exported
        rclpy.try_shutdown(context=context)
        raise LocalError(
            f"{' '.join(ros_args)}: ROS refused these arguments: {str(exc).splitlines()[0]}"
        ) from None


#: How often :meth:`Spinner.stop` wakes the spinning thread while it waits for it to leave (seconds).
WAKE_EVERY = 0.1
#: How long a spinning thread with ``on_fault`` pauses after an exception (seconds).
FAULT_PAUSE = 0.1
#: The longest a process's ROS close-down may take (seconds); then it is ended with every thread's
#: stack on standard error (:func:`bounded_close`).
CLOSE_BOUND = 20.0


class Spinner:
    """``executor`` spun on a daemon thread named ``name`` until :meth:`stop`.  An exception the executor
    raises (a callback's) ends the thread, unless ``on_fault`` is given: then it is told, and the thread
    spins on after :data:`FAULT_PAUSE` (one robot's fault does not stop the robots that share its
    executor, and a fault of every pass costs no core)."""

    def __init__(self, executor: Any, name: str, on_fault: Callable[[Exception], None] | None = None) -> None:
        self.executor = executor
        self.on_fault = on_fault
        self._stopping = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True, name=name)

    def start(self) -> None:
        """Start spinning."""
        self._thread.start()

    def _spin(self) -> None:
        # No timeout on the wait: an idle executor must cost nothing (a timed wait wakes, rebuilds its
        # wait set from every entity, and makes a timer, each time).  The executor's own wake-up (its
        # guard condition) only makes it look again, so the stop flag is its wait condition: rclpy's
        # single-threaded executor checks it each time its wait returns.
        spin_once = getattr(self.executor, "_spin_once_impl", None)
        with contextlib.suppress(ExternalShutdownException):
            while not self._stopping.is_set():
                try:
                    if spin_once is not None:
                        spin_once(None, self._stopping.is_set)
                    else:  # an executor without it: a bounded wait, looked at once a second
                        self.executor.spin_once(timeout_sec=1.0)
                except Exception as fault:
                    if self.on_fault is None or isinstance(fault, ExternalShutdownException):
                        raise
                    self.on_fault(fault)
                    self._stopping.wait(FAULT_PAUSE)  # a fault of every pass (its wait set's) costs no core

    @contextlib.contextmanager
    def paused(self, timeout: float = 5.0) -> Iterator[None]:
        """The thread leaves its loop (the executor kept) while the caller makes or destroys entities
        of its nodes, then spins again: rclpy's executor builds its wait set from every entity, and
        one destroyed under it ends the thread ("cannot use Destroyable").  Raises
        :class:`~dynevent.errors.LocalError` when the thread does not leave within ``timeout``."""
        if not self._left(timeout):
            raise LocalError(f"{self._thread.name}: the spinning thread did not pause within {timeout:g} s")
        try:
            yield
        finally:
            self._stopping = threading.Event()
            self._thread = threading.Thread(target=self._spin, daemon=True, name=self._thread.name)
            self._thread.start()

    def _left(self, timeout: float) -> bool:
        """Ask the thread to leave its loop and wait (at most ``timeout`` seconds); True if it did."""
        self._stopping.set()
        deadline = time.monotonic() + timeout
        while self._thread.is_alive() and time.monotonic() < deadline:
            self.executor.wake()  # its guard condition: the wait returns, the loop sees the flag
            self._thread.join(WAKE_EVERY)
        return not self._thread.is_alive()

    def stop(self, timeout: float = 5.0) -> bool:
        """Stop spinning and wait (at most ``timeout`` seconds) for the thread to leave; True if it did.
        The executor is shut down only then, so nothing of it is destroyed under the thread."""
        if not self._left(timeout):
            return False
        self.executor.shutdown(timeout_sec=0)
        return True


class Session:
    """A node named ``node_name`` and its executor, spun on a thread of its own from :meth:`start`:
    in the process's default context (started here with ``ros_args`` unless it is), or with
    ``own_context`` in a context, and so a DDS participant, of its own; ``thread`` names the thread.
    :meth:`close` ends it all, bounded."""

    def __init__(
        self, node_name: str, ros_args: Sequence[str] = (), *, own_context: bool = False, thread: str = ""
    ) -> None:
        import rclpy
        from rclpy.executors import SingleThreadedExecutor

        self.context = rclpy.Context() if own_context else None
        if own_context or not rclpy.ok():  # the default context once, for every session on it
            init(ros_args, self.context)
        elif ros_args:
            raise LocalError(
                f"{' '.join(ros_args)}: ROS is already started in this process, with arguments of its own"
            )
        self.node = rclpy.create_node(node_name, context=self.context)
        executor = SingleThreadedExecutor(context=self.context)
        executor.add_node(self.node)
        self.spinner = Spinner(executor, thread or node_name.replace("_", "-"))

    def start(self) -> None:
        """Spin the node."""
        self.spinner.start()

    def close(self, *first: Callable[[], object], bound: float = CLOSE_BOUND) -> None:
        """Stop spinning, call each of ``first`` (what is to be destroyed before the node), destroy the
        node and the context: all within ``bound`` seconds (:func:`bounded_close`)."""
        with bounded_close(bound):
            self.spinner.stop()
            for destroy in first:
                destroy()
            close_down([self.node], self.context)


def close_down(nodes: Iterable[Any], context: Any = None) -> None:
    """Destroy ``nodes`` with their action servers and clients, then shut down and destroy ``context``
    (the default context when None): its DDS participant is deleted here, not at the interpreter's exit.
    Stop every :class:`Spinner` of these nodes first."""
    import rclpy

    for node in nodes:
        for waitable in list(node.waitables):
            destroy = getattr(waitable, "destroy", None)
            if destroy is not None:
                destroy()
        node.destroy_node()
    if context is None:  # retired: the next rclpy.init of this process starts a new default context
        context = rclpy.get_default_context(shutting_down=True)
    rclpy.try_shutdown(context=context)
    destroy = getattr(context, "destroy", None)  # rclpy 9 (Kilted); older ones free it with the object
    if destroy is not None:
        destroy()


@contextlib.contextmanager
def bounded_close(bound: float = CLOSE_BOUND) -> Iterator[None]:
    """Bound a close-down: if it has not ended after ``bound`` seconds, faulthandler writes every
    thread's stack to standard error and ends the process (exit status 1).  The watch runs outside
    Python's lock, so it fires even if the close-down hangs inside the middleware."""
    faulthandler.dump_traceback_later(bound, exit=True)
    try:
        yield
    finally:
        faulthandler.cancel_dump_traceback_later()
