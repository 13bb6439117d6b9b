"""The simulated fleet ``dynevent serve`` runs: its configuration, read and checked without ROS 2.

:mod:`dynevent.sim.config` reads a ``--config`` file and the flags into a
:class:`~dynevent.sim.config.ServeConfig` (the fleet, its robots, the simulated categories, the
robots' map and actions, the mode, the shard) and says what a simulated child does with its
description (:func:`~dynevent.sim.config.plan`).  The command line checks its input with it before
it needs rclpy; :mod:`dynevent.ros.fleet` runs what it describes, for ``dynevent serve``.
"""

from __future__ import annotations

from dynevent.sim.config import CategorySpec, ServeConfig, Step, load_config, machine_config, plan

__all__ = ["CategorySpec", "ServeConfig", "Step", "load_config", "machine_config", "plan"]
