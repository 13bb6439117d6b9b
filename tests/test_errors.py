"""Every error dynevent raises is one class of one module, ``dynevent.errors``, under DyneventError."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import dynevent
from dynevent import errors

OLD_HOMES = {
    "dynevent.check": ["TraceError"],
    "dynevent.records": ["InvalidRecord"],
    "dynevent.store": ["InvalidStore"],
    "dynevent.vectors": ["InvalidVector", "ImplementationError"],
    "dynevent.fleet": ["UnknownRobot", "DuplicateRobot"],
}


def _modules() -> list[str]:
    names = []
    for info in pkgutil.walk_packages(dynevent.__path__, "dynevent."):
        if info.name.startswith(("dynevent.ros", "dynevent.testing")) or info.name == "dynevent.__main__":
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
