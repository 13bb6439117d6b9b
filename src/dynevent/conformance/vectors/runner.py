"""Running vectors against an implementation: in process, or a program speaking the driver protocol.

The runner is built to outlast the implementation it tests.  A driver that
dies, stalls, answers late, answers garbage or floods its output fails the
vector it was answering, and costs at most one timeout and one restart: the
driver is killed and started afresh before the next vector, so a late answer
can never be read as the answer to a later request.  Every vector run before
the trouble keeps its result, and a run that cannot go on (the driver will not
start again, it stopped answering :data:`MAX_STALLS` vectors in a row or broke
the protocol in :data:`MAX_BROKEN`, or ``max_failures`` was reached) reports
the rest as not run.
"""

from __future__ import annotations

import collections
import contextlib
import json
import os
import select
import shlex
import subprocess
import textwrap
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from typing import IO, Any, Protocol

import attrs

from dynevent import __version__
from dynevent.conformance.vectors.diff import (
    MAX_DIFFERENCES,
    Difference,
    differences,
    kept,
    labelled,
    matches,
)
from dynevent.conformance.vectors.files import Vector
from dynevent.errors import (  # defined there with every error; importable here too
    DeadlinePassed,
    DyneventError,
    ImplementationError,
    ImplementationGone,
)
from dynevent.wire import _json

__all__ = [
    "MAX_ANSWER_BYTES",
    "MAX_ANSWER_VALUES",
    "MAX_BROKEN",
    "MAX_STALLS",
    "MAX_TIMEOUT",
    "ExternalImplementation",
    "Failure",
    "Implementation",
    "InProcessImplementation",
    "Outcome",
    "run_vector",
    "run_vectors",
]

#: The longest an external implementation may take to answer one request, in seconds.
MAX_TIMEOUT = 3600.0
#: The least time a program is given to start and answer its ``hello`` (seconds), whatever the
#: timeout of a request: an interpreter's start on a busy machine is no answer of the protocol's.
START_TIMEOUT = 10.0
#: The longest answer line an external implementation may write, in bytes.
MAX_ANSWER_BYTES = 16 * 1024 * 1024
#: The most values (a separator, an array or an object each) an answer line may hold: what parsing
#: it holds in memory is bounded before it is parsed (a million values, some hundred megabytes).
MAX_ANSWER_VALUES = 1_000_000
#: How long a driver that closed its output is given to exit before it is ended, at least.
_LAST_WAIT = 0.5
#: The longest a driver is given to exit once its input is closed (seconds, or ``--timeout`` when less):
#: then it is killed, so that closing one never holds a run longer than this.
CLOSE_WAIT = 2.0
#: The most of a standard error line read at once.
_STDERR_PIECE = 4_096
#: Vectors in a row that may end in a timeout before the run stops: a driver that hangs on everything
#: costs this many timeouts, not one per vector (a vector whose first steps were answered and whose
#: next one was not is one of them).
MAX_STALLS = 3
#: Vectors in a row that may break the protocol in any way (die, garbage, stall) before the run stops.
MAX_BROKEN = 10
#: Lines of an external implementation's standard error kept to show when it fails.
STDERR_LINES = 8


class Implementation(Protocol):
    """What the runner needs of an implementation under test."""

    name: str

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        """Start a new server for one robot; :class:`ImplementationGone` when that is no longer possible."""

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        """Apply one input record; return the output records and the view."""

    def close(self) -> None:
        """Release the implementation."""


def _refused(answer: Any) -> ImplementationError:
    if isinstance(answer, dict) and answer.get("ok") is False:
        return ImplementationError(f"the implementation refused the request: {answer.get('error')}")
    return ImplementationError(f"malformed answer {_json.dumps(answer)[:200]}")


class InProcessImplementation:
    """dynevent itself, through the same driver code the external path uses."""

    def __init__(self) -> None:
        # imported here, not at the top: this package's __init__ imports this module, and
        # ``python -m dynevent.conformance.vectors.driver`` must not find its module imported before it runs
        from dynevent.conformance.vectors.driver import Driver

        self._driver: Driver = Driver()
        self.name = f"dynevent {__version__} (in process)"

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        """Start a new server."""
        answer = self._driver.handle(
            {"op": "reset", "fleet": fleet, "robot": robot, "config": config, "state": state}
        )
        if answer.get("ok") is not True:
            raise _refused(answer)

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        """Apply one input."""
        answer = self._driver.handle({"op": "apply", "input": event})
        if answer.get("ok") is not True:
            raise _refused(answer)
        answer = json.loads(_json.dumps(answer))  # the same JSON round trip the external path makes
        return answer["outputs"], answer.get("view")

    def close(self) -> None:
        """Nothing to release."""


class _Broken(ImplementationError):
    """The driver's stream can no longer be trusted (it died, stalled or wrote garbage): restart it."""

    def __init__(self, problem: str, *, stalled: bool = False) -> None:
        super().__init__(problem)
        self.stalled = stalled


class ExternalImplementation:
    """An implementation run as a separate program speaking the driver protocol.

    ``restarts`` counts the times the program was started again after it broke
    the protocol.  Its standard error is read beside it; the last
    :data:`STDERR_LINES` lines are quoted when it dies or stalls.  ``time_left``, when set, is what
    is left of a bound on the whole run (seconds): no request waits longer, and none is sent once it
    is spent (:class:`~dynevent.errors.DeadlinePassed`).
    """

    def __init__(self, command: str, timeout: float = 10.0) -> None:
        if (
            isinstance(timeout, bool)
            or not isinstance(timeout, (int, float))
            or not 0 < timeout <= MAX_TIMEOUT
        ):
            raise ImplementationError(
                f"timeout: expected seconds from 0 to {MAX_TIMEOUT:g} (got {timeout!r})"
            )
        try:
            self._words = shlex.split(command)
        except ValueError as exc:
            raise ImplementationError(f"cannot start {command!r}: {exc}") from None
        if not self._words:
            raise ImplementationError("the implementation's command is empty")
        self.command = command
        self.timeout = float(timeout)
        self.restarts = 0
        self._stalls = 0  # vectors in a row that ended in a timeout
        self._breaks = 0  # vectors in a row that broke the protocol in any way
        self.time_left: Callable[[], float] | None = None
        self._broken: _Broken | None = None
        self._process: subprocess.Popen[bytes] | None = None
        self._pending = b""
        self._stderr: collections.deque[str] = collections.deque(maxlen=STDERR_LINES)
        self.name = self._start()

    # ------------------------------------------------------------------ the process

    def _start(self) -> str:
        """Start the program and greet it; its name.  ImplementationError when it cannot serve."""
        self._pending = b""
        self._stderr = collections.deque(maxlen=STDERR_LINES)
        try:
            self._process = subprocess.Popen(
                self._words, stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE
            )
        except (OSError, ValueError) as exc:
            raise ImplementationError(f"cannot start {self.command!r}: {exc}") from None
        assert self._process.stderr is not None
        threading.Thread(target=_keep_tail, args=(self._process.stderr, self._stderr), daemon=True).start()
        try:
            hello = self._request({"op": "hello"}, max(self.timeout, START_TIMEOUT))
            if hello.get("ok") is not True or hello.get("protocol") != 1:
                raise ImplementationError(f"it does not speak driver protocol 1: {hello!r}")
        except ImplementationError as exc:
            self._stop()
            raise ImplementationError(f"{self.command!r}: {exc}") from None
        self._broken = None
        return str(hello.get("implementation", self.command))

    def _stop(self) -> None:
        """End the program within bounds, whatever state it is in."""
        process = self._process
        if process is None:
            return
        if process.stdin is not None:
            with contextlib.suppress(OSError):  # a dead program's pipe: nothing left to tell it
                process.stdin.close()
        try:
            process.wait(timeout=min(self.timeout, CLOSE_WAIT) if self._broken is None else _LAST_WAIT)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()
        if process.stdout is not None:
            process.stdout.close()

    def _last_words(self) -> str:
        time.sleep(0.05)  # let the stderr reader catch the last lines of a program that just ended
        return "; its standard error ended with: " + " | ".join(self._stderr) if self._stderr else ""

    def _break(self, problem: str, *, stalled: bool = False) -> _Broken:
        if stalled or (self._process is not None and self._process.poll() is not None):
            problem += self._last_words()
        self._broken = _Broken(problem, stalled=stalled)
        return self._broken

    # ------------------------------------------------------------------ one exchange

    def _request(self, request: Any, timeout: float | None = None) -> dict[str, Any]:
        """Send one request; its answer, within ``timeout`` seconds (the request timeout when None) or
        what :attr:`time_left` leaves, when less."""
        assert self._process is not None and self._process.stdin is not None
        bound = self.timeout if timeout is None else timeout
        left = bound if self.time_left is None else self.time_left()
        if left <= 0:
            raise DeadlinePassed("the run's deadline passed: the request was not sent")
        try:
            self._process.stdin.write((_json.dumps(request) + "\n").encode("utf-8"))
            self._process.stdin.flush()
        except OSError:
            raise self._break(f"the driver closed its input (exit code {self._process.poll()})") from None
        try:
            raw = self._read_line(min(bound, left))
        except _Broken as exc:  # broken all the same: a late answer is never read as a later one's
            if exc.stalled and left < bound:
                raise DeadlinePassed(
                    f"the run's deadline passed after {left:.3g} s of waiting for the answer"
                ) from None
            raise
        line = self._text(raw)
        try:
            answer = _json.parse(line)  # the line's bytes let go: a parsed line costs its text and its values
        except _json.JsonProblem as exc:
            raise self._break(f"the driver answered with {exc}: {line[:200]!r}") from None
        if not isinstance(answer, dict):
            raise self._break(f"the driver answered with a JSON value that is not an object: {line[:200]!r}")
        return answer

    def _text(self, raw: bytes) -> str:
        try:
            return raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise self._break(
                f"the driver answered with bytes that are not UTF-8 ({exc.reason} "
                f"at byte {exc.start}): {raw[:200]!r}"
            ) from None

    def _read_line(self, timeout: float) -> bytes:
        """One answer line, within ``timeout`` however the program writes it (a half line and a stall too)."""
        assert self._process is not None and self._process.stdout is not None
        stdout = self._process.stdout
        deadline = time.monotonic() + timeout
        while b"\n" not in self._pending:
            left = deadline - time.monotonic()
            ready, _, _ = select.select([stdout], [], [], max(left, 0.0))
            if not ready:
                raise self._break(f"the driver did not answer within {timeout:g} s", stalled=True)
            chunk = os.read(stdout.fileno(), 65536)
            if not chunk:
                try:
                    # as long as closing its input would give it (CLOSE_WAIT), within the answer's time
                    left = min(deadline - time.monotonic(), CLOSE_WAIT)
                    code = self._process.wait(timeout=max(left, _LAST_WAIT))
                except subprocess.TimeoutExpired:  # its output closed, the process still there
                    self._process.kill()
                    code = self._process.wait()
                    raise self._break(
                        "the driver closed its output and went on running: it was ended"
                    ) from None
                raise self._break(f"the driver ended (exit code {code})")
            self._pending += chunk
            if len(self._pending) > MAX_ANSWER_BYTES:
                raise self._break(f"the driver answered a line above {MAX_ANSWER_BYTES} bytes")
        line, _, self._pending = self._pending.partition(b"\n")
        # what parsing would hold in memory, counted before it is spent: one value a separator
        values = line.count(b",") + line.count(b"[") + line.count(b"{")
        if values > MAX_ANSWER_VALUES:
            raise self._break(f"the driver answered a line of more than {MAX_ANSWER_VALUES:,} values")
        return line

    # ------------------------------------------------------------------ the protocol

    def reset(self, fleet: str, robot: str, config: Any, state: Any) -> None:
        """Start a new server, first restarting the program if it broke the protocol.  A vector
        counts as a timeout (or a break) in a row only when it ended in one: the counts start again
        at a vector that did not."""
        if self._broken is None:
            self._stalls = self._breaks = 0
        else:
            self._stalls = self._stalls + 1 if self._broken.stalled else 0
            self._breaks += 1
            if self._stalls >= MAX_STALLS:
                raise ImplementationGone(
                    f"the driver stopped answering: {self._stalls} vectors in a row timed out"
                )
            if self._breaks >= MAX_BROKEN:
                raise ImplementationGone(f"the driver broke the protocol in {self._breaks} vectors in a row")
            self._stop()
            try:
                self._start()
            except ImplementationError as exc:
                raise ImplementationGone(f"the driver could not be started again: {exc}") from None
            self.restarts += 1
        answer = self._request(
            {"op": "reset", "fleet": fleet, "robot": robot, "config": config, "state": state}
        )
        if answer.get("ok") is not True:
            raise _refused(answer)

    def apply(self, event: Any) -> tuple[list[Any], Any]:
        """Apply one input."""
        answer = self._request({"op": "apply", "input": event})
        if answer.get("ok") is not True:
            raise _refused(answer)
        if not isinstance(answer.get("outputs"), list):
            raise self._break(f"the driver answered without an outputs list: {_json.dumps(answer)[:200]}")
        return answer["outputs"], answer.get("view")

    def close(self) -> None:
        """Stop the program (never raises: a program that already died is simply gone)."""
        self._stop()
        self._process = None


def _keep_tail(stream: IO[bytes], tail: collections.deque[str]) -> None:
    """Read a program's standard error to its end, keeping the last lines (each cut to 200 characters):
    a program that floods it can neither block on a full pipe nor fill this process's memory."""
    with contextlib.suppress(OSError, ValueError):
        while raw := stream.readline(_STDERR_PIECE):  # a line without end is read in pieces
            text = raw.decode("utf-8", "replace").rstrip()
            if text:
                tail.append(text[:200])


# --------------------------------------------------------------------------- results


@attrs.frozen
class Failure:
    """Where and how a vector failed: the step (0 for the reset), its input, what was expected and
    given, a one-line problem, and the field-level differences (none when nothing usable came back)."""

    step: int
    input: Any
    expected: Any
    got: Any
    problem: str
    differences: tuple[Difference, ...] = ()
    #: the differences past the :data:`~dynevent.conformance.vectors.diff.MAX_DIFFERENCES` listed
    more_differences: int = 0

    @classmethod
    def of(
        cls, step: int, input: Any, expected: Any, got: Any, problem: str, found: Sequence[Difference] = ()
    ) -> Failure:
        """A failure as a run keeps it, within bounds whatever the implementation answered: the first
        :data:`~dynevent.conformance.vectors.diff.MAX_DIFFERENCES` differences, and each value
        :func:`~dynevent.conformance.vectors.diff.kept`."""
        listed = tuple(
            attrs.evolve(difference, expected=kept(difference.expected), got=kept(difference.got))
            for difference in found[:MAX_DIFFERENCES]
        )
        more = max(len(found) - MAX_DIFFERENCES, 0)
        return cls(step, input, kept(expected), kept(got), problem, listed, more)

    def diff(self, width: int = 96) -> str:
        """A readable account within ``width`` columns: the step and its problem, its input, then each
        differing field (:meth:`Difference.describe`); long values are cut (``--json`` keeps them whole)."""
        lines = textwrap.wrap(f"step {self.step}: {self.problem}", width, subsequent_indent="    ")
        if self.input is not None:
            lines.extend(labelled("  input", self.input, width))
        for difference in self.differences:
            lines.extend("  " + line for line in difference.describe(width - 2))
        if self.more_differences:
            lines.append(f"  ... and {self.more_differences:,} more differences")
        return "\n".join(lines)


@attrs.frozen
class Outcome:
    """The result of one vector: passed, failed (``failure``) or not run (``not_run`` says why)."""

    vector: Vector
    failure: Failure | None
    not_run: str | None = None

    @property
    def passed(self) -> bool:
        """True when every step matched."""
        return self.failure is None and self.not_run is None


def run_vector(vector: Vector, implementation: Implementation) -> Outcome:
    """Run one vector; stop at the first mismatch.  :class:`ImplementationGone` passes through."""
    try:
        implementation.reset(vector.fleet, vector.robot, vector.config, vector.state)
    except ImplementationGone:
        raise
    except DyneventError as exc:
        return Outcome(vector, Failure(0, None, None, None, f"reset failed: {exc}"))
    for index, step in enumerate(vector.steps, start=1):
        expected = list(step.expect)
        try:
            outputs, view = implementation.apply(step.input)
        except DyneventError as exc:
            return Outcome(vector, Failure.of(index, step.input, expected, None, f"apply failed: {exc}"))
        if not matches(expected, outputs):
            found = differences(expected, outputs, "outputs")
            return Outcome(vector, Failure.of(index, step.input, expected, outputs, "outputs differ", found))
        if step.view is not None and not matches(step.view, view):
            found = differences(step.view, view, "view")
            return Outcome(vector, Failure.of(index, step.input, step.view, view, "view differs", found))
    return Outcome(vector, None)


def run_vectors(
    vectors: Sequence[Vector], implementation: Implementation, *, max_failures: int | None = None
) -> Iterator[Outcome]:
    """Run every vector in turn, yielding each outcome as it is known.

    After ``max_failures`` failed vectors, or once the implementation cannot go
    on (:class:`ImplementationGone`), the remaining vectors are yielded as not
    run, with the reason.
    """
    if max_failures is not None and (isinstance(max_failures, bool) or max_failures < 1):
        raise TypeError(f"max_failures: expected a positive int or None, got {max_failures!r}")
    failures = 0
    stopped: str | None = None
    for vector in vectors:
        if stopped is not None:
            yield Outcome(vector, None, not_run=stopped)
            continue
        try:
            outcome = run_vector(vector, implementation)
        except ImplementationGone as gone:
            stopped = f"the run stopped: {gone}"
            yield Outcome(vector, None, not_run=stopped)
            continue
        yield outcome
        failures += outcome.failure is not None
        if max_failures is not None and failures >= max_failures:
            stopped = f"the run stopped after {failures} failed vector{'s' if failures > 1 else ''}"
