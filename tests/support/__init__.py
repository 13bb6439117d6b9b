"""What the tests share, and nothing else: the one place of the test helpers (no test module here).

``pythonpath`` in pyproject.toml puts ``tests/`` on ``sys.path``, so a test in any folder imports a
helper as ``from support.scenario import waiting``; a script outside the tests (bench/) puts ``tests/``
on its path first.

- :mod:`support.scenario`: the server machine's situations and expected outputs (tests/spec, tests/server);
- :mod:`support.client_scenario`: the client machine's inputs and states (tests/client);
- :mod:`support.kit_runs`: how the stateful kit is run, and the input sequences drawn (tests/testing);
- :mod:`support.field_cases`: descriptions real clients send, with the fleet adapter's verdict;
- :mod:`support.doc_sessions`: the console sessions of the documentation;
- :mod:`support.probe_expected`: what the probe's cases find against serve and its broken variants;
- :mod:`support.broken_driver`, :mod:`support.misbehaving_driver`: implementations behind the driver
  protocol, broken on purpose, run as scripts (``python tests/support/broken_driver.py``);
- :mod:`support.recordings`: a robot's conversation written as a rosbag2 recording, and ``check`` run;
- :mod:`support.bag_readers`: readers of a recording other than dynevent's;
- :mod:`support.bag_bombs`: compressed recordings, honest and hostile.

The ROS tests' own helpers (tests/ros, tests/net) stay beside them: they run in the environments those
tests set up.
"""
