"""The command line, and what only it runs.

:mod:`~dynevent.tools.cli` (``dynevent``), :mod:`~dynevent.tools.check` (``dynevent check``: files,
progress and printing over :mod:`dynevent.conformance.judge` and :mod:`dynevent.bags`),
:mod:`~dynevent.tools.explain_command` (``dynevent explain``), :mod:`~dynevent.tools.demo` and
:mod:`~dynevent.tools.loopback` (a client and a server in one process) and
:mod:`~dynevent.tools.diagram` (the phase diagram).  Judging lives below it, in
:mod:`dynevent.conformance`, where ``dynevent.ros`` reads it too; nothing imports this package but
``dynevent.__main__``.
"""
