"""Every error dynevent raises is one class of one module, ``dynevent.errors``, under DyneventError."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import dynevent
from dynevent import errors

OLD_HOMES = {
    "dynevent.conformance.judge": ["TraceError"],
    "dynevent.conformance.records": ["InvalidRecord"],
    "dynevent.server.store": ["InvalidStore"],
    "dynevent.conformance.vectors": ["InvalidVector", "ImplementationError"],
    "dynevent.server.fleet": ["UnknownRobot", "DuplicateRobot"],
}


def _modules() -> list[str]:
    names = []
    for info in pkgutil.walk_packages(dynevent.__path__, "dynevent."):
        needs = ("dynevent.ros", "dynevent.tools.live", "dynevent.testing")
        if info.name.startswith(needs) or info.name == "dynevent.__main__":
            continue  # ROS 2 and hypothesis may be absent; their errors are checked below by name
        names.append(info.name)
    return names


def test_every_public_error_class_is_defined_in_dynevent_errors() -> None:
    for name in _modules():
        module = importlib.import_module(name)
        for attribute, value in vars(module).items():
            if (
                inspect.isclass(value)
                and issubclass(value, errors.DyneventError)
                and not attribute.startswith("_")
            ):
                assert value.__module__ == "dynevent.errors", (
                    f"{name}.{attribute} is defined in {value.__module__}"
                )


def test_every_error_in_errors_is_listed_and_is_a_value_error() -> None:
    defined = {
        name
        for name, value in vars(errors).items()
        if inspect.isclass(value) and issubclass(value, Exception)
    }
    assert defined == set(errors.__all__)
    assert all(issubclass(getattr(errors, name), (errors.DyneventError, ValueError)) for name in defined)
    assert {"GoalWaitTimeout", "ServeError", "SendError"} <= defined  # the ROS binding's, importable anywhere


@pytest.mark.parametrize(("module", "names"), sorted(OLD_HOMES.items()))
def test_the_old_import_paths_still_work(module: str, names: list[str]) -> None:
    for name in names:
        assert getattr(importlib.import_module(module), name) is getattr(errors, name)


def test_the_public_face_names_each_public_name_once_and_imports_it_on_first_use() -> None:
    import subprocess
    import sys

    assert sorted(dynevent.__all__, key=str) == sorted(
        {*dynevent._HOMES, *dynevent._MODULES, "DOCS", "HOME", "__version__"}, key=str
    )
    for name in dynevent.__all__:
        value = getattr(dynevent, name)
        if name in dynevent._HOMES:
            home = importlib.import_module(f"dynevent.{dynevent._HOMES[name]}")
            assert value is getattr(home, name)
            assert name in home.__all__, f"{name} is not public in dynevent.{dynevent._HOMES[name]}"
    assert set(dir(dynevent)) >= set(dynevent.__all__)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        dynevent.nothing  # noqa: B018
    probe = (
        "import sys, dynevent; print(sorted(m for m in sys.modules if m.startswith(('dynevent.', 'attr'))))"
    )
    done = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=60, check=True
    )
    assert done.stdout.strip() == "[]"  # `import dynevent` imports none of it


# --------------------------------------------------------------------------- whose fault


NEITHER = {"DyneventError", "LocalError", "RemoteError", "InvalidMessage", "GoalWaitTimeout"}


def test_every_error_says_whose_fault_it_is() -> None:
    """A LocalError is this program's misuse, a RemoteError bad data from outside; never both."""
    for name in errors.__all__:
        cls = getattr(errors, name)
        local, remote = issubclass(cls, errors.LocalError), issubclass(cls, errors.RemoteError)
        assert not (local and remote), name
        assert local or remote or name in NEITHER, f"{name} says neither whose fault it is"


def test_a_message_built_here_is_local_and_one_received_is_remote() -> None:
    from dynevent.wire.messages import Feedback, Goal

    with pytest.raises(errors.InvalidValue) as built:
        Goal(dynamic_event_seq=-1)
    assert isinstance(built.value, errors.LocalError) and not isinstance(built.value, errors.RemoteError)
    assert built.value.field == "dynamic_event_seq"
    for parse in (
        lambda: Goal.from_json('{"dynamic_event_seq": -1}'),  # the constructor's check, from outside
        lambda: Goal.from_json('{"dynamic_event_seq": 1.5}'),
        lambda: Goal.from_json("[1]"),
        lambda: Goal.from_json("{not json"),
        lambda: Feedback.from_dict({"logs": [{"seq": -2}]}),
    ):
        with pytest.raises(errors.MalformedMessage) as received:
            parse()
        assert isinstance(received.value, errors.RemoteError) and isinstance(
            received.value, errors.InvalidMessage
        )
        assert not isinstance(received.value, errors.LocalError)
    with pytest.raises(errors.MalformedMessage) as nested:
        Feedback.from_dict({"logs": [{"seq": -2}]})
    assert nested.value.field == "logs[0].seq"


def test_a_value_of_the_wrong_type_is_a_type_error_naming_what_was_expected() -> None:
    from dynevent import client, inputs, machine
    from dynevent.wire.messages import Goal

    state, config = machine.State.new("tinyRobot", "r1"), machine.ServerConfig()
    cases = [
        (lambda: machine.step(state, Goal(), config), "a server input", "dynevent.wire.messages.Goal"),
        (lambda: machine.step(state, client.Tick(now=0), config), "a server input", "dynevent.client"),
        (lambda: machine.step(config, inputs.Tick(now=0), config), "State", "ServerConfig"),
        (lambda: machine.step(state, inputs.Tick(now=0), None), "ServerConfig", "NoneType"),
        (lambda: machine.accept(state, inputs.Tick(now=0), config), "a dynevent.wire.messages.Goal", "Tick"),
        (lambda: client.step(client.ClientState.new("0" * 16), inputs.Tick(now=0)), "a client input", "Tick"),
        (lambda: client.step(state, client.Tick(now=0)), "ClientState", "State"),
    ]
    for call, expected, got in cases:
        with pytest.raises(TypeError) as refused:
            call()
        assert isinstance(refused.value, errors.WrongInput) and isinstance(refused.value, errors.LocalError)
        assert expected in str(refused.value) and got in str(refused.value), str(refused.value)


@pytest.mark.parametrize(
    "shape",
    [
        "000102030405060708090a0b0c0d0e0f",
        "000102030405060708090A0B0C0D0E0F",
        "00010203-0405-0607-0809-0a0b0c0d0e0f",
        bytes(range(16)),
        bytearray(range(16)),
        list(range(16)),
        tuple(range(16)),
        __import__("array").array("B", range(16)),
        __import__("uuid").UUID("00010203-0405-0607-0809-0a0b0c0d0e0f"),
    ],
    ids=["hex", "HEX", "hyphenated", "bytes", "bytearray", "ints", "tuple", "uint8-array", "uuid.UUID"],
)
def test_a_goal_uuid_is_taken_in_every_shape_the_wire_and_rclpy_use(shape: object) -> None:
    from dynevent import client, inputs

    assert inputs.GoalStarted(goal_uuid=shape, now=0).goal_uuid == "000102030405060708090a0b0c0d0e0f"
    assert client.GoalResponse(goal_uuid=shape, accepted=True).goal_uuid == "000102030405060708090a0b0c0d0e0f"


def test_a_goal_uuid_of_numpy_octets_is_taken() -> None:
    numpy = pytest.importorskip("numpy")
    octets = numpy.arange(16, dtype=numpy.uint8)  # goal_handle.goal_id.uuid in rclpy
    from dynevent import inputs

    assert inputs.GoalStarted(goal_uuid=octets, now=0).goal_uuid == "000102030405060708090a0b0c0d0e0f"


@pytest.mark.parametrize(
    ("shape", "problem"),
    [
        ([1] * 15, "16 octets, got 15"),
        ([256] + [0] * 15, "from 0 to 255, got 256"),
        ([True] * 16, "got True"),
        (["a"] * 16, "integers, got 'a'"),
        (bytes(15), "16 bytes, got 15"),
        ("zz", "expected 32 hexadecimal digits"),
        (3.5, "expected 32 hexadecimal digits, 16 bytes, 16 ints"),
    ],
)
def test_a_goal_uuid_of_no_shape_is_refused_naming_the_field(shape: object, problem: str) -> None:
    from dynevent import inputs

    with pytest.raises(errors.InvalidValue) as refused:
        inputs.GoalStarted(goal_uuid=shape, now=0)
    assert refused.value.field == "goal_uuid" and problem in str(refused.value), str(refused.value)
