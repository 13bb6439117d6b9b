"""Every error dynevent raises is one class of one module, ``dynevent.errors``, under DyneventError."""

from __future__ import annotations

import importlib
import inspect
import pkgutil

import pytest

import dynevent
from dynevent import errors

OLD_HOMES = {
    "dynevent.tools.check": ["TraceError"],
    "dynevent.conformance.records": ["InvalidRecord"],
    "dynevent.server.store": ["InvalidStore"],
    "dynevent.conformance.vectors": ["InvalidVector", "ImplementationError"],
    "dynevent.server.fleet": ["UnknownRobot", "DuplicateRobot"],
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
