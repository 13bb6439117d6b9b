"""A newcomer's path, as the README gives it, from a fresh clone: the README's set-up, then the ROS
set-up into the same environment, then ``dynevent serve --help`` from the sourced environment, and
the README's test command collecting the ROS tests.  No step needs knowledge the docs do not give."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _readme_commands() -> tuple[str, str]:
    """The README's two set-up commands: the main job's and the test command's."""
    blocks = re.findall(r"```sh\n(.*?)```", (ROOT / "README.md").read_text(encoding="utf-8"), re.S)
    main, test = (block.strip() for block in blocks[:2])
    assert "dynevent demo" in main and "pytest" in test
    return main, test


def _run(command: str, cwd: Path, timeout: float) -> subprocess.CompletedProcess[str]:
    environment = {key: value for key, value in os.environ.items() if not key.startswith(("AMENT", "COLCON"))}
    for key in ("PYTHONPATH", "CMAKE_PREFIX_PATH", "LD_LIBRARY_PATH", "VIRTUAL_ENV"):
        environment.pop(key, None)
    return subprocess.run(["bash", "-c", command], cwd=cwd, env=environment, capture_output=True, text=True,
                          timeout=timeout, check=False)  # fmt: skip


#: The bound on each step of the newcomer's path (seconds): a fresh venv and the project, the ROS
#: set-up, serve's help, the collection; the test's own deadline is their sum and the clone's.
STEPS = {"install": 600, "ros": 900, "serve": 120, "collect": 300}


@pytest.mark.skipif(
    shutil.which("git") is None or not (ROOT / ".git").exists(), reason="needs a git checkout"
)
@pytest.mark.deadline(sum(STEPS.values()) + 120)
def test_the_readme_path_to_ros_from_a_fresh_clone(tmp_path: Path) -> None:
    clone = tmp_path / "dynevent"
    subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True, timeout=120)
    _, test = _readme_commands()
    install = test.split(" && .venv/bin/python -m pytest", 1)[0]  # the set-up part of the test command
    python = sys.executable if Path(sys.executable).name.startswith("python3") else "python3"
    started = time.monotonic()
    done = _run(install.replace("python3 -m venv", f"{python} -m venv", 1), clone, STEPS["install"])
    assert done.returncode == 0, done.stdout + done.stderr
    ros = _run("bash tests/ros/setup-ros-env.sh", clone, STEPS["ros"])
    took = time.monotonic() - started
    assert ros.returncode == 0, ros.stdout + ros.stderr
    assert f"venv {clone}/.venv" in ros.stdout, ros.stdout  # the README's environment, not another
    serve = _run(". build/ros/env.sh && command -v dynevent && dynevent serve --help", clone, STEPS["serve"])
    assert serve.returncode == 0, serve.stdout + serve.stderr
    assert serve.stdout.splitlines()[0] == f"{clone}/.venv/bin/dynevent", serve.stdout
    assert "usage: dynevent serve" in serve.stdout
    header = _run(". build/ros/env.sh && .venv/bin/python -m pytest --co -q -p no:cacheprovider tests/ros "
                  "| tail -3", clone, STEPS["collect"])  # fmt: skip
    assert re.search(r"\d+ tests? collected", header.stdout), header.stdout + header.stderr
    print(f"the README's set-up and the ROS set-up from a fresh clone: {took:.0f} s")
