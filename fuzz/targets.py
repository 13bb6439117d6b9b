"""The entry points the fuzzer drives, each with valid seed documents and how to call it.

An entry point is any public function or constructor that takes outside
input: message mirrors (from dicts, JSON and keyword arguments), the
machine's inputs and configuration, records, snapshots of a robot and of a
fleet, the event description, protocol names, traces, vector files, the
driver protocol, the SQLite state store, the client machine's requests, and
each command line's arguments and files.  Each may raise only dynevent's
own errors (:class:`dynevent.errors.DyneventError`); a command line may
only exit 0, 1 or 2, and never print a traceback.
"""

from __future__ import annotations

import contextlib
import functools
import io
import os
import shlex
import shutil
import sqlite3
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import attrs

from dynevent import client as cl
from dynevent.conformance import vectors
from dynevent.conformance.judge import check_trace
from dynevent.conformance.records import config_from_json, input_from_json, output_from_json, rule_validator
from dynevent.conformance.vectors import driver
from dynevent.errors import DyneventError, FileError
from dynevent.server import inputs as ins
from dynevent.server import machine, snapshot
from dynevent.server.fleet import Fleet
from dynevent.server.store import StateStore
from dynevent.tools import cli
from dynevent.wire.description import EventDescription, EventSpec
from dynevent.wire.messages import MESSAGE_TYPES
from dynevent.wire.names import action_name, parse_name, validate_token

from . import mutate

ROOT = Path(__file__).resolve().parents[1]


@attrs.frozen
class Target:
    """One entry point: ``call`` takes a mutated seed; ``text`` seeds are mutated as text as well."""

    name: str
    seeds: tuple[Any, ...]
    call: Callable[[Any], object]
    text: bool = False
    cli: bool = False
    kwargs: bool = False  # the seed is keyword arguments: only their values are mutated


# --------------------------------------------------------------------------- seeds


@functools.cache
def material() -> dict[str, Any]:
    """Valid documents of every kind, taken from the shipped conformance vectors run through the machine."""
    found: dict[str, Any] = {"inputs": [], "outputs": [], "configs": [], "snapshots": [], "requests": []}
    for vector in vectors.load_vectors():
        found["configs"].append(vector.config)
        config = config_from_json(vector.config, "$.config")
        state = driver.state_from_json(vector.fleet, vector.robot, vector.state)
        found["requests"].append(
            {"op": "reset", "fleet": vector.fleet, "robot": vector.robot, "config": vector.config}
        )
        for step in vector.steps:
            found["inputs"].append(step.input)
            found["outputs"].extend(step.expect)
            found["requests"].append({"op": "apply", "input": step.input})
            try:
                state = machine.step(state, input_from_json(step.input, "$"), config).state
            except ValueError:  # a vector of a refused input
                continue
            found["snapshots"].append(snapshot.snapshot(state))
    found["snapshots"] = found["snapshots"][::7]
    fleet = Fleet(machine.ServerConfig())
    for index, data in enumerate(found["snapshots"][:6]):
        state = snapshot.restore(data)
        with contextlib.suppress(ValueError):
            fleet.add(
                state.fleet, f"{state.robot}{index}", state=attrs.evolve(state, robot=f"{state.robot}{index}")
            )
    found["fleet"] = fleet.snapshot()
    return found


def _of_type(kind: str) -> list[dict[str, Any]]:
    return [dict(record) for record in material()["inputs"] if record.get("type") == kind][:8]


def _kwargs(cls: type, value: Any) -> dict[str, Any]:
    """Only the keyword arguments ``cls`` takes (the values are the fuzzed part, not the names)."""
    names = {field.name for field in attrs.fields(cls)}
    return {key: item for key, item in value.items() if key in names} if isinstance(value, dict) else {}


def _messages() -> list[Target]:
    made = []
    for cls in MESSAGE_TYPES:
        seeds = (cls().to_dict(),)
        made.append(Target(f"{cls.__name__}.from_dict", seeds, cls.from_dict))
        made.append(
            Target(
                f"{cls.__name__}.from_json", tuple(mutate.dumps(s) for s in seeds), cls.from_json, text=True
            )
        )
        made.append(_keyword_target(f"{cls.__name__}(**fields)", cls, seeds))
    return made


def _keyword_target(name: str, cls: type, seeds: tuple[Any, ...]) -> Target:
    """``cls(**arguments)``: the arguments' values are mutated, never their names."""
    return Target(name, seeds, lambda value: cls(**_kwargs(cls, value)), kwargs=True)


def _inputs() -> list[Target]:
    made = []
    for kind, cls in ins.INPUT_TYPES.items():
        seeds = tuple({k: v for k, v in record.items() if k != "type"} for record in _of_type(kind)) or (
            {"now": 0},
        )
        made.append(_keyword_target(f"inputs.{cls.__name__}(**fields)", cls, seeds))
    return made


#: ServerConfig's plain fields (its categories are validators, given by the target itself).
_CONFIG_FIELDS = tuple(
    field.name for field in attrs.fields(machine.ServerConfig) if field.name != "categories"
)


def _server_config(value: Any) -> object:
    kwargs = {key: item for key, item in value.items() if key in _CONFIG_FIELDS}
    kwargs["categories"] = {"go_to_place": machine.any_description}
    return _run(machine.ServerConfig(**kwargs))


def _run(config: machine.ServerConfig) -> machine.State:
    """An accepted configuration must run: a robot's whole life steps without raising."""
    state = machine.State.new("f", "r")
    for record in material()["inputs"][:: max(1, len(material()["inputs"]) // 60)]:
        with contextlib.suppress(ValueError):
            state = machine.step(state, input_from_json(record, "$"), config).state
    return state


def _run_config(value: Any) -> object:
    return _run(config_from_json(value, "$"))


def _restore_and_run(value: Any) -> object:
    """A snapshot that restores must run: every kind of input steps from it without raising."""
    state = snapshot.restore(value)
    config = machine.ServerConfig()
    for record in material()["inputs"][:: max(1, len(material()["inputs"]) // 40)]:
        with contextlib.suppress(ValueError):
            machine.step(state, input_from_json(record, "$"), config)
    return snapshot.loads(snapshot.dumps(state))  # its own snapshot loads again


def _driver_session(value: Any) -> object:
    requests = value if isinstance(value, list) else [value]
    lines = "".join(
        (request if isinstance(request, str) else mutate.dumps(request)) + "\n" for request in requests
    )
    out = io.StringIO()
    driver.serve(io.StringIO(lines), out)
    return out.getvalue()


def _driver_seeds() -> tuple[Any, ...]:
    requests = material()["requests"]
    sessions = []
    for index, request in enumerate(requests):
        if request["op"] == "reset":
            sessions.append([{"op": "hello"}, request, *requests[index + 1 : index + 6]])
    return tuple(sessions[::5])


def _store_file(value: Any) -> object:
    """Open a store whose rows were written by someone else: refused cleanly, or loaded and usable."""
    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-")
    path = os.path.join(folder, "state.db")
    try:
        db = sqlite3.connect(path)
        db.executescript(
            "CREATE TABLE meta (key TEXT PRIMARY KEY, value TEXT);"
            "CREATE TABLE robots (fleet TEXT, robot TEXT, snapshot TEXT, PRIMARY KEY (fleet, robot));"
        )
        meta = value.get("meta") if isinstance(value, dict) else None
        rows = value.get("robots") if isinstance(value, dict) else None
        for key, item in meta.items() if isinstance(meta, dict) else ():
            db.execute("INSERT INTO meta VALUES (?, ?)", (_sql_text(str(key)), _sql_text(item)))
        for row in rows if isinstance(rows, list) else ():
            if isinstance(row, list) and len(row) == 3:
                db.execute(
                    "INSERT OR REPLACE INTO robots VALUES (?, ?, ?)", tuple(_sql_text(cell) for cell in row)
                )
        db.commit()
        db.close()
        store = StateStore(path)
        try:
            states = store.load()
            for state in states.values():
                store.save(state)
        finally:
            store.close()
        return states
    finally:
        for name in os.listdir(folder):
            os.unlink(os.path.join(folder, name))
        os.rmdir(folder)


def _sql_text(cell: Any) -> Any:
    """A value sqlite3 can store (it cannot encode lone surrogates): the store's reader gets the rest."""
    if isinstance(cell, (dict, list)):
        cell = mutate.dumps(cell)
    if isinstance(cell, str):
        return cell.encode("utf-8", "surrogatepass").decode("utf-8", "replace")
    return cell if not isinstance(cell, int) or abs(cell) < 2**63 else str(cell)


def _store_bytes(value: Any) -> object:
    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-")
    path = os.path.join(folder, "state.db")
    try:
        Path(path).write_bytes(
            value if isinstance(value, bytes) else str(value).encode("utf-8", "surrogatepass")
        )
        store = StateStore(path)
        try:
            return store.load()
        finally:
            store.close()
    finally:
        for name in os.listdir(folder):
            os.unlink(os.path.join(folder, name))
        os.rmdir(folder)


@functools.cache
def _store_seed() -> bytes:
    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-")
    path = os.path.join(folder, "state.db")
    store = StateStore(path)
    store.save(snapshot.restore(material()["snapshots"][1]))
    store.close()
    data = Path(path).read_bytes()
    for name in os.listdir(folder):
        os.unlink(os.path.join(folder, name))
    os.rmdir(folder)
    return data


def _cli(argv: list[str], stdin: str = "") -> object:
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = cli.main(argv)
        except SystemExit as exc:  # argparse's usage errors
            code = exc.code if isinstance(exc.code, int) else 2
    if code not in (0, 1, 2) or "Traceback" in out.getvalue() + err.getvalue():
        raise AssertionError(f"exit {code}: {err.getvalue()[-300:]}")
    return code


def _cli_with_file(command: str, value: Any, *extra: str) -> object:
    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-")
    path = os.path.join(folder, "input")
    try:
        data = value if isinstance(value, bytes) else str(value).encode("utf-8", "surrogatepass")
        Path(path).write_bytes(data)
        return _cli([command, *extra, path])
    finally:
        os.unlink(path)
        os.rmdir(folder)


def _trace_seeds() -> tuple[str, ...]:
    return tuple(
        (ROOT / "docs" / "examples" / name).read_text(encoding="utf-8")
        for name in ("clean-trace.jsonl", "rmf_ros2-trace.jsonl")
    )


def _vector_file_seeds() -> tuple[str, ...]:
    folder = ROOT / "src" / "dynevent" / "conformance" / "vectors"
    seeds = []
    for path in sorted(folder.glob("[0-9]*.json"))[::3]:
        data = mutate.json.loads(path.read_text(encoding="utf-8"))
        seeds.append(mutate.dumps({"vectors": data["vectors"][:1]}))
    return tuple(seeds)


def _text(value: str | bytes) -> str:
    """The str a str-only entry point is given: bytes that are not UTF-8 become U+FFFD."""
    return value.decode("utf-8", "replace") if isinstance(value, bytes) else value


def _explain(value: Any) -> object:
    status, goal = ([*value, None, None])[:2] if isinstance(value, list) else (value, None)
    return _cli(
        [
            "explain",
            "--status",
            status if isinstance(status, str) else mutate.dumps(status),
            "--goal",
            goal if isinstance(goal, str) else mutate.dumps(goal),
        ]
    )


def _client_request(value: Any) -> object:
    state = cl.ClientState.new("0123456789abcdef", categories=["go_to_place"])
    state = cl.step(state, cl.StatusReceived(message=_status(value.get("status")))).state
    return cl.request_next(
        state,
        value.get("category"),
        value.get("description"),
        stubborn_period=value.get("stubborn_period", 0.0),
        timeout=value.get("timeout"),
        now=value.get("now", 0),
    )


def _status(data: Any) -> Any:
    from dynevent.wire.messages import DynamicEventStatus

    return DynamicEventStatus.from_dict(data)


# --------------------------------------------------------------------------- the newer edges (#43)

#: The robot the description targets judge with: a map of 300 places, two actions.
_MAP = [f"place_{number:03d}" for number in range(300)]


@functools.cache
def _robot() -> Any:
    from dynevent import descriptions

    return descriptions.Robot(places=[*_MAP, None], actions=["wave", "charge"])


def _description_seeds() -> tuple[Any, ...]:
    return (
        ["go_to_place", {"one_of": ["place_001", {"waypoint": 3, "orientation": 1.5}, "plce_002"]}],
        ["go_to_place", {"place": "place_007", "followed_by": [1, 2, "place_009"]}],
        [
            "perform_action",
            {"category": "wave", "description": {"arm": [1, 2]}, "expected_finish_location": 4},
        ],
        [
            "sequence",
            [
                {"category": "go_to_place", "description": "place_001"},
                {"category": "clean", "description": {"zone": "z"}},
            ],
        ],
        ["pickup", {"place": "place_010", "payload": [{"sku": "box", "quantity": 2}]}],
        ["dropoff", {"place": 5, "handler": "h", "payload": {"sku": "box", "quantity": 1}}],
    )


def _robot_check(value: Any) -> object:
    """A description of any shape, judged by a robot with a map: a tuple of lines, within the listing
    bound (R4.19), never an error."""
    category, description = ([*value, None, None])[:2] if isinstance(value, list) else ("go_to_place", value)
    lines = _robot().check(category if isinstance(category, str) else "go_to_place", description)
    if not isinstance(lines, tuple) or len(lines) > machine.MAX_LISTED_ERRORS + 1:
        raise AssertionError(f"{len(lines)} lines")
    return lines


def _robot_config(value: Any) -> object:
    from dynevent import descriptions

    robot = descriptions.Robot(**value)
    return robot.check("go_to_place", {"one_of": ["place_001", 2]})


def _serve_config(value: Any) -> object:
    from dynevent.sim.config import load_config

    return _with_file(value, load_config)


def _with_file(value: Any, call: Callable[[str], object]) -> object:
    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-")
    path = os.path.join(folder, "input")
    try:
        data = value if isinstance(value, bytes) else str(value).encode("utf-8", "surrogatepass")
        Path(path).write_bytes(data)
        return call(path)
    finally:
        os.unlink(path)
        os.rmdir(folder)


def _send_request(value: Any) -> object:
    import argparse

    from dynevent.tools.send import goal_request

    def ask(path: str) -> object:
        flags = {"place": None, "cancel": False, "end": False, "category": "go_to_place"}
        return (
            goal_request(argparse.Namespace(**flags, file=path, description=None)),
            goal_request(argparse.Namespace(**flags, file=None, description="@" + path)),
        )

    return _with_file(value, ask)


#: A recording of the deployed server: its metadata.yaml (text) and its MCAP storage (bytes).
_BAG = ROOT / "tests" / "data" / "rmf_ros2" / "demos"


def _bag_metadata(value: Any) -> object:
    """A bag whose metadata.yaml is mutated (YAML structure, aliases, nesting), its storage whole."""
    return _bag(_text(value).encode("utf-8", "surrogatepass"), (_BAG / "demos.mcap").read_bytes())


def _bag_storage(value: Any) -> object:
    """A bag whose MCAP storage is mutated bytes, its metadata whole."""
    data = value if isinstance(value, bytes) else str(value).encode("utf-8", "surrogatepass")
    return _bag((_BAG / "metadata.yaml").read_bytes(), data)


def _bag(metadata: bytes, storage: bytes, stored_as: str = "demos.mcap") -> object:
    from dynevent.bags.reader import check_bag

    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-bag-")
    try:
        Path(folder, "metadata.yaml").write_bytes(metadata)
        Path(folder, stored_as).write_bytes(storage)
        return check_bag(folder)
    finally:
        for name in os.listdir(folder):
            os.unlink(os.path.join(folder, name))
        os.rmdir(folder)


#: A robot's status topic and type, as the compressed bags' seeds record them.
_STATUS = ("/rmf/dynamic_event/status/tinyRobot/r1", "rmf_task_msgs/msg/DynamicEventStatus")


def _statuses(count: int) -> list[bytes]:
    """``count`` status messages of a robot, serialized as a bag holds them."""
    from dynevent.bags.reader import typestore

    store = typestore()
    kinds = store.types
    return [
        store.serialize_cdr(
            kinds[_STATUS[1]](
                dynamic_event_seq=1, dynamic_state=1, status="standby", id=number,
                time=kinds["builtin_interfaces/msg/Time"](sec=number, nanosec=0),
            ),
            _STATUS[1],
        )
        for number in range(count)
    ]  # fmt: skip


@functools.cache
def _compressed_bags() -> dict[str, tuple[bytes, bytes]]:
    """Bags compressed in each of rosbag2's ways by rosbags' writer, as (metadata.yaml, storage file):
    the storage file zstd (``file``), each message zstd (``message``), MCAP's chunks zstd (``chunks``)."""
    from rosbags.rosbag2 import CompressionFormat, CompressionMode, StoragePlugin, Writer

    from dynevent.bags.reader import message_definition

    made = {}
    for name, mode in (
        ("file", CompressionMode.FILE),
        ("message", CompressionMode.MESSAGE),
        ("chunks", CompressionMode.STORAGE),
    ):
        with tempfile.TemporaryDirectory(prefix="dynevent-fuzz-seed-") as folder:
            path = Path(folder, "bag")
            writer = Writer(path, version=9, storage_plugin=StoragePlugin.MCAP)
            writer.set_compression(mode, CompressionFormat.ZSTD)
            with writer:
                topic = writer.add_connection(
                    *_STATUS, msgdef=message_definition(_STATUS[1]), rihs01="RIHS01_" + "0" * 64
                )
                for number, data in enumerate(_statuses(4)):
                    writer.write(topic, (1_700_000_000 + number) * 10**9, data)
            (storage,) = (file for file in path.iterdir() if file.name != "metadata.yaml")
            made[name] = ((path / "metadata.yaml").read_bytes(), storage.read_bytes())
    return made


def _lz4_chunks() -> bytes:
    """An MCAP file (profile ros2) of statuses, its chunks lz4 (Foxglove's writer: rosbags writes zstd)."""
    from mcap.writer import CompressionType, Writer

    stream = io.BytesIO()
    writer = Writer(stream, compression=CompressionType.LZ4)
    writer.start(profile="ros2", library="dynevent fuzz")
    schema = writer.register_schema(_STATUS[1], "ros2msg", b"")
    channel = writer.register_channel(_STATUS[0], "cdr", schema)
    for number, data in enumerate(_statuses(4)):
        time = (1_700_000_000 + number) * 10**9
        writer.add_message(channel, log_time=time, data=data, publish_time=time)
    writer.finish()
    return stream.getvalue()


def _compressed_storage(mode: str) -> Callable[[Any], object]:
    """A bag compressed in ``mode`` whose storage file is the mutated bytes, its metadata whole."""

    def call(value: Any) -> object:
        data = value if isinstance(value, bytes) else str(value).encode("utf-8", "surrogatepass")
        metadata = _compressed_bags()[mode][0]
        name = "bag.mcap.zstd" if mode == "file" else "bag.mcap"
        return _bag(metadata, data, name)

    return call


def _mcap_file(value: Any) -> object:
    """An MCAP file alone, its chunks compressed: the mutated bytes."""
    from dynevent.bags.reader import check_bag

    data = value if isinstance(value, bytes) else str(value).encode("utf-8", "surrogatepass")
    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-bag-")
    try:
        Path(folder, "bag.mcap").write_bytes(data)
        return check_bag(os.path.join(folder, "bag.mcap"))
    finally:
        for name in os.listdir(folder):
            os.unlink(os.path.join(folder, name))
        os.rmdir(folder)


def _output_path(value: Any) -> object:
    """An output path of any text, under a folder of the fuzzer's own (never above it): tried as a
    file and as a directory, refused with a FileError or written, and nothing left behind."""
    from dynevent import files

    folder = tempfile.mkdtemp(prefix="dynevent-fuzz-out-")
    try:
        Path(folder, "there").write_text("kept", encoding="utf-8")
        os.mkdir(os.path.join(folder, "folder"))
        # a command line's argument: bytes that are not UTF-8 as the interpreter reads them (surrogates)
        text = os.fsdecode(value) if isinstance(value, bytes) else value
        text = text if isinstance(text, str) else mutate.dumps(value)
        path = os.path.join(folder, text.replace("..", "__").lstrip("/"))
        for directory in (False, True):
            with contextlib.suppress(FileError):
                files.check_writable(path, "--out", directory=directory)
        left = sorted(os.listdir(folder))
        if left != ["folder", "there"] or os.listdir(os.path.join(folder, "folder")):
            raise AssertionError(f"the check left {left} behind")
        if Path(folder, "there").read_text(encoding="utf-8") != "kept":
            raise AssertionError("the check changed a file that was there")
        return path
    finally:
        shutil.rmtree(folder)


def _longer(value: Any) -> Any:
    """``value`` with each integer of 300 digits or more made longer than Python writes (4,300)."""
    if isinstance(value, bool) or not isinstance(value, (int, list, dict)):
        return value
    if isinstance(value, int):
        return value * 10**4_700 if abs(value) >= 10**300 else value
    if isinstance(value, list):
        return [_longer(item) for item in value]
    return {key: _longer(item) for key, item in value.items()}


def _descriptions_api(value: Any) -> object:
    """The descriptions API given a category and a description of any type and size: a value, or
    dynevent's own error (an unknown category is :class:`~dynevent.errors.UnknownCategory`)."""
    from dynevent import descriptions

    category, description = ([*value, None, None])[:2] if isinstance(value, list) else (value, value)
    sequence = descriptions.shape_validators()["sequence"]
    calls: tuple[Callable[[Any, Any], object], ...] = (
        descriptions.conforms,
        descriptions.shape_errors,
        descriptions.read,
        descriptions.shapes.form,
        lambda category, _: descriptions.schema(category),
        _robot().check,
        sequence,
    )
    found: list[object] = []
    for given in (description, _longer(description)):
        for call in calls:
            with contextlib.suppress(DyneventError):
                found.append(call(category, given))
    return found


def _runner_answer(value: Any) -> object:
    """A driver that greets properly, then answers every request with the mutated line: the runner
    judges it (a failure, a broken driver) or refuses it, within bounds, and ends the driver."""
    line = value if isinstance(value, bytes) else mutate.dumps(value).encode("utf-8", "surrogatepass")

    def run(path: str) -> object:
        hello = '{"ok": true, "implementation": "fuzz", "protocol": 1}'
        script = f"read x; echo '{hello}'; while read x; do cat {path}; echo; done"
        implementation = vectors.ExternalImplementation(f"sh -c {shlex.quote(script)}", timeout=2)
        try:
            return list(vectors.run_vectors(vectors.load_vectors()[:1], implementation))
        finally:
            implementation.close()

    return _with_file(line.replace(b"\n", b" "), run)


def _reports(value: Any) -> object:
    """Every report writer, given text of any kind where a driver's or server's text goes: the XML
    parses and every report encodes as UTF-8."""
    from xml.etree import ElementTree

    from dynevent.conformance.probe import cases as probe_cases
    from dynevent.conformance.vectors.runner import Failure, Outcome

    text = _text(value) if isinstance(value, (str, bytes)) else mutate.dumps(value)
    vector = vectors.load_vectors()[0]
    failed = Outcome(vector, Failure(1, {"x": text}, [text], [], text))
    written = [vectors.junit_xml([failed], text)]
    case = probe_cases.CASES[0]
    verdict = probe_cases.Verdict.FAIL
    finding = probe_cases.CaseFinding(case, verdict, expected=text, seen=text, messages=(text,))
    written.append(probe_cases.junit_xml([finding], text))
    for xml in written:
        ElementTree.fromstring(xml.encode("utf-8"))
    for page in (probe_cases.report([finding], text), probe_cases.report([finding], text, html_form=True)):
        page.encode("utf-8", "backslashreplace")
    return written


def targets() -> list[Target]:
    """Every entry point the fuzzer drives."""
    mat = material()
    by_type = {record["type"]: record for record in mat["inputs"]}
    rules = [rule for config in mat["configs"] for rule in (config.get("categories") or {}).values()][:10]
    status = {
        "dynamic_event_seq": 3,
        "dynamic_state": 2,
        "status": "underway",
        "id": 8,
        "time": {"sec": 1, "nanosec": 0},
    }
    goal = {
        "dynamic_event_seq": 3,
        "event_type": 2,
        "category": "",
        "description": "",
        "id": 8,
        "stubborn_period": 0.0,
    }
    description = {
        "category": "patrol",
        "detail": "rounds",
        "estimate": {"category": "go_to_place", "description": {"place": "lobby"}},
        "required": [{"category": "perform_action", "description": {"action": "wait"}}],
        "parameters": {"x": [1, 2.5, None, True]},
    }
    made = [
        *_messages(),
        *_inputs(),
        Target("records.input_from_json", tuple(mat["inputs"][::9]), lambda v: input_from_json(v, "$")),
        Target(
            "records.output_from_json",
            tuple(o for o in mat["outputs"][::9] if "*" not in mutate.dumps(o)),
            lambda v: output_from_json(v, "$"),
        ),
        Target("records.config_from_json, then run", tuple(mat["configs"][::5]), _run_config),
        Target("records.rule_validator", tuple(rules) or ([{"accept": "string"}],), rule_validator),
        Target(
            "machine.ServerConfig(**fields), then run",
            (
                {
                    "id_policy": "goal",
                    "compatibility": "standard",
                    "stubborn_minimum": 2.0,
                    "stubborn_refresh": 1.0,
                    "stubborn_move_threshold": 0.1,
                    "max_description_length": 1000,
                },
            ),
            _server_config,
            kwargs=True,
        ),
        Target("snapshot.restore, then run", tuple(mat["snapshots"][:40]), _restore_and_run),
        Target(
            "snapshot.loads", tuple(mutate.dumps(s) for s in mat["snapshots"][:20]), snapshot.loads, text=True
        ),
        Target("Fleet.restore", (mat["fleet"],), Fleet.restore),
        Target("Fleet.loads", (mutate.dumps(mat["fleet"]),), Fleet.loads, text=True),
        Target("EventDescription.from_dict", (description,), EventDescription.from_dict),
        Target(
            "EventDescription.from_json", (mutate.dumps(description),), EventDescription.from_json, text=True
        ),
        Target("EventSpec.from_dict", (description["estimate"],), EventSpec.from_dict),
        Target(
            "names.parse_name",
            (
                "rmf/dynamic_event/command/tinyRobot/tinyRobot1",
                "rmf/dynamic_event/status/f/r",
                "rmf/dynamic_event/begin",
            ),
            lambda v: parse_name(_text(v)),
            text=True,
        ),
        Target("names.validate_token", ("tinyRobot1",), lambda v: validate_token("robot", v)),
        Target(
            "names.action_name",
            (["tinyRobot", "tinyRobot1"],),
            lambda v: action_name(*([*v, "", ""])[:2]) if isinstance(v, list) else action_name(v, v),
        ),
        Target("check.check_trace", _trace_seeds(), lambda v: check_trace(_text(v)), text=True),
        Target(
            "vectors.parse_vector_file (schema)",
            _vector_file_seeds(),
            lambda v: vectors.parse_vector_file("fuzz.json", v, schema=True),
            text=True,
        ),
        Target("driver protocol session", _driver_seeds(), _driver_session),
        Target(
            "StateStore rows",
            (
                {
                    "meta": {"format": "dynevent-store", "version": "1"},
                    "robots": [["tinyRobot", "tinyRobot1", mat["snapshots"][1]]],
                },
            ),
            _store_file,
        ),
        Target("StateStore file bytes", (_store_seed(),), _store_bytes),
        Target(
            "client.request_next",
            (
                {
                    "status": status,
                    "category": "go_to_place",
                    "description": '"a"',
                    "stubborn_period": 0.5,
                    "timeout": 10**9,
                    "now": 5,
                },
            ),
            _client_request,
            kwargs=True,
        ),
        Target(
            "cli: dynevent check FILE",
            _trace_seeds(),
            lambda v: _cli_with_file("check", v),
            text=True,
            cli=True,
        ),
        Target("cli: dynevent explain", ([status, goal],), _explain, cli=True),
        Target(
            "cli: dynevent vectors FILE",
            _vector_file_seeds()[:2],
            lambda v: _cli_with_file("vectors", v),
            text=True,
            cli=True,
        ),
        Target(
            "cli: dynevent demo --seed",
            (["demo", "--seed", "3"], ["demo", "--json", "--seed", "1"]),
            lambda v: _cli([str(x) for x in v] if isinstance(v, list) else [str(v)]),
            cli=True,
        ),
        Target(
            "cli: dynevent diagram --format",
            (["diagram", "--format", "dot"],),
            lambda v: _cli([str(x) for x in v] if isinstance(v, list) else [str(v)]),
            cli=True,
        ),
        Target("descriptions.Robot.check", _description_seeds(), _robot_check),
        Target(
            "descriptions.Robot(**fields)",
            ({"places": ["a", None, "b"], "actions": ["wave"], "categories": ["go_to_place", "sequence"]},),
            _robot_config,
            kwargs=True,
        ),
        Target(
            "sim.load_config FILE",
            (
                mutate.dumps(
                    {
                        "fleet": "f",
                        "robots": ["r1"],
                        "rebegin": 1,
                        "places": ["a", None],
                        "categories": {"go_to_place": {"duration": 1, "fail_on": ["x"]}},
                    }
                ),
            ),
            _serve_config,
            text=True,
        ),
        Target(
            "send_request --file and --description @FILE",
            (mutate.dumps({"category": "go_to_place", "description": {"one_of": ["a"]}}),),
            _send_request,
            text=True,
        ),
        Target(
            "bags: metadata.yaml",
            ((_BAG / "metadata.yaml").read_text(encoding="utf-8"),),
            _bag_metadata,
            text=True,
        ),
        Target("bags: MCAP storage", ((_BAG / "demos.mcap").read_bytes()[:4_096],), _bag_storage, text=True),
        Target(
            "runner: a driver's answers",
            ({"ok": True, "outputs": [{"type": "publish_status", "message": {"id": 1}}], "view": None},),
            _runner_answer,
        ),
        Target("report writers", ("a name\u0007 with \udc80", {"rule": "R4.\x00"}), _reports),
        Target(
            "bags: compressed storage (compression_mode file)",
            (_compressed_bags()["file"][1],),
            _compressed_storage("file"),
        ),
        Target(
            "bags: compressed messages (compression_mode message)",
            (_compressed_bags()["message"][1],),
            _compressed_storage("message"),
        ),
        Target(
            "bags: an MCAP file's compressed chunks (zstd, lz4)",
            (_compressed_bags()["chunks"][1], _lz4_chunks()),
            _mcap_file,
        ),
        Target(
            "files.check_writable (an output path)",
            ("report.md", "/", "folder", "there", "missing/report.md", "x" * 300, "a\x00b", "./" * 3_000),
            _output_path,
            text=True,
        ),
        Target(
            "descriptions API: a category and a description of any type",
            (
                ["go_to_place", {"one_of": ["place_001", 3]}],
                ["sequence", [{"category": "clean", "description": 1}]],
                [{}, 0],
                [10**400, "place_001"],
                ["pickup", {"place": 10**400, "payload": {"sku": "a", "quantity": -(10**400)}}],
            ),
            _descriptions_api,
        ),
    ]
    assert by_type  # every input type has seeds from the vectors
    return made
