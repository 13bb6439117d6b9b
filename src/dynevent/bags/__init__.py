"""Recordings: a rosbag2 bag's Dynamic Event conversations, read into records and judged, without ROS.

A bag is files (``metadata.yaml`` beside MCAP or SQLite storage, CDR inside), so this room never
imports rclpy: it decodes with ``rosbags`` (the ``bags`` extra) and the project's own interface
files, turns each robot's messages into the records :mod:`dynevent.conformance.judge` reads, and
judges them (:func:`check_bag`).  ``dynevent record`` (in :mod:`dynevent.ros`, which needs rclpy)
writes what this reads; ``dynevent check BAG`` prints what it finds.
"""

from __future__ import annotations

from dynevent.bags.reader import BagReport, RobotReport, bag_records, check_bag

__all__ = ["BagReport", "RobotReport", "bag_records", "check_bag"]
