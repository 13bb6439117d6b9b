"""The one exception hierarchy of dynevent.

Exceptions are raised only at the edge: when a message is constructed or
parsed, when a name is built, when a description, snapshot or vector file is
read, or when the command line is given bad input.  The protocol machines
themselves never raise; every refusal there is a value.

Every class here subclasses :class:`ValueError`, so ``except ValueError``
keeps working for callers who do not know dynevent.

Each error also says whose fault it is, as h11 separates its local and remote
protocol errors: a :class:`LocalError` is this program's misuse of dynevent (a
value it built, an argument, a configuration: fix the calling code), a
:class:`RemoteError` is bad data from outside (a message received, a file, a
store, another process: refuse it and carry on).  :class:`InvalidMessage`, the
error of the wire mirrors, comes as :class:`InvalidValue` (built here) or
:class:`MalformedMessage` (received).
"""

from __future__ import annotations

import math

__all__ = [
    "BagError",
    "DeadlinePassed",
    "DuplicateRobot",
    "DyneventError",
    "FileError",
    "GoalWaitTimeout",
    "ImplementationError",
    "ImplementationGone",
    "InvalidConfig",
    "InvalidDescription",
    "InvalidEventDescription",
    "InvalidMessage",
    "InvalidName",
    "InvalidRecord",
    "InvalidSnapshot",
    "InvalidStore",
    "InvalidValue",
    "InvalidVector",
    "LocalError",
    "MalformedMessage",
    "MissingExtra",
    "NotSpinning",
    "ProbeError",
    "RecordError",
    "RemoteError",
    "RobotNotReady",
    "SendError",
    "ServeError",
    "TaskError",
    "TraceError",
    "UnknownCategory",
    "UnknownRobot",
    "WrongInput",
]

_VALUE_REPR_LIMIT = 80


#: Paths longer than this (far past any file system's limit) are shortened in an error message.
_PATH_REPR_LIMIT = 4_096


def shown_path(path: str) -> str:
    """A path as an error message shows it: whole and quoted, control characters escaped; shortened
    only when it is longer than any path a system takes."""
    text = repr(path)
    if len(text) > _PATH_REPR_LIMIT:
        text = f"{text[:77]}... ({len(path)} chars)"
    return text


#: Integers of more bits than this (about 4,200 digits) are named by their length, not written out:
#: Python refuses to write one of more than 4,300 digits by default, and none would fit a line.
_LONGEST_INTEGER_BITS = 14_000


def integer_text(value: int) -> str:
    """An integer as decimal text, or, past what Python writes, ``<an integer of about N digits>``:
    how every message of dynevent shows an integer it was given."""
    if value.bit_length() <= _LONGEST_INTEGER_BITS:
        try:
            return int.__repr__(value)
        except ValueError:  # the interpreter's limit on digits set lower than its default
            pass
    return f"<an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits>"


def short_repr(value: object) -> str:
    """Return ``repr(value)`` cut to a readable length for error messages (an integer too long to
    write is named by its length, :func:`integer_text`)."""
    try:
        text = integer_text(value) if type(value) is int else repr(value)
    except Exception:  # a hostile __repr__ must not hide the real error
        text = f"<unrepresentable {type(value).__name__}>"
    if len(text) > _VALUE_REPR_LIMIT:
        text = f"{text[: _VALUE_REPR_LIMIT - 3]}... ({len(text)} chars)"
    return text


class DyneventError(ValueError):
    """Base class of every error dynevent raises on bad input."""


class LocalError(DyneventError):
    """This program used dynevent wrongly: a message, input, argument or configuration it built has a
    value or type dynevent refuses.  The fix is in the calling code (as h11's ``LocalProtocolError``)."""


class RemoteError(DyneventError):
    """Data from outside this program was refused: a message received, a file, a store, another
    process's answers.  Refusing it is right; the other side is at fault (as h11's
    ``RemoteProtocolError``)."""


class InvalidMessage(DyneventError):
    """A wire message or an input could not be built or parsed: :class:`InvalidValue` when this
    program built it, :class:`MalformedMessage` when it came from outside.

    ``message`` is the class name (``"Goal"``), ``field`` the dotted path of the
    offending field (``"logs[2].seq"``; empty when the whole input is at fault)
    and ``value`` the value that was refused.
    """

    def __init__(self, message: str, field: str, value: object, problem: str) -> None:
        self.message_type = message
        self.field = field
        self.value = value
        self.problem = problem
        where = f"{message}.{field}" if field else message
        super().__init__(f"{where}: {problem} (got {short_repr(value)})")


class InvalidValue(InvalidMessage, LocalError):
    """A message or input built in this program has a value the wire cannot carry."""


class MalformedMessage(InvalidMessage, RemoteError):
    """A message received from outside (JSON text, a ROS message) has a value the wire cannot carry."""

    @classmethod
    def of(cls, error: InvalidMessage) -> MalformedMessage:
        """The same fault, as found in a message received."""
        return cls(error.message_type, error.field, error.value, error.problem)


class WrongInput(LocalError, TypeError):
    """A value of the wrong type was given where a machine takes one of its inputs (also a ``TypeError``)."""

    def __init__(self, where: str, expected: str, value: object) -> None:
        self.where = where
        self.expected = expected
        self.value = value
        kind = type(value)
        super().__init__(f"{where}: expected {expected}, got {kind.__module__}.{kind.__qualname__}")


class InvalidConfig(LocalError, TypeError):
    """A server configuration field has a value the machine cannot work with.

    Also a :class:`TypeError`, as a wrong argument to a constructor is.
    """

    def __init__(self, field: str, value: object, problem: str, *, owner: str = "ServerConfig") -> None:
        self.field = field
        self.value = value
        self.problem = problem
        super().__init__(f"{owner}.{field}: {problem} (got {short_repr(value)})")


class InvalidName(LocalError):
    """A fleet or robot name is not a valid ROS 2 name token, or a name is none of the protocol's.

    ``field`` is ``"fleet"`` or ``"robot"`` for a bad token, ``"name"`` for a
    whole name that could not be parsed.
    """

    def __init__(self, field: str, value: object, problem: str) -> None:
        self.field = field
        self.value = value
        self.problem = problem
        if field in ("fleet", "robot"):
            text = f"{field} name {short_repr(value)} is not a valid ROS 2 name token: {problem}"
        else:
            text = f"{field} {short_repr(value)} is not a Dynamic Event name: {problem}"
        super().__init__(text)


class InvalidDescription(RemoteError):
    """A ``dynamic_event`` description could not be parsed.

    ``path`` locates the fault inside the JSON document (``"$.required[1].category"``).
    """

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"dynamic_event description at {path}: {problem}")


class InvalidEventDescription(RemoteError):
    """A child's description that its category's schema, or the robot, does not accept.

    ``errors`` are the lines :mod:`dynevent.descriptions` gives, each with its JSON pointer.
    """

    def __init__(self, category: str, errors: tuple[str, ...]) -> None:
        self.category = category
        self.errors = errors
        super().__init__(f"{category} description refused: " + "; ".join(errors))


class InvalidSnapshot(RemoteError):
    """A snapshot of a state or a fleet could not be restored."""

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"snapshot at {path}: {problem}")


class TraceError(RemoteError):
    """A trace could not be read: ``source``, ``line`` (from 1) and ``field`` say where."""

    def __init__(self, source: str, line: int, field: str, problem: str) -> None:
        self.source = source
        self.line = line
        self.field = field
        self.problem = problem
        super().__init__(f"{source}:{line}: {field}: {problem}")


class BagError(RemoteError):
    """A rosbag2 recording could not be read: ``source`` is the bag, ``problem`` says what is wrong."""

    def __init__(self, source: str, problem: str) -> None:
        self.source = source
        self.problem = problem
        super().__init__(f"{source}: {problem}")


class InvalidRecord(RemoteError):
    """A JSON record is not a valid input, output or configuration; ``path`` says where."""

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"{path}: {problem}")


class InvalidStore(RemoteError):
    """A state store that cannot be used: not SQLite, not dynevent's, or holding a bad snapshot."""

    def __init__(self, path: str, problem: str) -> None:
        self.path = path
        self.problem = problem
        super().__init__(f"state store {path}: {problem}")


class InvalidVector(RemoteError):
    """A vector file is malformed; the message names the file and the JSON path."""

    def __init__(self, source: str, path: str, problem: str) -> None:
        self.source = source
        self.path = path
        self.problem = problem
        super().__init__(f"{source}: {path}: {problem}")


class ImplementationError(RemoteError):
    """The implementation under test broke the driver protocol (crashed, timed out, answered garbage)."""


class DeadlinePassed(ImplementationError):
    """A request to the implementation under test was not sent, or its answer not waited for to the
    end, because the run's deadline passed: the bound's doing, not a fault of the implementation's."""


class ImplementationGone(ImplementationError):
    """The implementation under test cannot go on (it will not start again, or it stopped answering):
    the conformance run stops and reports the vectors left as not run."""


class UnknownRobot(LocalError, KeyError):
    """No robot of that fleet and name is in the :class:`~dynevent.server.fleet.Fleet` (a ``KeyError``)."""

    def __init__(self, fleet: str, robot: str) -> None:
        self.fleet = fleet
        self.robot = robot
        super().__init__(f"robot {robot!r} of fleet {fleet!r} is not in this fleet")

    def __str__(self) -> str:
        # KeyError would print the repr of the message
        return str(self.args[0])


class UnknownCategory(LocalError, KeyError):
    """A category that :mod:`dynevent.descriptions` has no schema for (a ``KeyError``)."""

    def __init__(self, category: object, known: tuple[str, ...]) -> None:
        self.category = category
        self.known = known
        names = ", ".join(known)
        super().__init__(f"no description schema for category {short_repr(category)}: known are {names}")

    def __str__(self) -> str:
        return str(self.args[0])


class MissingExtra(LocalError):
    """A feature needs a package that an optional extra of dynevent installs, and it is not installed."""

    def __init__(self, extra: str, package: str, purpose: str) -> None:
        self.extra = extra
        self.package = package
        super().__init__(f"{package} is not installed; it {purpose}: pip install 'dynevent[{extra}]'")


class DuplicateRobot(LocalError):
    """A robot was added to a :class:`~dynevent.server.fleet.Fleet` that already holds it."""

    def __init__(self, fleet: str, robot: str) -> None:
        self.fleet = fleet
        self.robot = robot
        super().__init__(f"robot {robot!r} of fleet {fleet!r} is already in this fleet")


class GoalWaitTimeout(DyneventError, TimeoutError):
    """:meth:`dynevent.ros.GoalRun.wait` reached its bound before the goal was over."""


class NotSpinning(LocalError):
    """A client waited for what only its node's callbacks bring, and nothing spins its node."""


class RobotNotReady(LocalError, TimeoutError):
    """:meth:`dynevent.ros.RobotClient.ready` reached its bound: the message says what was missing."""


class SendError(LocalError):
    """A bad ``dynevent send`` request: the message names the flag and the value."""


class ServeError(LocalError):
    """A bad ``dynevent serve`` configuration."""


class RecordError(LocalError):
    """``dynevent record`` cannot run as asked (its output, its options)."""


class TaskError(LocalError):
    """A bad ``dynevent task`` request: the message names the flag and the value."""


class FileError(LocalError):
    """A file named on a command line (or to an API that takes a path) that cannot be read or
    written as asked: not there, not a regular file, too large, not UTF-8, not JSON, a path too
    long.  The message names what the file is for and the path."""

    def __init__(self, what: str, path: str, problem: str) -> None:
        self.what, self.path, self.problem = what, path, problem
        super().__init__(f"{what} {shown_path(path)}: {problem}")


class ProbeError(LocalError):
    """A bad ``dynevent probe`` request: the message names the flag and the value."""
