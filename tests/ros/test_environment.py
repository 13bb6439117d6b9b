"""What holds with or without ROS 2: the core never imports rclpy."""

from __future__ import annotations

from pathlib import Path


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


def test_each_xdist_worker_takes_a_dds_domain_of_its_own() -> None:
    """Two ROS tests that run at once, on two workers, never meet on DDS: each worker of a run takes its
    own domain, the same for the whole run; a domain the user gave is the first worker's."""
    from ros_support import DOMAINS, domain_of

    run = {"PYTEST_XDIST_TESTRUNUID": "3f2a"}
    domains = [domain_of({**run, "PYTEST_XDIST_WORKER": f"gw{n}"}) for n in range(8)]
    assert len(set(domains)) == 8 and all(1 <= domain <= DOMAINS for domain in domains), domains
    assert domains == [domain_of({**run, "PYTEST_XDIST_WORKER": f"gw{n}"}) for n in range(8)]
    many = [domain_of({**run, "PYTEST_XDIST_WORKER": f"gw{n}"}) for n in range(DOMAINS)]
    assert sorted(many) == list(range(1, DOMAINS + 1))  # counting round, never past the last
    given = {"ROS_DOMAIN_ID": "42"}
    assert [domain_of({**given, "PYTEST_XDIST_WORKER": f"gw{n}"}) for n in range(3)] == [42, 43, 44]
    assert domain_of(given) == 42
    assert 1 <= domain_of({}) <= DOMAINS


def test_a_domain_another_test_process_holds_is_never_taken(tmp_path: Path) -> None:
    """Two test runs on one machine draw their domains at random and may draw the same: each worker
    claims its domain with a lock that another process's claim skips, and that is free again once its
    holder has ended, however it ended."""
    import os
    import subprocess
    import sys

    from ros_support import _HELD, DOMAINS, claim_domain

    held = len(_HELD)
    holder = subprocess.Popen(
        [sys.executable, "-c", f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r})\n"
         f"from ros_support import claim_domain; print(claim_domain(7, {str(tmp_path)!r}), flush=True)\n"
         "sys.stdin.read()"],
        stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert holder.stdout is not None
        assert holder.stdout.readline().strip() == "7"
        assert claim_domain(7, str(tmp_path)) == 8  # held by the other process: the next one
        assert claim_domain(7, str(tmp_path)) == 9  # and by this one now
        assert claim_domain(DOMAINS, str(tmp_path)) == DOMAINS
        assert claim_domain(DOMAINS, str(tmp_path)) == 1  # counting round
    finally:
        holder.kill()
        holder.wait(30)
    assert claim_domain(7, str(tmp_path)) == 7  # its holder ended (killed): free again
    for handle in _HELD[held:]:
        os.close(handle)
    del _HELD[held:]
