"""What the ROS tests share: whether ROS 2 is here, the graph fixture's class, bounded waits."""

from __future__ import annotations

import contextlib
import fcntl
import importlib.util
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import zlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any, TypeVar

T = TypeVar("T")

ROS = all(importlib.util.find_spec(name) is not None for name in ("rclpy", "rmf_task_msgs"))
WHY = (
    "ROS 2 is not importable (rclpy, rmf_task_msgs): run tests/ros/setup-ros-env.sh, then . build/ros/env.sh"
)

#: The longest any ROS test may take, in seconds; then the process is ended with every thread's stack
#: (tests/conftest.py puts them in the failure report).  A backstop for a hang in the test's own process,
#: never a bound on how fast the machine is: it lies above every single bounded wait of a test (a child
#: process's, up to 90 s), so that a process that hangs is caught by the wait for it, which says where
#: it hung, native stacks included (:func:`stacks_of`), instead of taking the test's worker down.
TEST_DEADLINE = 600
#: The bound of every single wait in the ROS tests, in seconds.
WAIT = 15.0
#: The bound on a child process's start (a Python interpreter importing rclpy, on a loaded machine):
#: kept apart from WAIT so that a slow start is never mistaken for a discovery or protocol failure.
START = 60.0


def child_env() -> dict[str, str]:
    """The environment of a process under test: this one's, with faulthandler on, so that a process
    ended by :func:`stacks_of` prints every thread's Python stack."""
    return {**os.environ, "PYTHONFAULTHANDLER": "1"}


def stacks_of(process: subprocess.Popen[Any]) -> str:
    """Every thread's stack of a process that did not end in time, native (gdb, when the machine has it)
    and Python (faulthandler, which ``SIGABRT`` sets off: the process ends), for a failure message that
    says where it hung rather than only that it did."""
    native = ""
    if shutil.which("gdb") is not None:
        try:
            traced = subprocess.run(
                ["gdb", "-p", str(process.pid), "-batch", "-ex", "thread apply all bt"],
                capture_output=True,
                text=True,
                timeout=WAIT * 4,
                check=False,
            )
            native = traced.stdout[-30_000:]
        except subprocess.TimeoutExpired:
            native = "(gdb did not finish)"
    if process.poll() is None:
        process.send_signal(signal.SIGABRT)
    return f"native stacks (gdb):\n{native}"


def finish(process: subprocess.Popen[str], timeout: float) -> subprocess.CompletedProcess[str]:
    """A process started with piped text output, once it ends (at most ``timeout`` seconds): its exit
    code, standard output and error.  One that does not end fails the test with its output and
    every thread's stack (:func:`stacks_of`)."""
    try:
        stdout, stderr = process.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        stacks = stacks_of(process)
        stdout, stderr = process.communicate(timeout=WAIT)  # faulthandler's Python stacks at the end
        command = " ".join(str(word) for word in process.args)  # type: ignore[union-attr]
        raise AssertionError(
            f"{command} did not end within {timeout:g} s; its output:\n{stdout}{stderr or ''}\n{stacks}"
        ) from None
    return subprocess.CompletedProcess(process.args, process.returncode, stdout, stderr or "")


#: How many DDS domains the tests choose among (0 to 101 are safe on Linux; 0 is left to a default
#: ROS install).
DOMAINS = 100


def domain_of(environ: Mapping[str, str]) -> int:
    """The DDS domain this test process prefers: one per test run, and under pytest-xdist one per
    worker, so that two ROS tests running at once never meet (:func:`keep_dds_local` then skips a
    domain another test process on this machine holds, so that parallel runs never meet either).

    The run's domain is ``ROS_DOMAIN_ID`` when set (worker ``gwN`` then takes the Nth domain after
    it), else one of 1 to :data:`DOMAINS` drawn at random (under xdist from the run's id, which every
    worker shares; worker ``gwN`` takes the Nth after it, counting round).
    """
    worker = environ.get("PYTEST_XDIST_WORKER", "")
    index = int(worker[2:]) if worker.startswith("gw") and worker[2:].isdigit() else 0
    given = environ.get("ROS_DOMAIN_ID", "")
    if given.isdigit():
        return int(given) + index
    if "PYTEST_XDIST_TESTRUNUID" in environ:
        drawn = zlib.crc32(environ["PYTEST_XDIST_TESTRUNUID"].encode()) % DOMAINS
    else:
        drawn = random.randrange(DOMAINS)
    return 1 + (drawn + index) % DOMAINS


#: The lock files of the domains this process holds, kept open for its lifetime (:func:`claim_domain`).
_HELD: list[int] = []


def claim_domain(preferred: int, directory: str | None = None) -> int:
    """The first domain from ``preferred`` on (counting round :data:`DOMAINS`) that no other test
    process on this machine holds, held by this one until it ends: an exclusive ``flock`` on a file
    per domain in the temporary directory, which the kernel releases when the process ends, however
    it ends.  Two test runs on one machine (or a run and the ROS tests of another clone) thus never
    share a domain, where a domain drawn at random would be shared by 3 pairs of runs in 100."""
    folder = directory if directory is not None else tempfile.gettempdir()
    for step in range(DOMAINS):
        domain = 1 + (preferred - 1 + step) % DOMAINS
        handle = os.open(
            os.path.join(folder, f"dynevent-tests-dds-domain-{domain}.lock"), os.O_RDWR | os.O_CREAT
        )
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(handle)
            continue
        _HELD.append(handle)
        return domain
    raise RuntimeError(f"every DDS domain from 1 to {DOMAINS} is held by another test process")


def keep_dds_local() -> None:
    """A DDS domain of this process's own, which the processes it starts inherit; discovery stays
    on this machine.  The domain is ``ROS_DOMAIN_ID``'s when given (:func:`domain_of`), else the
    first one from :func:`domain_of`'s that no other test process here holds (:func:`claim_domain`)."""
    given = os.environ.get("ROS_DOMAIN_ID", "").isdigit()
    domain = domain_of(os.environ)
    os.environ["ROS_DOMAIN_ID"] = str(domain if given else claim_domain(domain))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    os.environ.pop("ROS_STATIC_PEERS", None)
    os.environ.pop("ROS_LOCALHOST_ONLY", None)


def wait_for(condition: Callable[[], bool], what: str, timeout: float = WAIT) -> None:
    """Wait until ``condition()`` holds, at most ``timeout`` seconds (checked every 10 ms)."""
    event = threading.Event()
    deadline = timeout
    while not condition():
        if deadline <= 0:
            raise AssertionError(f"timed out after {timeout:g} s waiting for {what}")
        event.wait(0.01)
        deadline -= 0.01


class Graph:
    """An rclpy context with nodes spun by a multi-threaded executor on a background thread."""

    def __init__(self) -> None:
        import rclpy
        from rclpy.executors import MultiThreadedExecutor

        self.context = rclpy.Context()
        rclpy.init(context=self.context)
        self.executor = MultiThreadedExecutor(num_threads=4, context=self.context)
        self.nodes: list[Any] = []
        self.died: BaseException | None = None
        self._closing = threading.Event()
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        """Spin until :meth:`close` asks to stop; the executor is shut down only once this returns, so no
        callback of rclpy's own meets an entity already destroyed."""
        from rclpy.executors import ExternalShutdownException

        try:
            with contextlib.suppress(ExternalShutdownException):
                while not self._closing.is_set():
                    self.executor.spin_once(timeout_sec=0.05)
        except BaseException as error:  # the test that owns the graph fails with it, at close
            self.died = error
            raise

    def node(self, name: str, build: Callable[[Any], T] | None = None) -> Any:
        """A new node, spun once ``build(node)`` (if given) has made its entities; returns what it built.

        Entities are made before the node joins the spinning executor: rclpy's ``ActionClient`` is
        added to its node before its lock exists, and an executor that meets it half made dies.
        """
        import rclpy

        node = rclpy.create_node(name, context=self.context)
        built = build(node) if build is not None else node
        self.nodes.append(node)
        self.executor.add_node(node)
        return built

    def close(self) -> None:
        """Stop spinning and destroy everything the graph made, down to its DDS participant.

        rclpy's ``destroy_node`` leaves a node's waitables (action servers and clients) alive, and they
        keep the node, and ``shutdown`` keeps the context's participant, until the garbage collector
        gets to them: a later test's client would meet this test's action servers, still on the graph
        under the same names (the ROS tests' missed discoveries came from there).
        """
        from dynevent.ros.spinning import close_down

        self._closing.set()
        self._thread.join(timeout=5)
        # MultiThreadedExecutor.shutdown (rclpy 9.1.2) destroys the executor's guard condition before
        # it waits for its thread pool, where a callback that found its callback group busy still
        # triggers that guard condition: the task fails ("cannot use Destroyable"), and its exception
        # is printed when the task is collected.  The pool's callbacks end first here.
        self.executor._executor.shutdown(wait=True)
        self.executor.shutdown(timeout_sec=5)
        close_down(self.nodes, self.context)
        if self.died is not None:
            raise AssertionError(f"the executor thread died: {self.died!r}") from self.died


class Child:
    """A Python process under test, with its output read live into ``lines``.

    ``wait_line`` bounds the wait for a line and fails at once, with the whole output, if the process
    has ended; ``stop`` ends it within bounds. Every failure message carries the process's output, so a
    failed run in CI says why the other side was not there.
    """

    def __init__(self, argv: Sequence[str]) -> None:
        self.argv = [sys.executable, *argv]
        self.lines: list[str] = []
        self.process = subprocess.Popen(
            self.argv,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
            env=child_env(),
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    @property
    def output(self) -> str:
        return "\n".join(self.lines)

    def saw(self, text: str) -> bool:
        return any(text in line for line in self.lines)

    def wait_line(self, text: str, timeout: float = START) -> None:
        """Wait until a line containing ``text`` is printed, at most ``timeout`` seconds."""

        def seen_or_ended() -> bool:
            return self.saw(text) or self.process.poll() is not None

        wait_for(seen_or_ended, f"{text!r} from {' '.join(self.argv[1:])}", timeout)
        if not self.saw(text):
            self._reader.join(timeout=WAIT)
            raise AssertionError(
                f"the process ended with {self.process.returncode} before printing {text!r}:\n{self.output}"
            )

    def stop(self, signum: int = signal.SIGINT) -> int:
        """Send ``signum`` unless the process has ended, wait for it; its exit code."""
        if self.process.poll() is None:
            self.process.send_signal(signum)
        try:
            code = self.process.wait(timeout=WAIT)
        except subprocess.TimeoutExpired as late:
            self.process.kill()
            self.process.wait(timeout=WAIT)
            ended = f"the process did not end within {WAIT:g} s of signal {signum}"
            raise AssertionError(f"{ended}:\n{self.output}") from late
        self._reader.join(timeout=WAIT)
        return code
