"""The package layout is the architecture: imports go one way,
wire <- server <- client/descriptions <- conformance <- bags/sim <- ros <- tools: judging lives
below the command line, and nothing imports the command line but ``__main__``.

Every import in ``src/dynevent`` (at module level or inside a function) is read from the source, so a
lazy import that crosses a layer the wrong way fails here as a module-level one would.

tests/ mirrors the package folder for folder, with the test helpers in one place (tests/support).
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

import pytest

import dynevent

SRC = Path(__file__).resolve().parents[2] / "src" / "dynevent"

#: What each part of the package may import of dynevent (besides itself).  The top of the package
#: (``dynevent/__init__.py``) names everything lazily, and ``__main__`` is the command line.
ALLOWED: dict[str, frozenset[str]] = {
    "errors": frozenset(),
    # a command line's stop (SIGINT, SIGTERM): what the commands and the ROS sessions share
    "interrupts": frozenset(),
    "wire": frozenset({"errors"}),
    # the files a user names: read bounded, only regular ones, one error line for any fault
    "files": frozenset({"errors", "wire"}),
    "server": frozenset({"errors", "wire"}),
    "client": frozenset({"errors", "wire", "server"}),
    # the probe's in-process link runs the machine as serve's simulated fleet does
    "conformance": frozenset({"errors", "wire", "server", "descriptions", "files", "sim"}),
    "descriptions": frozenset({"errors", "wire", "server"}),
    # recordings are files: read and judged below ros (no rclpy)
    "bags": frozenset({"errors", "wire", "server", "conformance", "files"}),
    # the simulated fleet serve runs, its configuration checked before rclpy is needed
    "sim": frozenset({"errors", "wire", "server", "descriptions", "files"}),
    # the command line, and what only it runs: nothing below imports it
    "tools": frozenset(
        {
            "errors",
            "wire",
            "server",
            "client",
            "conformance",
            "descriptions",
            "files",
            "bags",
            "sim",
            "ros",
            "interrupts",
        }
    ),
    # judging is conformance (docs/design): ros reads the judges from below, never the command line
    "ros": frozenset(
        {"errors", "wire", "server", "client", "conformance", "descriptions", "files", "bags", "sim"}
    ),
    "testing": frozenset({"errors", "wire", "server", "conformance"}),
    # behaviour trees over a robot client (its type only: the tree's author opens the client)
    "bt": frozenset({"errors", "wire", "client", "ros"}),
}


def _part(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def _modules() -> list[tuple[str, Path]]:
    found = []
    for path in sorted(SRC.rglob("*.py")):
        parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        found.append((".".join(parts), path))
    return found


def _imports(module: str, path: Path) -> set[str]:
    """The dynevent modules ``module`` imports, as absolute names."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                target = ".".join([*base, node.module] if node.module else base)
            else:
                target = node.module or ""
            names.add(target)
            names.update(_resolved(target, alias.name) for alias in node.names)
    return {name for name in names if name.split(".")[0] == "dynevent"}


def _resolved(package: str, name: str) -> str:
    """``from package import name``: a module, or a name the top of dynevent re-exports lazily."""
    if package == "dynevent":
        if name in dynevent._MODULES:
            return f"dynevent.{dynevent._MODULES[name]}"
        if name in dynevent._HOMES:
            return f"dynevent.{dynevent._HOMES[name]}"
    return f"{package}.{name}"


LAYERED = [(module, path) for module, path in _modules() if _part(module) in ALLOWED]


def test_every_part_of_the_package_has_a_place_in_the_layers() -> None:
    parts = {_part(module) for module, _ in _modules()} - {"", "__main__"}
    assert parts == set(ALLOWED)


@pytest.mark.parametrize(("module", "path"), LAYERED, ids=[module for module, _ in LAYERED])
def test_imports_go_one_way(module: str, path: Path) -> None:
    own = _part(module)
    wrong = sorted(
        name
        for name in _imports(module, path)
        if _part(name) in ALLOWED and _part(name) not in ALLOWED[own] | {own}
    )
    assert not wrong, f"{module} imports {wrong}: {own} may import only {sorted(ALLOWED[own])}"


#: conformance's three folders and what each may import of the others: the vectors and the judge
#: neither each other, the probe both (it runs a driver through the vectors' runner and has its trace
#: judged).  The modules beside the folders (records, received, explain: "") import none of the three.
CONFORMANCE_PARTS: dict[str, frozenset[str]] = {
    "vectors": frozenset(),
    "judge": frozenset(),
    "probe": frozenset({"vectors", "judge"}),
    "": frozenset(),
}


def _conformance_part(module: str) -> str:
    """The folder of conformance a module (or a name in one) lies in; ``""`` beside the folders."""
    parts = module.split(".")
    return parts[2] if len(parts) > 2 and parts[2] in CONFORMANCE_PARTS else ""


CONFORMANCE = [(module, path) for module, path in _modules() if _part(module) == "conformance"]


#: Former paths the package keeps for 0.1.0's users, each importing only the module it now names.
FORMER_PATHS = {
    "dynevent.conformance.driver": "dynevent.conformance.vectors.driver",  # `python -m` of the driver
    "dynevent.tools.loopback": "dynevent.tools.demo.simulated_session",  # docs/client.md's session
}


def test_a_former_path_imports_only_the_module_it_now_names() -> None:
    paths = dict(_modules())
    for module, now in FORMER_PATHS.items():
        imported = _imports(module, paths[module])
        assert now in MODULES and now in imported, (module, now)
        assert all(name == now or name.startswith(f"{now}.") for name in imported), (module, sorted(imported))


@pytest.mark.parametrize(("module", "path"), CONFORMANCE, ids=[module for module, _ in CONFORMANCE])
def test_conformances_parts_import_one_way(module: str, path: Path) -> None:
    own = _conformance_part(module)
    former = {_conformance_part(FORMER_PATHS[module])} if module in FORMER_PATHS else set()
    allowed = CONFORMANCE_PARTS[own] | {own, ""} | former
    wrong = sorted(
        name
        for name in _imports(module, path)
        if _part(name) == "conformance" and _conformance_part(name) not in allowed
    )
    assert not wrong, f"{module} imports {wrong}: conformance/{own} may import only {sorted(allowed)}"


def test_conformance_has_its_three_folders_and_the_reader_tells_them_apart() -> None:
    folders = {path.parent.name for module, path in CONFORMANCE if path.name == "__init__.py"}
    assert folders == {"conformance", "vectors", "probe", "judge"}
    assert _conformance_part("dynevent.conformance.probe.runner.Link") == "probe"
    assert _conformance_part("dynevent.conformance.vectors") == "vectors"
    assert _conformance_part("dynevent.conformance.records") == ""


def test_the_reader_sees_a_wrong_way_import(tmp_path: Path) -> None:
    """The check is not blind: a lazy import of the tools inside the machine is seen."""
    path = tmp_path / "machine.py"
    path.write_text(
        "def f():\n    from dynevent.tools import explain\n    from ..client import step\n"
        "    from dynevent import RobotServer\n"
    )
    found = _imports("dynevent.server.machine", path)
    assert {"dynevent.tools.explain", "dynevent.client.step", "dynevent.server.holder"} <= found


def test_the_ros_client_and_server_import_neither_each_other() -> None:
    """What both need (the topics' QoS, introspection) is in dynevent.ros.qos: no import circle, even
    one made lazy inside a function."""
    package = Path(__file__).resolve().parents[2] / "src" / "dynevent" / "ros"
    for module, other in (("client", "server"), ("server", "client")):
        tree = ast.parse((package / f"{module}.py").read_text(encoding="utf-8"))
        imported = {
            node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.module
        }
        assert f"dynevent.ros.{other}" not in imported, f"ros/{module}.py imports ros/{other}.py"


#: The top-level packages a ROS 2 environment provides: only dynevent.ros imports them.
ROS_PACKAGES = frozenset(
    {"rclpy", "rmf_task_msgs", "action_msgs", "builtin_interfaces", "service_msgs", "unique_identifier_msgs",
     "rosidl_runtime_py", "rosbag2_py"}
)  # fmt: skip


def _top_imports(path: Path) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and not node.level and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_only_the_ros_binding_imports_ros() -> None:
    """The core, the judges and the bag reader run without ROS 2: a recording is files."""
    wrong = {
        module: sorted(_top_imports(path) & ROS_PACKAGES)
        for module, path in _modules()
        if _part(module) != "ros" and _top_imports(path) & ROS_PACKAGES
    }
    assert not wrong, wrong
    assert _top_imports(SRC / "ros" / "record.py") & ROS_PACKAGES  # the reader sees one


#: The longest a class and a function may be, in lines (docstrings included): past them a part no
#: longer reads as one thing.
LONGEST_CLASS, LONGEST_FUNCTION = 350, 80


def _too_long(tree: ast.Module) -> list[tuple[str, int]]:
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, (ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)):
            continue
        length = (node.end_lineno or node.lineno) - node.lineno + 1
        if isinstance(node, ast.ClassDef) and length > LONGEST_CLASS:
            found.append((f"class {node.name}", length))
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and length > LONGEST_FUNCTION:
            found.append((f"def {node.name}", length))
    return found


def test_no_class_or_function_is_too_long_to_read_as_one_thing() -> None:
    trees = {module: ast.parse(path.read_text(encoding="utf-8")) for module, path in _modules()}
    found = {module: too_long for module, tree in trees.items() if (too_long := _too_long(tree))}
    assert not found, found
    made = "class Long:\n" + "    x = 1\n" * LONGEST_CLASS + "def long():\n" + "    pass\n" * LONGEST_FUNCTION
    expected = [("class Long", LONGEST_CLASS + 1), ("def long", LONGEST_FUNCTION + 1)]
    assert _too_long(ast.parse(made)) == expected


def test_the_ros_entry_points_take_typed_options_not_the_command_lines_namespace() -> None:
    """serve, send, record and probe are called with typed options the command line builds: none of
    their bodies (dynevent.tools.live) nor of dynevent.ros reads argparse, and judging below the
    command line does not either."""
    below = ("ros", "conformance", "bags", "sim")
    readers = sorted(
        module
        for module, path in _modules()
        if (_part(module) in below or module.startswith("dynevent.tools.live"))
        and "argparse" in _top_imports(path)
    )
    assert readers == [], readers


def _private_imports(module: str, source: str) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(source)):
        if not (isinstance(node, ast.ImportFrom) and (node.module or "").startswith("dynevent")):
            continue
        for alias in node.names:
            name = alias.name
            if name.startswith("_") and not name.startswith("__") and f"{node.module}.{name}" not in MODULES:
                found.append(f"{module}: from {node.module} import {name}")
    return found


def test_no_module_imports_a_private_name_of_another() -> None:
    """What parts share is public in its module: a private name stays in its own (a private module,
    ``_json`` or ``_fields``, is the package's to import)."""
    found = [
        line for module, path in _modules() for line in _private_imports(module, path.read_text("utf-8"))
    ]
    assert not found, found
    seen = (
        "from dynevent.wire import _json\nfrom dynevent.conformance.judge.trace import _Hidden, __version__\n"
    )
    assert _private_imports("m", seen) == ["m: from dynevent.conformance.judge.trace import _Hidden"]


#: Every module of the package, by its dotted name.
MODULES = frozenset(module for module, _ in _modules())


#: Methods that change the container they are called on.
_MUTATORS = frozenset(
    {"add", "append", "appendleft", "clear", "discard", "extend", "insert", "pop", "popitem", "popleft"}
    | {"remove", "setdefault", "sort", "update"}
)


def _reach(node: ast.expr) -> tuple[str, int] | None:
    """The name an attribute chain starts from and how many attributes deep it goes (``self.a.b``:
    ``("self", 2)``); subscripts do not count; None when the chain starts elsewhere (a call)."""
    depth = 0
    while isinstance(node, (ast.Attribute, ast.Subscript)):
        depth += isinstance(node, ast.Attribute)
        node = node.value
    return (node.id, depth) if isinstance(node, ast.Name) else None


def _foreign_changes(source: str) -> list[str]:
    """Where code changes what another object keeps: it assigns or deletes an attribute of anything but
    ``self`` (``seen.answered = 1``, ``self.books.state = s``), or calls a mutating method of a
    container another object holds (``self.books.owed.pop()``).  A local's own items (``found[0] = x``)
    and ``self.x`` are the code's own."""
    found: list[tuple[int, str]] = []
    for node in ast.walk(ast.parse(source)):
        targets: list[ast.expr] = []
        if isinstance(node, ast.Assign):
            targets = list(node.targets)
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        elif isinstance(node, ast.Delete):
            targets = list(node.targets)
        for target in targets:
            for item in target.elts if isinstance(target, ast.Tuple) else [target]:
                reach = _reach(item)
                if reach is None or reach[1] == 0:
                    continue
                name, depth = reach
                if name != "self" or depth > 1:
                    found.append((node.lineno, f"line {node.lineno}: {ast.unparse(item)} changed"))
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr in _MUTATORS
            and (reach := _reach(node.func.value)) is not None
            and reach[1] >= (2 if reach[0] == "self" else 1)
        ):
            found.append((node.lineno, f"line {node.lineno}: {ast.unparse(node.func)}() called"))
    return [text for _, text in sorted(found)]


def test_the_observers_parts_change_what_the_rooms_keep_only_through_their_methods() -> None:
    """The observer's rooms (findings, the records ahead, the server as the machine has it, the goals
    seen) are each the only writer of what they keep; the parts that judge call their methods."""
    for name in ("observer", "abduction"):
        source = (SRC / "conformance" / "judge" / f"{name}.py").read_text("utf-8")
        assert _foreign_changes(source) == [], name
    shared = (
        "def f(self, seen, found):\n"
        "    self.own = 1\n    self.own[2] = 3\n    found[0] = 1\n    self._owed.pop(0)\n"
        "    seen.answered = 4\n    self.books.state = 5\n    del self.books.owed[0]\n"
        "    self.books.owed.pop(0)\n    seen.log.append(6)\n    a, seen.b = 7, 8\n"
    )
    assert _foreign_changes(shared) == [
        "line 6: seen.answered changed",
        "line 7: self.books.state changed",
        "line 8: self.books.owed[0] changed",
        "line 9: self.books.owed.pop() called",
        "line 10: seen.log.append() called",
        "line 11: seen.b changed",
    ]


#: The most lines the ROS binding may hold.  It is a binding: the nodes, the action server and client,
#: conversions, spinning, the participant, the probe's link over DDS, the recorder's subscriptions,
#: the simulated fleet's hosting and its task's parameters (interrupted, set from outside), and the
#: ways round rclpy's own faults (its executor's shutdown, its goal sending, a callback's exception
#: that would end the thread of every robot of its lane).  What the commands do
#: with it (their terminal lines, their reports) is dynevent.tools.live's, and what needs no rclpy is
#: below it (the adapter's side of a server, a goal run, the probe's cases; the client machine asks
#: again for the results a restart or a partition lost).
ROS_LINES = 2_650


def test_the_ros_package_is_a_binding_only() -> None:
    """Under :data:`ROS_LINES`, and it writes nothing to a terminal: every line a command shows goes
    through the command's own ``say`` and the one progress writer (dynevent.tools._progress)."""
    sources = {path.name: path.read_text(encoding="utf-8") for path in sorted((SRC / "ros").glob("*.py"))}
    lines = sum(len(text.splitlines()) for text in sources.values())
    assert lines < ROS_LINES, f"dynevent/ros holds {lines} lines"
    writers = {name for name, text in sources.items() for word in ("print(", "sys.stdout", "sys.stderr",
               "isatty") if word in text}  # fmt: skip
    assert writers == set(), writers
    live = SRC / "tools" / "live"
    bodies = {path.name: path.read_text(encoding="utf-8") for path in live.glob("*.py")}
    assert {name for name, text in bodies.items() if "\\033[" in text or "\\x1b[" in text} == set()


def test_the_reference_drivers_former_path_still_runs_it() -> None:
    """0.1.0 documented ``python -m dynevent.conformance.driver``: implementations' scripts run it."""
    import subprocess
    import sys

    hello = subprocess.run(
        [sys.executable, "-m", "dynevent.conformance.driver"], input='{"op":"hello"}\n', capture_output=True,
        text=True, timeout=60, check=False,
    )  # fmt: skip
    assert hello.returncode == 0, hello.stderr
    assert '"protocol":1' in hello.stdout, hello.stdout


#: The most lines the command line may hold: the grammar (every command's flags, with their help), and
#: the dispatch to the command's module.  What a command does is in that module, not here.
CLI_LINES = 600

#: What the command line imports of dynevent: the names its grammar shows (the version, the docs'
#: address, the modes and formats it offers as choices, the vectors' bound on --timeout) and the errors
#: it turns into one line.  A command's module is imported by name only when the command runs.
CLI_IMPORTS = frozenset(
    {"dynevent", "dynevent.DOCS", "dynevent.__version__", "dynevent.wire.vocab",
     "dynevent.wire.vocab.Compatibility", "dynevent.tools.diagram", "dynevent.tools.diagram.FORMATS",
     "dynevent.conformance.vectors", "dynevent.conformance.vectors.MAX_TIMEOUT", "dynevent.errors",
     "dynevent.errors.DyneventError", "dynevent.interrupts", "dynevent.interrupts.Interrupted"}
)  # fmt: skip

#: What dynevent/tools holds beside the commands' modules: the command line, the ROS bodies of the
#: commands on a live graph, the one progress writer, and 0.1.0's path of the simulated session.
TOOLS_BESIDE_COMMANDS = frozenset({"__init__", "cli", "live", "_progress", "loopback"})


def test_the_command_line_parses_and_dispatches_only() -> None:
    path = SRC / "tools" / "cli.py"
    lines = len(path.read_text(encoding="utf-8").splitlines())
    assert lines <= CLI_LINES, f"tools/cli.py holds {lines} lines"
    assert _imports("dynevent.tools.cli", path) == CLI_IMPORTS
    diagram = ast.parse((SRC / "tools" / "diagram.py").read_text(encoding="utf-8"))
    tops = [node for node in diagram.body if isinstance(node, (ast.Import, ast.ImportFrom))]
    assert {ast.unparse(node) for node in tops} == {"from __future__ import annotations", "import argparse"}


def test_every_command_is_one_module_whose_run_the_command_line_calls() -> None:
    import importlib
    import inspect

    from dynevent.tools import cli

    tools = SRC / "tools"
    entries = {path.stem for path in tools.glob("*.py")} | {
        path.name for path in tools.iterdir() if (path / "__init__.py").is_file()
    }
    assert entries - TOOLS_BESIDE_COMMANDS == set(cli.COMMANDS)
    for command in cli.COMMANDS:
        run = importlib.import_module(f"dynevent.tools.{command}").run
        assert list(inspect.signature(run).parameters) == ["args"], command
    for module, path in _modules():  # a command shares only the ROS bodies and the progress writer
        command = module.split(".")[2] if module.startswith("dynevent.tools.") else None
        if command not in cli.COMMANDS:
            continue
        tools = {name.split(".")[2] for name in _imports(module, path) if name.startswith("dynevent.tools.")}
        assert tools <= {command, "live", "_progress"}, f"{module} imports {sorted(tools)} of dynevent.tools"


def _writes(source: str) -> list[str]:
    """Where code opens a file to write it itself: ``open()`` or a path's ``open()`` in a mode that
    writes, a path's ``write_text()`` or ``write_bytes()``, ``os.open()`` of anything but ``os.devnull``."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if not isinstance(node, ast.Call):
            continue
        func, text = node.func, ast.unparse(node)
        given = [*node.args, *(keyword.value for keyword in node.keywords if keyword.arg == "mode")]
        modes = [arg.value for arg in given if isinstance(arg, ast.Constant) and isinstance(arg.value, str)]
        writes = any(set(mode) & set("wax+") for mode in modes if len(mode) <= 3)
        if isinstance(func, ast.Name) and func.id == "open" and writes:
            found.append(text)
        elif isinstance(func, ast.Attribute) and func.attr == "open":
            owner = ast.unparse(func.value)
            if (owner == "os" and "os.devnull" not in text) or (owner != "os" and writes):
                found.append(text)
        elif (
            isinstance(func, ast.Attribute)
            and func.attr in ("write_text", "write_bytes")
            and ast.unparse(func.value) != "files"
        ):
            found.append(text)
    return found


#: The modules that open files to write them themselves: the one writer of the files a command is
#: given (dynevent.files), and the bag reader's copy of a compressed bag, unpacked in a temporary
#: directory of its own (no path a user names).
WRITERS = frozenset({"dynevent.files", "dynevent.bags.unpack"})


def test_every_file_a_command_writes_goes_through_the_one_writer() -> None:
    """A command's outputs (--junit, --report, --trace, --output) are checked before its work starts
    and written by dynevent.files, whichever room makes their text: no other module opens a file to
    write it."""
    found = {
        module: writes
        for module, path in _modules()
        if module not in WRITERS and (writes := _writes(path.read_text(encoding="utf-8")))
    }
    assert found == {}, found
    assert _writes((SRC / "bags" / "unpack.py").read_text(encoding="utf-8"))  # the reader sees one
    seen = (
        "open(p, 'w')\nopen(p)\npath.open('xb')\npath.open('rb')\np.write_text(t)\n"
        "files.write_text(p, t, f)\nos.open(p, os.O_WRONLY)\nos.open(os.devnull, os.O_WRONLY)\n"
        "open(p, mode='a')\n"
    )
    assert _writes(seen) == [
        "open(p, 'w')", "path.open('xb')", "p.write_text(t)", "os.open(p, os.O_WRONLY)", "open(p, mode='a')"
    ]  # fmt: skip


ARCHITECTURE = SRC.parents[1] / "docs" / "architecture.md"


def _floors() -> dict[str, int]:
    """Each room's floor: 1 for a room that may import none, else one above the highest it may."""
    floors: dict[str, int] = {}

    def floor(room: str) -> int:
        if room not in floors:
            floors[room] = 1 + max((floor(below) for below in ALLOWED[room]), default=0)
        return floors[room]

    for room in ALLOWED:
        floor(room)
    return floors


def _architecture_rows(text: str) -> dict[str, tuple[int, frozenset[str], str]]:
    """docs/architecture.md's table of rooms: each room's floor, what it may import, what it must never
    know."""
    rows = {}
    for line in text.splitlines():
        cells = [cell.strip() for cell in line.strip().strip("|").split("|")]
        if len(cells) == 4 and cells[0].startswith("`") and cells[1].isdigit():
            may = frozenset(name.strip("` ") for name in cells[2].split(",") if "`" in name)
            rows[cells[0].strip("`")] = (int(cells[1]), may, cells[3])
    return rows


def test_the_architecture_page_names_every_room_with_its_floor_and_what_it_may_import() -> None:
    """docs/architecture.md cannot fall behind the package: every room under src/dynevent is a row of
    its table, with the floor its imports give and exactly the rooms it may import."""
    rows = _architecture_rows(ARCHITECTURE.read_text(encoding="utf-8"))
    rooms = {_part(module) for module, _ in _modules()} - {"", "__main__"}
    assert set(rows) == rooms
    floors = _floors()
    for room, (floor, may, never) in rows.items():
        assert may == ALLOWED[room], (room, sorted(may), sorted(ALLOWED[room]))
        assert floor == floors[room], (room, floor, floors[room])
        assert never, room
    text = ARCHITECTURE.read_text(encoding="utf-8")
    drawn = {
        int(floor): {word for word in rest.split() if word in rooms}
        for floor, rest in re.findall(r"^floor +(\d+) +(.*)$", text, re.MULTILINE)
    }
    assert drawn == {
        floor: {room for room in rooms if floors[room] == floor} for floor in set(floors.values())
    } | {max(floors.values()) + 1: set()}  # the drawing's top floor: __main__
    for name in re.findall(r"`(test_\w+)`", text):
        assert name in globals(), f"docs/architecture.md names {name}, which is no test here"
    made = "| `wire` | 2 | `errors` | a state |\n| `files` | 3 | `errors`, `wire` | what a file means |\n"
    assert _architecture_rows(made) == {
        "wire": (2, frozenset({"errors"}), "a state"),
        "files": (3, frozenset({"errors", "wire"}), "what a file means"),
    }


# --------------------------------------------------------------------------- tests/ mirrors src/

TESTS = SRC.parents[1] / "tests"

#: The folders of tests/ that mirror nothing of the package, and what each holds instead.
TESTS_OF_THEIR_OWN = {
    "spec": "docs/spec.md section by section, one file a section, whatever module carries a rule out",
    "project": "the project as a whole: this layout, the docs and their examples, errors, hostile input",
    "net": "a site across hosts (network namespaces): the ROS binding and the commands between machines",
    "support": "the helpers the tests share (no test here)",
    "data": "the files the tests read: recordings, schemas, stores (no code)",
}

#: Where a module that is not a test may lie: the one place of the shared helpers, and beside the tests
#: that run in environments of their own (ROS 2 over DDS, hosts), which start their helpers as scripts.
HELPERS = ("support", "ros", "net")


def _packages(src: Path) -> list[str]:
    """The package's folders that hold modules, as paths below it (``conformance/probe``)."""
    return sorted(
        path.parent.relative_to(src).as_posix() for path in src.rglob("__init__.py") if path.parent != src
    )


def _unmirrored(src: Path, tests: Path) -> list[str]:
    """The package's folders whose tests folder of the same path is missing or holds no test."""
    return [package for package in _packages(src) if not any((tests / package).glob("test_*.py"))]


def _foreign(src: Path, tests: Path) -> list[str]:
    """The folders of tests/ that name neither a folder nor a module of the package at their path and
    are none of :data:`TESTS_OF_THEIR_OWN` (nor inside one)."""
    found = []
    for folder in sorted(path for path in tests.rglob("*") if path.is_dir()):
        relative = folder.relative_to(tests)
        if relative.parts[0] in TESTS_OF_THEIR_OWN or "__pycache__" in relative.parts:
            continue
        if not ((src / relative / "__init__.py").exists() or (src / relative).with_suffix(".py").exists()):
            found.append(relative.as_posix())
    return found


def _stray_helpers(tests: Path) -> list[str]:
    """Modules of tests/ that are neither a test nor a conftest.py and lie outside :data:`HELPERS`; and
    tests inside ``support``."""
    found = []
    for path in sorted(tests.rglob("*.py")):
        relative = path.relative_to(tests)
        test = path.name.startswith("test_") or path.name == "conftest.py"
        home = relative.parts[0] if len(relative.parts) > 1 else ""
        if (not test and home not in HELPERS) or (path.name.startswith("test_") and home == "support"):
            found.append(relative.as_posix())
    return found


def test_every_folder_of_the_package_has_its_tests_at_the_same_path_under_tests() -> None:
    """A maintainer finds a module's tests without a search: src/dynevent/conformance/probe's are in
    tests/conformance/probe, src/dynevent/testing's in tests/testing (the binding's, ros, need ROS 2)."""
    assert _unmirrored(SRC, TESTS) == []


def test_every_folder_of_tests_mirrors_the_package_or_says_what_it_holds() -> None:
    """tests/bt mirrors the module dynevent/bt.py; tests/spec, tests/project, tests/net, tests/support and
    tests/data are the documented exceptions."""
    assert _foreign(SRC, TESTS) == []


def test_the_test_helpers_lie_in_one_place() -> None:
    """No helper lies loose at the top of tests/ or in a folder of tests: the shared ones are in
    tests/support (``from support.scenario import ...``), the ROS tests' and the hosts' beside them."""
    assert _stray_helpers(TESTS) == []
    assert (TESTS / "support" / "__init__.py").exists()


def test_the_mirrors_reader_sees_a_missing_folder_a_foreign_one_and_a_loose_helper(tmp_path: Path) -> None:
    """The checks are not blind: a package folder without tests, a tests folder that mirrors nothing,
    a loose helper and a test among the helpers are each seen."""
    src, tests = tmp_path / "src", tmp_path / "tests"
    for name in ("a/__init__.py", "a/b/__init__.py", "c/__init__.py", "d.py", "__init__.py"):
        (src / name).parent.mkdir(parents=True, exist_ok=True)
        (src / name).write_text("")
    made = ["a/test_a.py", "a/b/helper.py", "d/test_d.py", "e/test_e.py", "data/x/y.txt", "scenario.py"]
    made += ["conftest.py", "support/test_s.py", "support/tool.py", "net/hosts.py"]
    for name in made:
        (tests / name).parent.mkdir(parents=True, exist_ok=True)
        (tests / name).write_text("")
    assert _unmirrored(src, tests) == ["a/b", "c"]
    assert _foreign(src, tests) == ["e"]
    assert _stray_helpers(tests) == ["a/b/helper.py", "scenario.py", "support/test_s.py"]
