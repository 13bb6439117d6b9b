"""The tools over the protocol core: the command line and what it runs.

:mod:`~dynevent.tools.cli` (``dynevent``), :mod:`~dynevent.tools.check` (a trace checker),
:mod:`~dynevent.tools.explain` (answers in words), :mod:`~dynevent.tools.demo` and
:mod:`~dynevent.tools.loopback` (a client and a server in one process) and
:mod:`~dynevent.tools.diagram` (the phase diagram).
"""
