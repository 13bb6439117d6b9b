"""The wire: what travels between a Dynamic Event client and server, and nothing that decides.

:mod:`~dynevent.wire.messages` (frozen mirrors of every message, checked to the wire's ranges),
:mod:`~dynevent.wire.vocab` (the protocol's vocabularies as enums),
:mod:`~dynevent.wire.names` (the ROS 2 names of a robot's action, topics and service) and
:mod:`~dynevent.wire.description` (the ``dynamic_event`` event description).  The wire imports
nothing of the rest of dynevent but :mod:`dynevent.errors`.
"""
