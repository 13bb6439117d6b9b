"""What holds with or without ROS 2: the core never imports rclpy."""

from __future__ import annotations


def test_no_core_module_imports_rclpy() -> None:
    """Importing every dynevent module but the binding leaves rclpy unimported."""
    import subprocess
    import sys

    code = (
        "import importlib, pkgutil, sys, dynevent\n"
        "names = [m.name for m in pkgutil.walk_packages(dynevent.__path__, 'dynevent.')]\n"
        "for name in names:\n"
        "    if not name.startswith('dynevent.ros.'):  # the package itself is lazy\n"
        "        importlib.import_module(name)\n"
        "bad = sorted(m for m in sys.modules if m.split('.')[0] in ('rclpy', 'rmf_task_msgs'))\n"
        "print(len(names), bad)\n"
        "sys.exit(1 if bad else 0)\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False
    )
    assert done.returncode == 0, done.stdout + done.stderr
