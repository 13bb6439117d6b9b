"""serve's DDS participant (dynevent.ros.participant): set only where it is the user's to set, and,
over real Fast DDS, a participant with the shipped profile hears none of its own endpoints while
another participant of the same process hears them (which is why serve's judge has its own)."""

from __future__ import annotations

import subprocess
import sys
import textwrap

from ros_support import child_env

from dynevent.ros import participant


def test_the_profile_is_given_only_where_the_user_gave_none() -> None:
    environ: dict[str, str] = {}
    assert participant.ignore_own_endpoints(environ) == ""
    assert environ == {"FASTDDS_DEFAULT_PROFILES_FILE": str(participant.PROFILE)}
    assert participant.PROFILE.is_file()
    theirs = {"FASTRTPS_DEFAULT_PROFILES_FILE": "/etc/site.xml"}
    said = participant.ignore_own_endpoints(theirs)
    assert "FASTRTPS_DEFAULT_PROFILES_FILE names your own profiles" in said
    assert "fastdds.ignore_local_endpoints=true" in said
    assert theirs == {"FASTRTPS_DEFAULT_PROFILES_FILE": "/etc/site.xml"}  # left as it was
    other = {"RMW_IMPLEMENTATION": "rmw_cyclonedds_cpp"}
    assert participant.ignore_own_endpoints(other).startswith("DDS: rmw_cyclonedds_cpp")
    assert "FASTDDS_DEFAULT_PROFILES_FILE" not in other


HEAR = textwrap.dedent("""
    import time, rclpy
    from rmf_task_msgs.msg import DynamicEventStatus as String
    from dynevent.ros import participant
    from dynevent.ros.spinning import Session
    assert participant.ignore_own_endpoints() == ""
    own = Session("speaker", own_context=True)
    node = own.node
    other = Session("listener", own_context=True)
    listener = other.node
    heard = {"own": 0, "other": 0}
    def counter(key):
        return lambda message: heard.__setitem__(key, heard[key] + 1)
    node.create_subscription(String, "chatter", counter("own"), 10)
    listener.create_subscription(String, "chatter", counter("other"), 10)
    publisher = node.create_publisher(String, "chatter", 10)
    ex = [own.spinner.executor, other.spinner.executor]
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and heard["other"] < 5:
        publisher.publish(String(status="hello"))
        for e in ex:
            e.spin_once(timeout_sec=0.05)
    print(heard["own"], heard["other"])
""")


def test_a_participant_with_the_profile_hears_not_itself_and_another_hears_it() -> None:
    env = {name: value for name, value in child_env().items() if "PROFILES_FILE" not in name}
    argv = [sys.executable, "-c", HEAR]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=60, env=env, check=False)
    assert done.returncode == 0, done.stderr
    own, other = (int(word) for word in done.stdout.split())
    assert other >= 5 and own == 0, done.stdout
