"""The command line, and what only it runs.

:mod:`~dynevent.tools.cli` (``dynevent``) parses the command line and calls one function, the
``run(args)`` of the command's own module: :mod:`~dynevent.tools.demo` (with the simulated session it
plays, :mod:`~dynevent.tools.demo.simulated_session`), :mod:`~dynevent.tools.check`,
:mod:`~dynevent.tools.explain`, :mod:`~dynevent.tools.diagram`, :mod:`~dynevent.tools.vectors`, and the
commands on a live ROS 2 graph, :mod:`~dynevent.tools.serve`, :mod:`~dynevent.tools.send`,
:mod:`~dynevent.tools.probe` and :mod:`~dynevent.tools.record`, which check their own input before
their bodies over ROS (:mod:`dynevent.tools.live`) are imported.  Every file a command writes goes
through :mod:`dynevent.files`.  Judging lives below, in :mod:`dynevent.conformance`, where
``dynevent.ros`` reads it too; nothing imports this package but ``dynevent.__main__``.
"""
