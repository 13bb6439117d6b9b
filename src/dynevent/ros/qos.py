"""What the binding's endpoints share: the QoS of the Dynamic Event topics, and turning on an action's
service introspection.  A module of its own, so that the client and the server import neither
each other."""

from __future__ import annotations

from typing import Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

__all__ = ["introspect", "latched", "latched_publisher"]


def latched(depth: int) -> QoSProfile:
    """The QoS of the Dynamic Event topics: reliable, transient-local, keeping ``depth`` messages (R1.4)."""
    return QoSProfile(
        history=HistoryPolicy.KEEP_LAST,
        depth=depth,
        reliability=ReliabilityPolicy.RELIABLE,
        durability=DurabilityPolicy.TRANSIENT_LOCAL,
    )


def latched_publisher(node: Any, message_type: Any, topic: str, depth: int) -> Any:
    """A publisher of a Dynamic Event topic (:func:`latched`) without rclpy's default QoS-event
    handlers: two waitables per publisher that every pass of the executor visits, a cost on every
    goal's round trip.  Offering the strongest QoS, it can be incompatible with a subscription only
    in a deadline or a liveliness lease asked for, which that subscription's handlers report."""
    from rclpy.event_handler import PublisherEventCallbacks

    quiet = PublisherEventCallbacks(use_default_callbacks=False)
    return node.create_publisher(message_type, topic, latched(depth), event_callbacks=quiet)


def introspect(action: Any, node: Any, qos: QoSProfile | None = None) -> bool:
    """Turn on the introspection, with contents, of an rclpy action client or server: its service
    events are published (``<action>/_action/<service>/_service_event``) with ``qos`` (reliable,
    volatile, 100 deep when None).  False where rclpy cannot."""
    configure = getattr(action, "configure_introspection", None)
    if configure is None:
        return False
    from rclpy.service_introspection import ServiceIntrospectionState

    configure(node.get_clock(), qos or QoSProfile(depth=100), ServiceIntrospectionState.CONTENTS)
    return True
