"""The robot's side of the protocol: the pure machine and what holds it.

:mod:`~dynevent.server.inputs` and :mod:`~dynevent.server.outputs` (the machine's values),
:mod:`~dynevent.server.machine` (``accept`` and ``step`` over a frozen ``State``: every rule of
docs/spec.md that decides something), :mod:`~dynevent.server.snapshot` (state to JSON and back),
:mod:`~dynevent.server.holder` (a thin mutable holder for one robot),
:mod:`~dynevent.server.fleet` (many robots) and :mod:`~dynevent.server.store` (an SQLite store
that survives a restart).  The server imports the wire, never the client or the tools.
"""
