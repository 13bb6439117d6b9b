"""bench/results.md in parts: the in-process tables (bench/run.py) and one section per ROS benchmark.

Each ROS benchmark owns a section between ``<!-- begin NAME -->`` and
``<!-- end NAME -->``; writing one section keeps every other part of the file,
and bench/run.py keeps the ROS sections when it rewrites its tables.
"""

from __future__ import annotations

import datetime
import importlib.metadata
import os
import platform
import re
from collections.abc import Sequence
from pathlib import Path

RESULTS = Path(__file__).resolve().parent / "results.md"
_SECTION = re.compile(r"<!-- begin (?P<name>[\w-]+) -->\n.*?<!-- end (?P=name) -->\n", re.DOTALL)


def machine_description(packages: Sequence[str]) -> list[str]:
    """Markdown bullets naming the date, the load, the machine, Python and the packages' versions."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = []
    for package in packages:
        try:
            versions.append(f"{package} {importlib.metadata.version(package)}")
        except importlib.metadata.PackageNotFoundError:
            versions.append(f"{package} (not installed)")
    try:
        load = "load average (1, 5, 15 min) at the end: " + ", ".join(f"{x:.2f}" for x in os.getloadavg())
    except OSError:
        load = "load average: unknown"
    return [
        f"- date: {datetime.datetime.now(datetime.timezone.utc).strftime('%Y-%m-%d %H:%M UTC')}",
        f"- {load} (other work on the machine inflates medians and spreads)",
        f"- machine: {cpu}, {os.cpu_count()} logical CPUs, {platform.platform()}",
        f"- Python: {platform.python_implementation()} {platform.python_version()}",
        f"- packages: {', '.join(versions)}",
    ]


def sections(text: str) -> dict[str, str]:
    """The named sections of a results text, each with its markers."""
    return {match["name"]: match[0] for match in _SECTION.finditer(text)}


def section(name: str, lines: Sequence[str]) -> str:
    """``lines`` as the section ``name``, markers included."""
    return f"<!-- begin {name} -->\n" + "\n".join(lines).rstrip("\n") + f"\n<!-- end {name} -->\n"


def with_section(text: str, name: str, block: str) -> str:
    """``text`` with its section ``name`` replaced by ``block``, or ``block`` appended."""
    current = sections(text).get(name)
    if current is not None:
        return text.replace(current, block)
    return text.rstrip("\n") + "\n\n" + block


def write_section(name: str, lines: Sequence[str], path: Path = RESULTS) -> None:
    """Replace (or add) the section ``name`` of ``path``, keeping the rest of the file."""
    text = path.read_text(encoding="utf-8") if path.exists() else ""
    path.write_text(with_section(text, name, section(name, lines)), encoding="utf-8")


def keep_sections(new_text: str, path: Path = RESULTS) -> str:
    """``new_text`` followed by the named sections ``path`` holds today (bench/run.py's rewrite)."""
    if not path.exists():
        return new_text
    for name, block in sections(path.read_text(encoding="utf-8")).items():
        new_text = with_section(new_text, name, block)
    return new_text
