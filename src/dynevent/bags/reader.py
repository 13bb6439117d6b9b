"""Rosbag2 recordings of Dynamic Event conversations, read and judged without ROS.

A bag is a directory (``metadata.yaml`` and its storage files) or one storage
file, MCAP (``.mcap``, rosbag2's default since Iron) or SQLite (``.db3``).  It
is read with ``rosbags`` (the ``bags`` extra: ``pip install 'dynevent[bags]'``),
its CDR messages decoded with the project's own interface files
(``dynevent/ros/setup/interfaces``), so no ROS installation is needed.

Every topic named after a robot (:mod:`dynevent.wire.names`) is that robot's:
its status and begin topics, the action's ``_action/feedback`` topic and,
when the bag has them, the introspection service events of the action's
``send_goal``, ``get_result`` and ``cancel_goal`` services, which carry the
goals, their responses, their answers and the action-level cancels (ROS 2
records them when introspection is on, at the server or the client).  The
fleet-wide begin topic is read for a robot whose own begin topic the bag
lacks.  Each robot's messages become trace records (docs/trace-format.md),
in bag order, judged by a :class:`~dynevent.conformance.judge.observer.Checker` of
their own: one pass over the bag, whatever its size, holding a few records
per robot.

A robot whose goals the bag lacks (no ``send_goal`` introspection topic) is a
partial view: its statuses show child events no goal the bag holds explains,
so the machine cannot be run.  What its topics show by themselves is judged
(:mod:`dynevent.conformance.judge.partial`), and its :class:`RobotReport` says which
channels were absent, rather than report a violation the missing channel
would cause.  A finding's ``line`` is the bag time of its message, in
nanoseconds.
"""

from __future__ import annotations

import collections
import contextlib
import functools
import heapq
import importlib.resources
import os
import stat
from collections.abc import Callable, Container, Iterator, Mapping, Sequence
from pathlib import Path, PurePath
from typing import Any, NamedTuple

import attrs

from dynevent import files
from dynevent.bags import sent, unpack
from dynevent.conformance.judge.observer import AnswerEvidence, Checker
from dynevent.conformance.judge.partial import GOAL_STATUSES, PartialJudge
from dynevent.conformance.judge.trace import (
    SKIPS_OR_LOST,
    TERMINATED,
    Answer,
    Finding,
    Record,
    Report,
    TraceHeader,
)
from dynevent.conformance.received import (
    begin_from_ros,
    feedback_from_ros,
    goal_from_ros,
    result_from_ros,
    status_from_ros,
    uuid_from_ros,
)
from dynevent.errors import (
    BagError,
    DyneventError,
    FileError,
    InvalidMessage,
    InvalidName,
    MissingExtra,
    TraceError,
    short_repr,
)
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback
from dynevent.wire.names import BEGIN_TOPIC, NameKind, parse_name
from dynevent.wire.vocab import (
    CANCEL_GOAL_TERMINATED,
    Compatibility,
    DynamicState,
    EventType,
    GoalStatus,
    Status,
    Violation,
)

__all__ = [
    "HIDDEN_SUFFIXES",
    "SKEW",
    "BagReport",
    "Channel",
    "RobotReport",
    "channel_of",
    "check_bag",
    "message_definition",
    "typestore",
]

#: The action's hidden topics (``<action>/_action/...``) and the channel each is.
FEEDBACK, GOAL_STATUS = "feedback", "goal status"
SEND_GOAL, GET_RESULT, CANCEL_GOAL = "send_goal", "get_result", "cancel_goal"
HIDDEN = {
    "/_action/feedback": FEEDBACK,
    "/_action/status": GOAL_STATUS,
    "/_action/send_goal/_service_event": SEND_GOAL,
    "/_action/get_result/_service_event": GET_RESULT,
    "/_action/cancel_goal/_service_event": CANCEL_GOAL,
}
#: The type each channel carries: a topic of a Dynamic Event name with another type is not read.
TYPES = {
    "status": "rmf_task_msgs/msg/DynamicEventStatus",
    "begin": "rmf_task_msgs/msg/DynamicEventDescription",
    FEEDBACK: "rmf_task_msgs/action/DynamicEvent_FeedbackMessage",
    GOAL_STATUS: "action_msgs/msg/GoalStatusArray",
    SEND_GOAL: "rmf_task_msgs/action/DynamicEvent_SendGoal_Event",
    GET_RESULT: "rmf_task_msgs/action/DynamicEvent_GetResult_Event",
    CANCEL_GOAL: "action_msgs/srv/CancelGoal_Event",
}
#: The suffixes of the action's hidden topics, after ``<action>``.
HIDDEN_SUFFIXES = tuple(HIDDEN)


class Channel(NamedTuple):
    """What a topic on a Dynamic Event name carries: the robot (an empty fleet and robot for the
    fleet-wide begin topic, which carries every robot's begins) and the channel (``status``,
    ``begin``, or one of the action's hidden topics, :data:`HIDDEN`)."""

    fleet: str
    robot: str
    channel: str


def channel_of(topic: str) -> Channel | None:
    """The robot and channel of ``topic``, or None for a topic on no Dynamic Event name (the
    action's own name is no topic, and a hidden suffix on a topic's name is no name)."""
    if topic.lstrip("/") == BEGIN_TOPIC:
        return Channel("", "", "begin")
    name, channel = topic, ""
    for suffix, hidden in HIDDEN.items():
        if topic.endswith(suffix):
            name, channel = topic[: -len(suffix)], hidden
    try:
        parsed = parse_name(name)
    except InvalidName:
        return None
    if (parsed.kind is NameKind.ACTION) != bool(channel) or parsed.kind is NameKind.DESCRIPTION:
        return None  # the description query is a service: no topic of a recording
    return Channel(parsed.fleet, parsed.robot, channel or str(parsed.kind))


#: The channels a robot's judgement needs, in the words a partial view line uses.
CHANNELS = {
    "status": "the status topic",
    "begin": "the begin topic",
    FEEDBACK: "feedback",
    SEND_GOAL: "goals and their responses (send_goal introspection)",
    GET_RESULT: "answers (get_result introspection)",
}

#: service_msgs/ServiceEventInfo event types.
_REQUEST_SENT, _REQUEST_RECEIVED, _RESPONSE_SENT, _RESPONSE_RECEIVED = 0, 1, 2, 3
#: action_msgs/GoalStatus's statuses (0, unknown, is none of a goal's); the terminal ones answer it.
_GOAL_STATUSES = {
    1: GoalStatus.ACCEPTED,
    2: GoalStatus.EXECUTING,
    3: GoalStatus.CANCELING,
    4: GoalStatus.SUCCEEDED,
    5: GoalStatus.CANCELED,
    6: GoalStatus.ABORTED,
}
_TERMINAL = {code: status for code, status in _GOAL_STATUSES.items() if status.is_terminal}


@attrs.frozen
class RobotReport:
    """One robot of a bag: the channels the bag recorded for it (keys of :data:`CHANNELS`, and
    ``"goal status"``, the action's goal statuses), the ones a full judgement needs that it lacks,
    its report, whether that report judged only what the topics show (``partial``: the bag lacks the
    robot's goals, :mod:`dynevent.conformance.judge.partial`), how many of its messages the mirrors
    refused (a value the wire cannot carry: not judged), and the goals whose request the bag lacked
    though it holds others (``lost``: the judgement began anew there, see :meth:`_Robot.lost_request`)."""

    fleet: str
    robot: str
    channels: tuple[str, ...]
    absent: tuple[str, ...]
    report: Report
    partial: bool = False
    refused: int = 0
    #: where the bag lacked a goal's request: (the bag time of the first record naming the goal, its UUID)
    lost: tuple[tuple[int, str], ...] = ()
    #: where the bag held a goal's request but lacked its response, and its feedback or answer came:
    #: (the bag time of that record, the goal's UUID); the goal is read as accepted from there
    unheard: tuple[tuple[int, str], ...] = ()
    #: the server's messages received more than :data:`HOLD` after they were sent, after records it
    #: sent later had been judged (a lossy link on a loaded host): (bag time, channel, when sent, as the
    #: bag says); each is left unjudged, and said
    late: tuple[tuple[int, str, int], ...] = ()
    #: where the bag lacked a run's begin (on every begin topic it recorded), its first status read as
    #: the begin's: (the bag time of that status, the run's seq)
    unbegun: tuple[tuple[int, int], ...] = ()

    @property
    def name(self) -> str:
        return f"{self.fleet}/{self.robot}"


@attrs.frozen
class BagReport:
    """What :func:`check_bag` found: each robot's report, and how many messages the bag held on the
    Dynamic Event names (``messages``) and on others (``other``)."""

    source: str
    robots: tuple[RobotReport, ...]
    messages: int
    other: int

    @property
    def clean(self) -> bool:
        """No robot's judgement found a violation."""
        return all(robot.report.clean for robot in self.robots)


def check_bag(path: str | Path, *, compatibility: Compatibility | str = Compatibility.STANDARD) -> BagReport:
    """Judge every Dynamic Event conversation of the bag at ``path``; ``compatibility="rmf_ros2"``
    judges each server as ``dynevent serve --compatibility rmf_ros2`` behaves.

    Raises :class:`~dynevent.errors.MissingExtra` without ``rosbags``, and
    :class:`~dynevent.errors.BagError` for a bag that cannot be read (no such
    file, not a bag, truncated or corrupt, a message that cannot be decoded).
    """
    return _read(path, Compatibility(compatibility), keep=False)[0]


def bag_records(path: str | Path) -> dict[tuple[str, str], list[Record]]:
    """Each robot's records in the bag at ``path``, by (fleet, robot), in the order the server
    made them (as :func:`check_bag` judges them; what :mod:`dynevent.conformance.judge.replay` replays).
    Raises as :func:`check_bag` does."""
    robots = _read(path, Compatibility.STANDARD, keep=True)[1]
    return {key: robot.kept for key, robot in sorted(robots.items())}


def _read(
    path: str | Path, compatibility: Compatibility, *, keep: bool
) -> tuple[BagReport, dict[tuple[str, str], _Robot]]:
    source = str(path)
    reader_errors = _rosbags()[1]
    metadata = _vet(source, Path(path))
    with contextlib.ExitStack() as unpacked:
        with _storage(source, reader_errors):  # every chunk the library will unpack, vetted first
            bag = unpacked.enter_context(unpack.readable(source, Path(path), metadata))
        return _judge(source, bag, compatibility, keep, numbered=_numbered(metadata))


def _numbered(metadata: Any) -> bool:
    """Whether a bag's metadata says its MCAP sequences are its publishers' publication numbers
    (``dynevent record``'s bags: :data:`dynevent.bags.sent.SEQUENCE_KEY`)."""
    information = metadata.get("rosbag2_bagfile_information") if isinstance(metadata, dict) else None
    custom = information.get("custom_data") if isinstance(information, dict) else None
    return isinstance(custom, dict) and custom.get(sent.SEQUENCE_KEY) == sent.SEQUENCE_VALUE


def _judge(
    source: str,
    readable: unpack.Readable,
    compatibility: Compatibility,
    keep: bool,
    *,
    numbered: bool = False,
) -> tuple[BagReport, dict[tuple[str, str], _Robot]]:
    """Judge the bag the storage library reads at ``readable.path``; each message unpacked within its
    budget when the bag's messages are compressed, and ordered by when it was sent where the bag
    says (:mod:`dynevent.bags.sent`), with its publisher's number where the bag holds them
    (``numbered``)."""
    bag, budget = readable.path, readable.budget
    sent_at = sent.publish_times(source, readable.mcap, numbered=numbered)
    reader_type, reader_errors = _rosbags()
    robots: dict[tuple[str, str], _Robot] = {}
    messages = other = 0
    with _storage(source, reader_errors):
        reader = reader_type(bag)
        reader.open()
    try:
        with _storage(source, reader_errors):
            routes = _routes(reader.connections, robots, compatibility, keep)
            other = sum(item.msgcount for item in reader.connections if item.id not in routes)
            wanted = [item for item in reader.connections if item.id in routes]
            end = int(reader.end_time) - 1  # the recording's last message, on any topic
        store = typestore()
        decode_as = {item.id: _stored_name(store, item.msgtype) for item in wanted}
        for connection in wanted:  # introspection without contents (METADATA) holds no goal
            robot, channel = routes[connection.id]
            if channel == SEND_GOAL and isinstance(robot, _Robot) and connection.msgcount:
                with _storage(source, reader_errors):
                    first = next(iter(reader.messages(connections=[connection])))
                event = _decode(store, _unpacked(first, budget, source), decode_as[connection.id], source)
                robot.contents = bool(len(event.request) or len(event.response))
        stream = iter(reader.messages(connections=wanted) if wanted else ())
        while True:
            with _storage(source, reader_errors):
                item = next(stream, None)
            if item is None:
                break
            connection, time, raw = item
            if type(time) is not int:  # a SQLite column holds whatever a writer put there
                raise BagError(
                    source, f"{connection.topic}: a message's time is {short_repr(time)}, not nanoseconds"
                )
            end = max(end, time)
            robot, channel = routes[connection.id]
            message = _decode(store, _unpacked(item, budget, source), decode_as[connection.id], source)
            messages += 1
            mark = sent_at.get((connection.topic, time, hash(bytes(raw)))) if sent_at else None
            if mark is not None and mark.number and channel == FEEDBACK and isinstance(robot, _Robot):
                robot.lateness.numbered(time, message, mark.number)  # its writer's number-th
            robot.take(channel, time, message, None if mark is None else mark.time)
        reports = tuple(robot.finish(source, end) for _, robot in sorted(robots.items()))
    except TraceError as exc:  # a record the observer cannot take, in the bag's order
        raise BagError(source, f"{exc.field} at bag time {exc.line}: {exc.problem}") from None
    finally:
        with _storage(source, reader_errors):
            reader.close()
    return BagReport(source=source, robots=reports, messages=messages, other=other), robots


def _unpacked(
    item: tuple[Any, int, bytes], budget: unpack.Budget | None, source: str
) -> tuple[Any, int, bytes]:
    """A message as the bag holds it, unpacked within ``budget`` where the bag compresses its messages."""
    if budget is None:
        return item
    connection, time, raw = item
    return connection, time, unpack.unpack_message(source, raw, f"{connection.topic} at {time}", budget)


#: The largest metadata.yaml read (a recording's is a few KB per topic) and its deepest nesting.
MAX_METADATA_BYTES = 4_000_000
_METADATA_DEPTH = 64


def _vet(source: str, path: Path) -> Any:
    """What a bag is made of, checked before the storage library opens any of it: every file it
    would read is a regular file (a FIFO would block the read for ever), and metadata.yaml is
    bounded YAML without aliases (a "billion laughs" would take the machine's memory; no rosbag2
    writer uses an alias).  Its metadata.yaml, parsed (None for a storage file alone)."""
    mode = _mode(source, path)
    if not stat.S_ISDIR(mode):
        if not stat.S_ISREG(mode):
            raise BagError(source, f"not a rosbag2 recording: {files.kind(mode)}, not a bag's file")
        return None
    metadata = path / "metadata.yaml"
    if not metadata.exists():
        raise BagError(source, "not a rosbag2 recording: a bag directory holds a metadata.yaml")
    try:
        text = files.read_text(str(metadata), "metadata.yaml", limit=MAX_METADATA_BYTES)
    except FileError as exc:
        raise BagError(source, f"not a readable rosbag2 recording: {exc}") from None
    document = _metadata(source, text)
    for name in _storage_files(document):
        storage = path / PurePath(name).name  # as the reader finds it: beside metadata.yaml
        if storage.name and os.path.lexists(storage):
            kind = _mode(source, storage)
            if not stat.S_ISREG(kind):
                raise BagError(source, f"{storage.name}: {files.kind(kind)}, not a bag's storage file")
    return document


def _mode(source: str, path: Path) -> int:
    try:
        return os.stat(path).st_mode
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else "not a path"
        raise BagError(source, f"cannot read: {reason}") from None


def _metadata(source: str, text: str) -> Any:
    """metadata.yaml, parsed after its events are vetted (no alias, nesting bounded), so that
    composing it costs no more than its size."""
    from ruamel.yaml import YAML
    from ruamel.yaml.error import YAMLError
    from ruamel.yaml.events import AliasEvent, CollectionEndEvent, CollectionStartEvent

    yaml = YAML(typ="safe")
    depth = 0
    try:
        for event in yaml.parse(text):
            if isinstance(event, AliasEvent):
                raise BagError(source, "metadata.yaml uses a YAML alias, which no rosbag2 recording does")
            depth += isinstance(event, CollectionStartEvent) - isinstance(event, CollectionEndEvent)
            if depth > _METADATA_DEPTH:
                raise BagError(source, f"metadata.yaml is nested deeper than {_METADATA_DEPTH} levels")
        return yaml.load(text)
    except YAMLError as exc:
        raise BagError(source, f"not a readable rosbag2 recording: metadata.yaml: {_one_line(exc)}") from None


def _storage_files(document: Any) -> list[str]:
    """The storage files metadata.yaml names."""
    information = document.get("rosbag2_bagfile_information") if isinstance(document, dict) else None
    names = information.get("relative_file_paths") if isinstance(information, dict) else None
    return [name for name in names if isinstance(name, str)] if isinstance(names, list) else []


@contextlib.contextmanager
def _storage(source: str, reader_errors: tuple[type[BaseException], ...]) -> Iterator[None]:
    """Around a call into the storage library: what it raises for a file that is not a readable bag
    (its own errors, and apsw's or zstandard's on a corrupt file) becomes one :class:`BagError` line."""
    try:
        yield
    except DyneventError:  # a ValueError too: before the library's
        raise
    except (FileNotFoundError, IsADirectoryError, PermissionError) as exc:
        raise BagError(source, f"cannot read: {exc.strerror or exc}") from None
    except reader_errors as exc:
        raise BagError(source, f"not a readable rosbag2 recording: {_one_line(exc)}") from None
    except Exception as exc:  # the storage library's own (apsw, zstandard) on a corrupt file
        raise BagError(
            source, f"not a readable rosbag2 recording: {type(exc).__name__}: {_one_line(exc)}"
        ) from None


def _decode(store: Any, item: tuple[Any, int, bytes], msgtype: str, source: str) -> Any:
    """A bag message, decoded; a decoder's error, of any kind, means the bag is not what it says."""
    connection, time, raw = item
    try:
        return store.deserialize_cdr(raw, msgtype)
    except Exception as exc:
        raise BagError(source, f"{connection.topic} at {time}: cannot decode: {exc}") from None


def _one_line(exc: BaseException) -> str:
    return " ".join(str(exc).split())


def _stored_name(store: Any, msgtype: str) -> str:
    """The name the type store knows a bag's type by: rosbags files a service's types
    (``action_msgs/srv/CancelGoal_Event``) under ``.../srv/msg/...``."""
    if msgtype in store.types:
        return msgtype
    from rosbags.typesys.msg import normalize_msgtype

    normalized: str = normalize_msgtype(msgtype)
    return normalized


def _rosbags() -> tuple[Any, tuple[type[BaseException], ...]]:
    """rosbags' reader, and the errors it raises for a file that is not a readable bag."""
    try:
        from rosbags.rosbag2 import Reader, ReaderError
    except ImportError:
        raise MissingExtra("bags", "rosbags", "reads rosbag2 recordings") from None
    return Reader, (ReaderError, ValueError, OSError, EOFError)


def _routes(
    connections: Any, robots: dict[tuple[str, str], _Robot], compatibility: Compatibility, keep: bool = False
) -> dict[int, tuple[_Robot, str]]:
    """Each connection (by id) on a Dynamic Event name: the robot it belongs to and its channel."""
    routes: dict[int, tuple[_Robot, str]] = {}
    fleet_wide = []
    for connection in connections:
        found = channel_of(connection.topic)
        if found is None or connection.msgtype != TYPES[found.channel]:
            continue  # a Dynamic Event name with another type: not this protocol's
        key, channel = (found.fleet, found.robot), found.channel
        if not found.robot:  # the fleet-wide begin topic
            fleet_wide.append(connection)
            continue
        robot = robots.setdefault(key, _Robot(*key, compatibility=compatibility, keep=keep))
        if connection.msgcount:  # a topic subscribed to in vain holds nothing to judge
            robot.channels.add(channel)
            robot.begins.own = robot.begins.own or channel == "begin"
        routes[connection.id] = (robot, channel)
    for connection in fleet_wide:  # a robot's begins, with those of its own begin topic, read once
        routes[connection.id] = (_FleetBegins(robots, compatibility, keep), "begin")  # type: ignore[assignment]
    return routes


class _Calls:
    """A robot's service calls, as its introspection events come: a response event carries no request
    (ROS 2 introspection), so the request of the same call (client GID and sequence number) is kept
    until its response comes, and a response that comes first is kept until its request does."""

    def __init__(self) -> None:
        # calls whose response is to come, and (kept as :attr:`early`) responses whose request is to
        # come: (the event, its bag time, when it was sent); the latest _CALLS of each
        self.requests: collections.OrderedDict[tuple[str, bytes, int], Any] = collections.OrderedDict()
        self.early: collections.OrderedDict[tuple[str, bytes, int], tuple[Any, int, int | None]] = (
            collections.OrderedDict()
        )

    def paired(
        self, channel: str, event: Any, came: tuple[int, int | None]
    ) -> tuple[int, Any, Any, tuple[str, bytes, int]] | None:
        """A service event as (kind, request, response, call).  None for a response whose request the
        bag does not hold yet: it is kept in :attr:`early`, with when it ``came`` (its bag time, when
        it was sent), for its request (a lossy link may deliver the request's event after the
        response's), whose taker takes it then (:meth:`_Robot.take`)."""
        kind = int(event.info.event_type)
        call = (channel, bytes(bytearray(event.info.client_gid)), int(event.info.sequence_number))
        request = event.request[0] if len(event.request) else None
        response = event.response[0] if len(event.response) else None
        if kind in (_REQUEST_SENT, _REQUEST_RECEIVED):
            if request is None:
                return None  # introspection without contents: nothing to judge
            _remember(self.requests, call, request)
            return kind, request, None, call
        request = request if request is not None else self.requests.pop(call, None)
        if request is None and response is not None:
            _remember(self.early, call, (event, *came))
        if request is None or response is None:
            return None
        return kind, request, response, call


class _Lateness:
    """A robot's messages that came later than the records wait (:data:`HOLD`), by when the bag says
    the server sent them: the least time any of them was on its way (the link's, and the offset of
    the server's clock from the bag's), and when the server sent the latest record passed on.  A
    message on its way more than HOLD longer than the least is delayed; one sent before a record
    already passed on is late (:attr:`late`), and not judged."""

    def __init__(self) -> None:
        #: the late messages: (bag time, channel, when sent)
        self.late: list[tuple[int, str, int]] = []
        self._sent_of: dict[int, int] = {}  # when the server sent each waiting record, by arrival
        self._sent_passed = 0  # the latest time the server sent a record passed on
        self._least_lag: int | None = None  # bag time less when sent, the least of the server's messages
        self._logs: set[int] = set()  # the log seqs of late feedback
        #: the feedback writer's numbers received (the latest NUMBERS_KEPT), and each log seq's
        self._numbers: collections.OrderedDict[int, None] = collections.OrderedDict()
        self._log_numbers: collections.OrderedDict[int, int] = collections.OrderedDict()
        self._runs: set[int] = set()  # the runs (dynamic event seqs) whose begin came late
        self._cancelled: set[str] = set()  # the goals an action-level cancel of came late

    def delayed(self, time: int, sent: int) -> bool:
        """Was a message of the server's received at bag ``time`` and ``sent`` then on its way more than
        :data:`HOLD` longer than the quickest?"""
        lag = time - sent
        self._least_lag = lag if self._least_lag is None else min(self._least_lag, lag)
        return lag - self._least_lag > HOLD

    @property
    def clocks_agree(self) -> bool:
        """Do the server's clock and the bag's agree within :data:`SKEW` (its quickest message's lag)?"""
        return self._least_lag is not None and abs(self._least_lag) <= SKEW

    def overtaken(self, time: int, channel: str, message: Any, sent: int) -> bool:
        """Was a delayed message ``sent`` before a record already passed on?  Then it is late: kept in
        :attr:`late`, and a feedback's log seqs with it (a skip judged before it lacked them)."""
        if sent >= self._sent_passed:
            return False
        self.late.append((time, channel, sent))
        if channel == FEEDBACK:
            with contextlib.suppress(InvalidMessage):
                for record in _RECORDS[channel](time, message):
                    self._logs.update(entry.seq for entry in record.message.logs)
        elif channel == "begin":
            self._runs.add(int(message.dynamic_event_seq))
        elif channel == CANCEL_GOAL:  # the event of its request, or of its response, which lists the goals
            with contextlib.suppress(InvalidMessage):
                asked = (uuid_from_ros(request.goal_info.goal_id) for request in message.request)
                self._cancelled.update(asked)
                for response in message.response:
                    self._cancelled.update(uuid_from_ros(info.goal_id) for info in response.goals_canceling)
        return True

    def numbered(self, time: int, message: Any, number: int) -> None:
        """A feedback received at bag ``time`` was its writer's ``number``-th message."""
        _remember(self._numbers, number, None, NUMBERS_KEPT)
        with contextlib.suppress(InvalidMessage):
            for record in _RECORDS[FEEDBACK](time, message):
                for entry in record.message.logs:
                    _remember(self._log_numbers, entry.seq, number, NUMBERS_KEPT)

    def lost_before(self, feedback: Feedback) -> bool:
        """Whether the feedback writer's numbers show a message lost for good between the feedback
        that carried the log entry heard before a skip in ``feedback`` and ``feedback`` itself: the
        log seqs it lacked may have been on it.  A skip within one feedback, or where the bag holds
        no numbers (another recorder's), is not explained so."""
        for entry in feedback.logs:
            number = self._log_numbers.get(entry.seq)
            before = next(
                (back for back in range(1, SKIP_SPAN + 1) if (entry.seq - back) % 2**32 in self._log_numbers),
                None,
            )
            if number is None or before is None or before == 1:
                continue
            earlier = self._log_numbers[(entry.seq - before) % 2**32]
            if 0 < number - earlier <= NUMBERS_KEPT and any(
                between not in self._numbers for between in range(earlier + 1, number)
            ):
                return True
        return False

    def waits(self, arrival: int, sent: int) -> None:
        """The record that arrived ``arrival``-th, which the server ``sent`` then, waits."""
        self._sent_of[arrival] = sent

    def passed(self, arrival: int) -> None:
        """The record that arrived ``arrival``-th is passed on."""
        sent = self._sent_of.pop(arrival, None)
        if sent is not None:
            self._sent_passed = max(self._sent_passed, sent)

    def explains(self, finding: Finding, answered: Mapping[int, str]) -> bool:
        """Whether ``finding`` is what a late message not judged leaves: a log seq that skips (R7.3)
        where the seq it lacked came late, on feedback (lost on the way and sent again, not skipped);
        a status of a run whose begin came late (R2.2), read where no begin had opened it; a goal
        answered ``canceled`` where ``aborted`` was owed, its result the same (R8.2), whose
        action-level cancel came late (``answered``: the goal of each answer, by its line)."""
        seen = finding.seen
        if (
            finding.code == "goal_status"
            and isinstance(seen, Answer)
            and isinstance(finding.owed, Answer)
            and (seen.status, finding.owed.status) == (GoalStatus.CANCELED.value, GoalStatus.ABORTED.value)
            and seen.result == finding.owed.result
        ):
            return answered.get(finding.line) in self._cancelled
        if (
            finding.code == Violation.LOG_SEQ.code
            and finding.detail == SKIPS_OR_LOST
            and isinstance(seen, Feedback)
        ):
            return any((entry.seq - 1) % 2**32 in self._logs for entry in seen.logs) or self.lost_before(seen)
        owed = finding.owed
        if finding.code == Violation.STATUS_MISMATCH.code and isinstance(seen, DynamicEventStatus):
            other_run = (
                isinstance(owed, DynamicEventStatus) and owed.dynamic_event_seq != seen.dynamic_event_seq
            )
            return other_run and seen.dynamic_event_seq in self._runs
        return False


class _Begins:
    """A robot's begins: a server publishes each on the robot's own begin topic and on the fleet's,
    and a lossy link may lose either copy for good.  One copy is read; and where the bag recorded the
    robot's own topic (:attr:`own`), a fleet-wide begin only of a run after every begin read (the
    fleet's topic keeps earlier runs' begins, which a recording that starts late receives)."""

    def __init__(self) -> None:
        self.own = False  # the bag recorded the robot's own begin topic
        # the begins read lately, and on which topic each came (fleet-wide or not)
        self._read: collections.OrderedDict[DynamicEventDescription, bool] = collections.OrderedDict()
        self._last: int | None = None  # the run of the latest begin read

    def taken(self, begin: DynamicEventDescription, fleet_wide: bool) -> bool:
        """Whether to read ``begin``, come on the fleet's begin topic or (not ``fleet_wide``) the robot's."""
        if self._read.get(begin, fleet_wide) is not fleet_wide:
            return False  # the same begin, come on the other topic
        seq, last = begin.dynamic_event_seq, self._last
        if fleet_wide and self.own and last is not None and not 0 < (seq - last) % 2**32 < 2**31:
            return False
        _remember(self._read, begin, fleet_wide)
        self._last = seq
        return True


class _Listings:
    """What the action's goal statuses showed: the goals the latest held open and when it came
    (:attr:`open`), every goal it listed (:attr:`all`), and a goal they listed first, just accepted,
    whose request the bag lacks (:attr:`unheard`, until the next status takes it)."""

    def __init__(self) -> None:
        self.open: tuple[frozenset[str], int] = (frozenset(), 0)
        self.all: frozenset[str] | None = None
        self.unheard = ""

    def read(self, record: Record, *known: Container[str]) -> None:
        """Goal statuses ``record``; ``known``: the goals whose request the bag holds."""
        held_open = frozenset(uuid for uuid, status in record.message if not status.is_terminal)
        self.open = (held_open, record.line)
        self.unheard = _unheard_of(record.message, self.all, *known) or self.unheard
        self.all = frozenset(uuid for uuid, _ in record.message)

    def take_unheard(self) -> str:
        """The goal :attr:`unheard` names, which a status now takes."""
        unheard, self.unheard = self.unheard, ""
        return unheard


class _Robot:
    """One robot's records, judged as they come.  A client's and the server's introspection both
    record each goal, response and answer: a record the same as one taken before is taken once (an
    answer that differs is a second answer, which the judgement sees)."""

    def __init__(
        self,
        fleet: str,
        robot: str,
        *,
        compatibility: Compatibility | str = Compatibility.STANDARD,
        keep: bool = False,
    ) -> None:
        self.fleet, self.robot = fleet, robot
        self.compatibility = Compatibility(compatibility)
        self._judge: Checker | PartialJudge | None = None  # made at the first record: the channels are known
        self.channels: set[str] = set()
        self.begins = _Begins()
        self.contents = True  # its send_goal introspection holds the goals (not METADATA alone)
        self.refused = 0
        # the records taken lately: the client's copy of one comes close to the server's
        self._seen: collections.OrderedDict[tuple[Any, ...], None] = collections.OrderedDict()
        self._calls = _Calls()
        # records held for the server's order: (stamp, order, arrival, record)
        self._waiting: list[tuple[int, float, int, Record]] = []
        self._waiting_goals: dict[str, tuple[int, float, int, Record]] = {}
        self._waiting_answers: dict[str, tuple[int, float, int, Record]] = {}
        self._waiting_responses: dict[str, tuple[int, float, int, Record]] = {}
        self._last: collections.OrderedDict[str, int] = collections.OrderedDict()  # a goal's latest key
        self._goals: collections.OrderedDict[str, Record] = collections.OrderedDict()  # awaiting a response
        self._passed_goals: collections.OrderedDict[str, Record] = collections.OrderedDict()  # passed on
        self._answered: collections.OrderedDict[int, str] = collections.OrderedDict()  # goals, by answer line
        # the goals whose answer a client asked for, and those whose goal status showed their end
        self._asked: collections.OrderedDict[str, None] = collections.OrderedDict()
        self._settled: collections.OrderedDict[str, str] = collections.OrderedDict()
        self._requested: collections.OrderedDict[str, None] = collections.OrderedDict()  # goals passed on
        self._last_status: Record | None = None
        self._listings = _Listings()
        self._before: list[Report] = []  # the judgements cut where the bag lost a goal's request
        self.lost: list[tuple[int, str]] = []
        self.unheard: list[tuple[int, str]] = []
        self._unbegun: list[tuple[int, int]] = []  # of the judgements cut where a request was lost
        self.lateness = _Lateness()
        self._arrived = 0
        self._began: int | None = None  # the bag time of the robot's first message
        self._server_introspects = False  # the bag holds the server's own records of its goal service
        self._logged_last = 0  # the latest time a feedback's logs carried so far
        self.keep = keep  # keep every record passed on, in ``kept`` (bag_records)
        self.kept: list[Record] = []

    def take(
        self, channel: str, time: int, message: Any, sent: int | None = None, *, fleet_wide: bool = False
    ) -> None:
        """A message received at bag ``time`` and, where the bag says, ``sent`` by its publisher then
        (``fleet_wide``: a begin of the fleet's begin topic)."""
        self.channels.add(channel)
        if self._began is None:
            self._began = time
        server_sent = sent is not None and (
            channel not in _SERVICES or int(message.info.event_type) in (_REQUEST_RECEIVED, _RESPONSE_SENT)
        )
        while self._waiting and self._waiting[0][0] <= time - HOLD:  # what is due goes first
            self._release()
        delayed = server_sent and sent is not None and self.lateness.delayed(time, sent)
        if delayed and sent is not None and self.lateness.overtaken(time, channel, message, sent):
            return  # sent before what was passed on: not judged
        stamp = _stamp(channel, message, time, sent)
        if delayed and sent is not None and self.lateness.clocks_agree:
            stamp = sent  # nothing sent after it passed on yet: it goes where it was sent
        # nothing goes before the robot's first message: a status latched for a late subscriber comes
        # at once, published before the recording began
        stamp = max(stamp, self._began)
        sent_then = channel == FEEDBACK and stamp != time and sent == stamp
        call: tuple[str, bytes, int] | None = None
        own = False  # a cancel the server stamped: by its own stamp, not after what named its goal
        try:
            if channel in _SERVICES:
                message = self._calls.paired(channel, message, (time, sent))
                if message is None:
                    return
                call = message[3]
                own = channel == CANCEL_GOAL and message[0] in (_REQUEST_RECEIVED, _RESPONSE_SENT)
                if channel == SEND_GOAL and message[0] in (_REQUEST_RECEIVED, _RESPONSE_SENT):
                    self._server_introspects = True
                if channel == GET_RESULT and message[2] is None:
                    _remember(self._asked, uuid_from_ros(message[1].goal_id), None)
            for record in _RECORDS[channel](time, message):
                if record.kind == "begin" and not self.begins.taken(record.message, fleet_wide):
                    continue
                if record.kind in _EVENT_KINDS:
                    # one call seen by both the client's and the server's introspection is one record; an
                    # answer asked for again is the same answer (another answer to the goal is not)
                    same = (
                        (record.goal_uuid, record.message, record.status) if record.kind == "result" else call
                    )
                    key = (record.kind, same)
                    if key in self._seen:
                        continue
                    self._seen[key] = None
                    if len(self._seen) > _CALLS:
                        self._seen.popitem(last=False)
                self._order(record, stamp, sent_then, sent if server_sent else None, own=own)
        except InvalidMessage:
            self.refused += 1
        early = self._calls.early.pop(call, None) if call is not None else None
        if early is not None:  # its response came first: taken now, as of when it came
            self.take(channel, early[1], early[0], early[2])

    def _logged_after(self, stamp: int) -> tuple[int, float, int, Record] | None:
        """The first waiting feedback whose logs the server stamped after ``stamp``, if any (looked for
        only when feedback came out of its order: in order, nothing is)."""
        if stamp >= self._logged_last:
            self._logged_last = stamp
            return None
        later = [item for item in self._waiting if item[3].kind == "feedback" and _logged(item[3]) > stamp]
        return min(later) if later else None

    def _order(
        self,
        record: Record,
        stamp: int,
        sent: bool = False,
        server_sent: int | None = None,
        *,
        own: bool = False,
    ) -> None:
        """Pass records on in the server's order: a recorder receives each topic in order, but not
        the topics in order with one another (a goal's request event may come after the status its
        start published).  Each record waits :data:`SKEW` of bag time, then goes in the order of the
        time the server stamped on it (a status's ``time``, a begin's ``start_time``, a service
        event's ``stamp``; for feedback, when it was sent where the bag says, else the bag time), ties
        in bag order.  The records of one goal
        keep their own order: its answer goes after the feedback received before it, and feedback
        received while its answer waits is read as sent before it (the feedback topic and the
        result service are two channels: a recorder cannot tell late delivery from late sending), unless
        the bag says when the feedback was sent (``sent``): then it goes by that alone; a cancel the
        server stamped (``own``, its own record of a cancel's request or response) goes by its stamp
        too.  A record the server published keeps the time the bag says it was sent (``server_sent``)
        until it is passed on: a message sent before the latest of those came too late to be put in
        its place (:attr:`_Lateness.late`)."""
        while self._waiting and self._waiting[0][0] <= record.time - HOLD:  # what is due goes first
            self._release()
        after = _after_its_request(self._waiting, record)
        guess = record.kind == "feedback" and not sent  # when it was sent, read from what came around it
        answer = self._waiting_answers.get(record.goal_uuid) if guess else None
        logged = _logged(record) if guess else 0
        overtaken = self._logged_after(logged) if logged else None
        key: tuple[int, float]
        if after is not None:
            key = after
        elif overtaken is not None or answer is not None:
            # feedback received after feedback the server logged later (a lossy link sent it again,
            # after those) goes before them, by its logs' time; received while its answer waits, it
            # goes before that answer; the earlier of the two where both hold
            key = min((item[0], item[1] - 0.5) for item in (overtaken, answer) if item is not None)
        elif sent:
            key = (stamp, float(self._arrived))
        elif record.goal_uuid and record.kind not in _OPENING and not own:
            key = (max(stamp, self._last.get(record.goal_uuid, stamp)), float(self._arrived))
        else:  # a goal's request and response go by their own stamps: what names it goes after them
            key = (stamp, float(self._arrived))
        if record.goal_uuid:
            self._last[record.goal_uuid] = max(key[0], self._last.get(record.goal_uuid, key[0]))
            while len(self._last) > _CALLS:
                self._last.popitem(last=False)
        entry = (key[0], key[1], self._arrived, record)
        if server_sent is not None:
            self.lateness.waits(self._arrived, server_sent)
        heapq.heappush(self._waiting, entry)
        self._arrived += 1
        if record.kind == "goal":
            self._waiting_goals[record.goal_uuid] = entry
        elif record.kind == "goal_response":
            self._waiting_responses[record.goal_uuid] = entry
        elif record.kind == "result":
            self._waiting_answers[record.goal_uuid] = entry
        while self._waiting and self._waiting[0][0] <= record.time - HOLD:
            self._release()

    def _release(self) -> None:
        """Pass on the first record waiting; a goal stamped later than a record that names it (two
        hosts' clocks) goes first, and so does its response: a client stamps the response when it
        receives it, after the server has begun to send the goal's feedback."""
        entry = heapq.heappop(self._waiting)
        record = entry[3]
        if self._waiting_answers.get(record.goal_uuid) is entry:
            del self._waiting_answers[record.goal_uuid]
        if self._waiting_responses.get(record.goal_uuid) is entry:
            del self._waiting_responses[record.goal_uuid]
        uuid = record.goal_uuid
        goal = self._waiting_goals.pop(uuid, None) if uuid else None
        response = self._waiting_responses.pop(uuid, None) if uuid and record.kind != "goal" else None
        for first in (goal, response):
            if first is not None and first is not entry:
                self._waiting.remove(first)
                heapq.heapify(self._waiting)
                self._passing(first)
        self._passing(entry)
        # its response lost, and its feedback or answer among the records held: it was accepted as it
        # came, before the records between (the status of a child's end, say)
        lost = record.kind == "goal" and uuid in self._goals and uuid not in self._waiting_responses
        if lost and any(item[3].goal_uuid == uuid and item[3].kind in _ACCEPTED_BY for item in self._waiting):
            self.unheard_response(record)

    def _passing(self, entry: tuple[int, float, int, Record]) -> None:
        """Pass on a waiting record, noting when the server sent it where the bag says."""
        self.lateness.passed(entry[2])
        self._pass(entry[3])

    @property
    def judge(self) -> Checker | PartialJudge:
        """The observer, for a robot whose goals the bag holds; else the judge of what its topics show."""
        if self._judge is None:
            header = TraceHeader(fleet=self.fleet, robot=self.robot, compatibility=self.compatibility)
            self._judge = Checker(header, apart=True) if self.judged else PartialJudge(header, SKEW)
        return self._judge

    def _pass(self, record: Record) -> None:
        if self.keep:
            self.kept.append(record)
        if isinstance(self.judge, PartialJudge):
            self.judge.push(record)
            return
        if record.kind == GOAL_STATUSES:  # the goals' own records tell the rest
            for uuid, _ in record.message:
                # the server lists only a goal it accepted: one whose response has not come (a lossy
                # link delivers it late, or never) was accepted by now
                if uuid in self._goals and uuid not in self._waiting_responses:
                    self.unheard_response(record, uuid)
            self._goals_ended(record.message)
            self._listings.read(record, self._requested, self._waiting_goals)
            return
        listed = self._listings.take_unheard() if record.kind == "status" else ""
        if (
            listed and listed not in self._requested
        ):  # the first status after them (its feedback did not come first)
            self.lost_request(attrs.evolve(record, goal_uuid=listed), seed=record)
            self._last_status = record
            return
        if record.kind in ("feedback", "result") and record.goal_uuid not in self._requested:
            assert isinstance(self._judge, Checker)
            if _names_another_child(self._judge.pending, self._last_status, record):  # the next status
                self._listings.unheard = record.goal_uuid
                return
            self.lost_request(record)
        elif record.kind in _ACCEPTED_BY and record.goal_uuid in self._goals:
            self.unheard_response(record)
        elif record.kind == "status":
            self._last_status = record
            started = _started_by(self._goals, record.message, *self._listings.open)
            if started is not None and self._server_introspects:
                self.unheard_response(record, started)
        if record.kind == "result":
            _remember(self._answered, record.line, record.goal_uuid)
        if record.kind == "goal":
            _remember(self._requested, record.goal_uuid, None)
            _remember(self._passed_goals, record.goal_uuid, record)
            self._goals[record.goal_uuid] = record
            if len(self._goals) > _CALLS:
                self._goals.popitem(last=False)
        elif record.kind == "goal_response":
            if record.goal_uuid not in self._goals:
                return  # the response to a goal the bag does not hold (lost, or before the recording)
            del self._goals[record.goal_uuid]
            ended = _published_on_acceptance(self._waiting, record.goal_uuid) if record.accepted else None
            if ended is not None:
                self._goals_ended(ended, but=record.goal_uuid)
        self.judge.push(record)

    def _goals_ended(self, statuses: Sequence[tuple[str, GoalStatus]], but: str = "") -> None:
        """Goal statuses that show goals ended (all but ``but``): each goal's end shows its child's end,
        unless its answer, among the records held, says the child was cancelled (a server may answer a
        goal as it takes a CANCEL, before the child's end: the answer, in its place, is judged then)."""
        for uuid, status in statuses:
            if status.is_terminal and uuid != but:
                held = self._waiting_answers.get(uuid)
                stopped = held is not None and held[3].message.status == Status.CANCELED.value
                if uuid not in self._settled and not stopped and isinstance(self.judge, Checker):
                    self.judge.goal_ended(uuid)
                _remember(self._settled, uuid, status.value)

    def lost_request(self, record: Record, seed: Record | None = None) -> None:
        """``record`` names a goal whose request the bag lacks (lost on the way: a recorder that had
        not yet matched a new client's publisher; or sent before the recording began, or so late it
        is not judged): the statuses around it show a child no goal explains.  What was judged within
        :data:`SKEW` before it is let go (its findings may be that goal's doing), and the judgement
        begins anew, as a trace that begins mid-way does (:func:`_begun_anew`), or at ``seed``, the
        first status after goal statuses that listed the goal just accepted."""
        assert isinstance(self._judge, Checker)
        report, pending = self._judge.cut()
        self._unbegun.extend(self._judge.unbegun)
        kept = tuple(finding for finding in report.findings if finding.line < record.time - SKEW)
        self._before.append(attrs.evolve(report, findings=kept))
        self.lost.append((record.time, record.goal_uuid))
        header = TraceHeader(fleet=self.fleet, robot=self.robot, compatibility=self.compatibility)
        self._judge = Checker(header, apart=True)
        for item in _begun_anew(pending, self._last_status, self._goals, self._passed_goals, seed):
            self._judge.push(item)
        _remember(self._requested, record.goal_uuid, None)  # what follows of it is the new judgement's

    def unheard_response(self, record: Record, uuid: str | None = None) -> None:
        """``record`` is the feedback or answer of a goal whose request the bag holds and whose response
        it lacks (or the status that shows goal ``uuid``'s child running, or the goal statuses that
        list it): a server feeds back, answers, runs the child of and lists only a goal it accepted,
        so the response was accepted, and lost (or delayed past :data:`HOLD`) on its way to the
        recorder (a lossy link: a service event a writer's short history let go before it was sent
        again).  It is read as accepted, here, and said."""
        uuid = record.goal_uuid if uuid is None else uuid
        self._goals.pop(uuid)
        self.unheard.append((record.time, uuid))
        time = record.time
        response = Record(line=record.line, kind="goal_response", time=time, goal_uuid=uuid, accepted=True)
        if self.keep:
            self.kept.append(response)
        self.judge.push(response)

    @property
    def judged(self) -> bool:
        """Whether the bag recorded this robot's goals (its send_goal introspection): without them,
        its statuses show child events no goal explains, and it is a partial view."""
        return SEND_GOAL in self.channels and self.contents

    def finish(self, source: str, end: int) -> RobotReport:
        """The robot's report; ``end`` is the bag time of the bag's last message: an answer owed by a
        step within :data:`HOLD` of it may have been on its way when the recording stopped (a lossy
        link delivers a message that late: found leaving out of a 30% run's bag a FINISHED's answer
        and the goal statuses that showed it, 5 s before the recording stopped)."""
        channels = tuple(sorted(self.channels))
        absent = tuple(CHANNELS[name] for name in CHANNELS if name not in self.channels)
        if SEND_GOAL in self.channels and not self.contents:
            absent = (f"{CHANNELS[SEND_GOAL]}: recorded without contents (METADATA)", *absent)
        while self._waiting:
            self._release()
        self.judge.source = f"{source}: {self.fleet}/{self.robot}"
        if isinstance(self.judge, Checker):
            evidence = AnswerEvidence(asked=self._asked, settled=self._settled, until=end - HOLD)
            report = self.judge.finish(evidence)
        else:
            report = self.judge.finish()
        for before in reversed(self._before):
            records = before.records + report.records
            report = attrs.evolve(report, records=records, findings=before.findings + report.findings)
        explained = self.lateness.explains
        kept = tuple(finding for finding in report.findings if not explained(finding, self._answered))
        return RobotReport(
            self.fleet, self.robot, channels, absent, attrs.evolve(report, findings=kept), not self.judged,
            self.refused, tuple(self.lost), tuple(self.unheard), tuple(self.lateness.late),
            (*self._unbegun, *self.judge.unbegun),
        )  # fmt: skip


def _started_by(
    goals: Mapping[str, Record], status: Any, listing: Container[str] = (), listed_at: int = 0
) -> str | None:
    """The goal of ``goals`` (awaiting their responses) whose child ``status`` shows running: a NEXT of
    the status's run that names the child's id, else the first of that run that lets the server name
    it (id 0); of several, one the latest goal statuses held open (``listing``, at bag time
    ``listed_at``) first, and never one requested :data:`SKEW` or more before them that they do not
    hold.  A server shows a child running only once it accepted and started its NEXT, and lists only
    a goal it accepted (found dropping messages of a 30% run's bag: a NEXT refused for its NaN
    stubborn period, its response lost, was read as accepted, R4.11, from the status of a later
    NEXT's child naming the same id).  Only where the bag holds the server's own records of its
    goals: a response recorded by a client alone is stamped as it arrives, after the statuses the
    server published on accepting the goal."""
    if status.dynamic_state != DynamicState.RUNNING:
        return None
    run = status.dynamic_event_seq
    nexts = [
        (uuid, goal.message) for uuid, goal in goals.items()
        if goal.message.event_type == EventType.NEXT and goal.message.dynamic_event_seq == run
    ]  # fmt: skip
    possible = [
        (uuid, goal) for uuid, goal in nexts if uuid in listing or goals[uuid].line > listed_at - SKEW
    ]
    named = [uuid for uuid, goal in possible if goal.id == status.id]
    unnamed = [uuid for uuid, goal in possible if goal.id == 0]
    candidates = named or unnamed
    return next((uuid for uuid in candidates if uuid in listing), next(iter(candidates), None))


def _unheard_of(
    statuses: Sequence[tuple[str, GoalStatus]], before: Container[str] | None, *known: Container[str]
) -> str:
    """The first goal ``statuses`` list just accepted, or list first where the goal statuses ``before``
    them were read (executing or ended: the goal statuses of its acceptance replaced on the way),
    that none of ``known`` holds (its request lost on the way, or so late it is not judged), or
    ``""``."""
    accepted = (
        uuid
        for uuid, status in statuses
        if status is GoalStatus.ACCEPTED or (before is not None and uuid not in before)
    )
    return next((uuid for uuid in accepted if not any(uuid in goals for goals in known)), "")


def _after_its_request(
    waiting: list[tuple[int, float, int, Record]], record: Record
) -> tuple[int, float] | None:
    """Where ``record`` goes when it is a cancel's response that refused it as of a goal already
    terminated (:data:`TERMINATED`), and the cancel's request still ``waiting``: just after that
    request, where the judge reads it beside the request (the goal's end goes before the request).
    Found at 10% loss: a goal's answer came late, the status of its child's end was lost, and the
    refused cancel was read as a refusal of a running goal's (R10.3); and in the lab's recordings,
    a child that ended as the cancel came, its records between the cancel's request and response."""
    if record.kind != "cancel_response" or record.status != TERMINATED:
        return None
    requests = (item for item in waiting if item[3].kind == "cancel_request")
    request = next((item for item in requests if item[3].goal_uuid == record.goal_uuid), None)
    return None if request is None else (request[0], request[1] + 0.25)


def _names_another_child(pending: Sequence[Record], last_status: Record | None, record: Record) -> bool:
    """Whether the status a judgement begun anew at ``record`` (the feedback or answer of a goal whose
    request the bag lacks) would take first, of the records ``pending`` or else ``last_status``, shows
    another child running than ``record`` names: the statuses since were lost, and that child may have
    ended (found at 30% loss: the status of child 13's end, its answer and the next NEXT's request
    lost, the judgement begun at child 13 running read child 14's statuses as wrong, R2.2).  The
    judgement then begins at the next status, as for a goal the goal statuses listed
    (:func:`_begun_anew`)."""
    statuses = [item for item in pending if item.kind == "status"]
    seed = statuses[-1] if statuses else last_status
    if seed is None or seed.message.dynamic_state != DynamicState.RUNNING:
        return False  # from WAITING (or INACTIVE) the goal's NEXT may start any child
    return int(seed.message.id) != int(record.message.id)


def _published_on_acceptance(
    waiting: list[tuple[int, float, int, Record]], uuid: str
) -> Sequence[tuple[str, GoalStatus]] | None:
    """The goal statuses the server published as it accepted goal ``uuid``, among the records
    ``waiting``: the first that list it, where they list it as accepted, or as executing and were
    sent before any feedback of it held (a binding that starts a goal as it accepts it publishes the
    two arrays at once, and the second replaces the first).  They show the goals that had ended by then:
    where the bag lost the status of a child's end and the goal statuses that followed it (each
    topic keeps one message, and the next replaced it), that end goes before the acceptance, not
    after it (found at 30% loss: a NEXT accepted after the previous child's end, read as accepted
    while it ran, R4.6)."""
    arrays = [
        item
        for item in waiting
        if item[3].kind == GOAL_STATUSES and any(u == uuid for u, _ in item[3].message)
    ]
    if not arrays:
        return None
    first = min(arrays)
    status = dict(first[3].message)[uuid]
    fed_back = [item for item in waiting if item[3].kind == "feedback" and item[3].goal_uuid == uuid]
    started = status is GoalStatus.EXECUTING and (not fed_back or first < min(fed_back))
    return first[3].message if status is GoalStatus.ACCEPTED or started else None


def _begun_anew(
    pending: list[Record],
    last_status: Record | None,
    goals: Mapping[str, Record],
    passed: Mapping[str, Record],
    seed: Record | None,
) -> list[Record]:
    """What a judgement begun anew where the bag lacks a goal's request takes first, of the records
    ``pending`` (pushed and not judged): the latest status before the goal's feedback or answer (its
    start, or later; else ``last_status``, the last judged), the requests whose responses are to come
    (:func:`_awaiting`), then the rest.  Or ``seed``, the first status after goal statuses that listed
    the goal just accepted, and the requests awaiting responses, nothing before it: what the goal did
    comes after those goal statuses (found at 30% loss: a FINISHED whose request and response came 12 s
    late, after the run's INACTIVE, the status of the last child's end lost; the judgement begun at the
    status before held that child running)."""
    statuses = [index for index, item in enumerate(pending) if item.kind == "status"]
    if seed is not None:
        return [seed, *_awaiting(goals, passed, [])]
    seed = pending[statuses[-1]] if statuses else last_status
    rest = pending[statuses[-1] + 1 :] if statuses else pending
    awaiting = _awaiting(goals, passed, rest)
    return [seed, *awaiting, *rest] if seed is not None else [*awaiting, *rest]


def _awaiting(goals: Mapping[str, Record], passed: Mapping[str, Record], rest: list[Record]) -> list[Record]:
    """The requests a judgement begun anew before ``rest`` takes first: of the ``goals`` whose
    responses are to come, and of the goals ``passed`` on whose responses are among ``rest`` without
    their requests (a request judged just before the cut, its response not yet), in bag order."""
    requested = {item.goal_uuid for item in rest if item.kind == "goal"}
    responded = [
        passed[item.goal_uuid] for item in rest
        if item.kind == "goal_response" and item.goal_uuid not in requested and item.goal_uuid in passed
    ]  # fmt: skip
    awaiting = [goal for goal in goals.values() if goal not in rest]
    awaiting += [goal for goal in responded if goal not in awaiting]
    return sorted(awaiting, key=lambda goal: goal.line)


def _remember(books: collections.OrderedDict[Any, Any], key: Any, value: Any, limit: int = 0) -> None:
    """Keep ``key`` in ``books``, the latest ``limit`` keys only (:data:`_CALLS` where not said)."""
    books[key] = value
    books.move_to_end(key)
    while len(books) > (limit or _CALLS):
        books.popitem(last=False)


#: How long (bag time, nanoseconds) a record waits for records the server published before it; a
#: stamp farther than this from the bag time (another clock: simulated time, another host) is not used.
SKEW = 1_000_000_000


#: How long a record waits (bag time) for those the server sent before it, on other channels or,
#: for feedback, on its own: a recorder on a lossy link receives a lost message when it is sent again,
#: seconds later (Fast DDS repairs at its writers' heartbeat, every 3 s by default).  A message of the
#: server's that the bag says was on its way more than this longer than its quickest goes where it was
#: sent, unless it was sent before a record already passed on: then it is not judged, and
#: :attr:`RobotReport.late` says it (:class:`_Lateness`).
HOLD = 10_000_000_000


def _stamp(channel: str, message: Any, time: int, sent: int | None) -> int:
    """The time the server stamped on a message, when it is within :data:`SKEW` of the bag time (a
    status or a service event of the server's, its goal request received or its response sent: up to
    :data:`HOLD` before it, since a server stamps them as it publishes them, R2.2, and a lossy link
    may deliver them that late).  A message with no stamp of its own (feedback, the goal
    statuses), or whose stamp is not used (a begin's start time more than :data:`SKEW` before the
    bag time), goes by the time its publisher sent it where the bag holds it
    (:mod:`dynevent.bags.sent`), up to :data:`HOLD` before the bag time; else by the bag time.  A
    service event a client published
    (its request sent, its response received) has the client's clock, which may be another host's:
    its bag time is used.  (A feedback's logs' time orders it among feedback alone: :func:`_logged`.)"""
    if channel in _SERVICES and int(message.info.event_type) in (_REQUEST_SENT, _RESPONSE_RECEIVED):
        return time
    source = {"status": "time", "begin": "start_time"}.get(channel)
    stamped = (
        getattr(message, source, None) if source else getattr(getattr(message, "info", None), "stamp", None)
    )
    by_sent = sent if sent is not None and -HOLD <= sent - time <= SKEW else time
    if stamped is None:
        return by_sent
    nanoseconds = int(stamped.sec) * 1_000_000_000 + int(stamped.nanosec)
    # what the server stamps as it sends it (a status, its own record of a goal's request and
    # response) a lossy link may deliver up to HOLD late
    server = channel == "status" or channel in _SERVICES
    earliest = HOLD if server else SKEW
    return nanoseconds if -earliest <= nanoseconds - time <= SKEW else by_sent


def _logged(record: Record) -> int:
    """The time the server logged a feedback record's last entry, in nanoseconds (0: no entry)."""
    logs = record.message.logs
    return int(logs[-1].unix_millis_time) * 1_000_000 if logs else 0


#: The channels of service events, and how many calls without a response (and records taken lately)
#: a robot keeps.
_SERVICES = frozenset({SEND_GOAL, GET_RESULT, CANCEL_GOAL})
_CALLS = 1024
#: How many of a robot's feedback numbers (and log seqs, each with its feedback's number) a reader
#: keeps, the latest: a gap farther back than these is not read as a feedback lost.
NUMBERS_KEPT = 65_536
#: The most log seqs a skip explained by a feedback lost may lack (a feedback carries a few).
SKIP_SPAN = 64
#: The records that open a goal: each goes by its own stamp, never after a record that names the goal
#: but was received first (its start's feedback, say).
_OPENING = frozenset({"goal", "goal_response"})
#: The records of a goal that show it was accepted (a server feeds back and answers only a goal it
#: accepted).
_ACCEPTED_BY = frozenset({"feedback", "result"})
#: The records a service event gives.
_EVENT_KINDS = frozenset({"goal", "goal_response", "result", "cancel_request", "cancel_response"})


class _FleetBegins:
    """The fleet-wide begin topic: each begin goes to its robot, which reads a begin that came on
    its own begin topic too once (either may be lost over a lossy link, and the other not)."""

    def __init__(
        self, robots: dict[tuple[str, str], _Robot], compatibility: Compatibility, keep: bool = False
    ) -> None:
        self.robots = robots
        self.compatibility = compatibility
        self.keep = keep

    def take(self, channel: str, time: int, message: Any, sent: int | None = None) -> None:
        key = (str(message.fleet), str(message.robot))
        robot = self.robots.get(key)
        if robot is None:
            robot = self.robots[key] = _Robot(*key, compatibility=self.compatibility, keep=self.keep)
        robot.take(channel, time, message, sent, fleet_wide=True)


def _status(time: int, message: Any) -> Iterator[Record]:
    yield Record(line=time, kind="status", time=time, message=status_from_ros(message))


def _begin(time: int, message: Any) -> Iterator[Record]:
    yield Record(line=time, kind="begin", time=time, message=begin_from_ros(message))


def _feedback(time: int, message: Any) -> Iterator[Record]:
    uuid = uuid_from_ros(message.goal_id)
    yield Record(
        line=time, kind="feedback", time=time, goal_uuid=uuid, message=feedback_from_ros(message.feedback)
    )


def _goal_status(time: int, message: Any) -> Iterator[Record]:
    statuses = tuple(
        (uuid_from_ros(item.goal_info.goal_id), _GOAL_STATUSES[int(item.status)])
        for item in message.status_list
        if int(item.status) in _GOAL_STATUSES
    )
    yield Record(line=time, kind=GOAL_STATUSES, time=time, message=statuses)


def _send_goal(time: int, call: Any) -> Iterator[Record]:
    _, request, response, _ = call
    uuid = uuid_from_ros(request.goal_id)
    if response is None:
        yield Record(line=time, kind="goal", time=time, goal_uuid=uuid, message=goal_from_ros(request.goal))
    else:
        yield Record(
            line=time, kind="goal_response", time=time, goal_uuid=uuid, accepted=bool(response.accepted)
        )


def _get_result(time: int, call: Any) -> Iterator[Record]:
    _, request, response, _ = call
    status = None if response is None else _TERMINAL.get(int(response.status))
    if status is not None:  # STATUS_UNKNOWN: the server knows no such goal, which answers nothing
        uuid = uuid_from_ros(request.goal_id)
        result = result_from_ros(response.result)
        yield Record(line=time, kind="result", time=time, goal_uuid=uuid, message=result, status=status)


def _cancel_goal(time: int, call: Any) -> Iterator[Record]:
    _, request, response, _ = call
    uuid = uuid_from_ros(request.goal_info.goal_id)
    if uuid == "0" * 32:
        return  # a cancel of every goal (or of goals before a time): no record says that
    if response is None:
        yield Record(line=time, kind="cancel_request", time=time, goal_uuid=uuid)
    else:
        canceling = {uuid_from_ros(info.goal_id) for info in response.goals_canceling}
        ended = int(response.return_code) == CANCEL_GOAL_TERMINATED and uuid not in canceling
        yield Record(
            line=time, kind="cancel_response", time=time, goal_uuid=uuid, accepted=uuid in canceling,
            status=TERMINATED if ended else "",
        )  # fmt: skip


_RECORDS: dict[str, Callable[[int, Any], Iterator[Record]]] = {
    "status": _status,
    "begin": _begin,
    FEEDBACK: _feedback,
    GOAL_STATUS: _goal_status,
    SEND_GOAL: _send_goal,
    GET_RESULT: _get_result,
    CANCEL_GOAL: _cancel_goal,
}


# --------------------------------------------------------------------------- the message definitions

#: The action's own message types (``rmf_task_msgs/action/DynamicEvent_*``) and the services ROS 2
#: derives from every action (``ros2/rcl_interfaces``' action_msgs and the rosidl action
#: generators), whose introspection events a bag may hold.
_DERIVED = {
    "rmf_task_msgs/action/DynamicEvent_FeedbackMessage": (
        "unique_identifier_msgs/UUID goal_id\nrmf_task_msgs/action/DynamicEvent_Feedback feedback"
    ),
    "rmf_task_msgs/action/DynamicEvent_SendGoal_Request": (
        "unique_identifier_msgs/UUID goal_id\nrmf_task_msgs/action/DynamicEvent_Goal goal"
    ),
    "rmf_task_msgs/action/DynamicEvent_SendGoal_Response": "bool accepted\nbuiltin_interfaces/Time stamp",
    "rmf_task_msgs/action/DynamicEvent_GetResult_Request": "unique_identifier_msgs/UUID goal_id",
    "rmf_task_msgs/action/DynamicEvent_GetResult_Response": (
        "int8 status\nrmf_task_msgs/action/DynamicEvent_Result result"
    ),
    "action_msgs/srv/CancelGoal_Request": "action_msgs/GoalInfo goal_info",
    "action_msgs/srv/CancelGoal_Response": ("int8 return_code\naction_msgs/GoalInfo[] goals_canceling"),
}
_EVENTS = (
    "rmf_task_msgs/action/DynamicEvent_SendGoal",
    "rmf_task_msgs/action/DynamicEvent_GetResult",
    "action_msgs/srv/CancelGoal",
)


@functools.cache
def typestore() -> Any:
    """rosbags' type store for ROS 2 Jazzy, with every type a Dynamic Event conversation uses."""
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.ROS2_JAZZY)
    types: dict[str, Any] = {}
    for name, text in _definitions().items():
        types.update(get_types_from_msg(text, name))
    store.register(types)
    return store


def _definitions() -> dict[str, str]:
    """Every definition, from the project's interface files and :data:`_DERIVED`."""
    # the package's files, without importing dynevent.ros (which needs rclpy)
    root = importlib.resources.files("dynevent") / "ros" / "setup" / "interfaces" / "rmf_task_msgs"
    definitions = {}
    for name in ("DynamicEventStatus", "DynamicEventDescription", "LogEntry"):
        definitions[f"rmf_task_msgs/msg/{name}"] = (root / "msg" / f"{name}.msg").read_text("utf-8")
    parts = (root / "action" / "DynamicEvent.action").read_text("utf-8").split("\n---")
    for part, text in zip(("Goal", "Result", "Feedback"), parts, strict=True):
        definitions[f"rmf_task_msgs/action/DynamicEvent_{part}"] = text.strip("-\n")
    definitions.update(_DERIVED)
    for service in _EVENTS:
        definitions[f"{service}_Event"] = "\n".join(
            (
                "service_msgs/ServiceEventInfo info",
                f"{service}_Request[<=1] request",
                f"{service}_Response[<=1] response",
            )
        )
    return definitions


def message_definition(msgtype: str) -> str:
    """The definition of ``msgtype`` as rosbag2 keeps it beside a topic: ROS 2's concatenated form,
    the type's own text, then each type it uses after a line of ``=`` and ``MSG: <type>``."""
    own = _definitions()
    store = typestore()

    def text_of(name: str) -> str:
        if name in own:
            return own[name]
        generated: str = store.generate_msgdef(name, ros_version=2)[0]
        return generated.split("\n" + "=" * 80, maxsplit=1)[0]

    used: list[str] = []

    def visit(name: str) -> None:
        for line in text_of(name).splitlines():
            words = line.split("#", 1)[0].split()
            if len(words) >= 2 and "/" in words[0] and "=" not in words[1]:
                sub = _full_name(words[0].split("[", 1)[0])
                if sub not in used:
                    used.append(sub)
                    visit(sub)

    visit(msgtype)
    parts = [text_of(msgtype).rstrip("\n")]
    for name in used:
        parts.append("=" * 80 + f"\nMSG: {name}\n" + text_of(name).rstrip("\n"))
    return "\n".join(parts) + "\n"


def _full_name(name: str) -> str:
    """``pkg/Type`` as ``pkg/msg/Type``; a name with its interface kind stays."""
    return name if name.count("/") == 2 else name.replace("/", "/msg/", 1)
