"""The field's event descriptions: the shapes a child's description may take, and what a robot can do.

A NEXT goal names a category and carries a JSON description of the child to
run.  For the categories of the deployed system (``go_to_place``,
``perform_action``, ``sequence``, ``clean``, ``pickup``, ``dropoff``) this
module checks a description as the fleet adapter does: first its category's
JSON schema (:mod:`~dynevent.descriptions.shapes`), then the robot
(:class:`Robot`: the places on its map, the actions it performs, the
categories a sequence's activities may use).  Every fault is one line with its
JSON pointer (``/one_of/1: 5.5 is not a place``), as a refusal's ``errors``
carry them (R4.10, R4.18).

>>> from dynevent import ServerConfig, descriptions
>>> robot = descriptions.Robot(places=["pantry", "lounge"], actions=["wave"])
>>> robot.check("go_to_place", {"one_of": ["pantry", 5.5]})
('/one_of/1: 5.5 is not a place',)
>>> robot.check("go_to_place", {"waypoint": "lounge", "orientation": 1.57})
()
>>> config = ServerConfig(categories=robot.validators())

The verdict takes a few microseconds (a compiled schema) and needs nothing
beyond ``attrs``; the lines that say where a description goes wrong come from
the ``jsonschema`` package: ``pip install 'dynevent[descriptions]'``.
"""

from __future__ import annotations

from dynevent.descriptions.reading import (
    Activity,
    Clean,
    GoToPlace,
    PayloadItem,
    PayloadTransfer,
    PerformAction,
    Place,
    Reading,
    Sequence,
    read,
)
from dynevent.descriptions.robot import Robot, shape_validators
from dynevent.descriptions.shapes import CATEGORIES, conforms, schema, shape_errors

__all__ = [
    "CATEGORIES",
    "Activity",
    "Clean",
    "GoToPlace",
    "PayloadItem",
    "PayloadTransfer",
    "PerformAction",
    "Place",
    "Reading",
    "Robot",
    "Sequence",
    "conforms",
    "read",
    "schema",
    "shape_errors",
    "shape_validators",
]
