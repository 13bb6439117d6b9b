"""``dynevent probe``: a client that breaks the protocol on purpose, over any link.

:mod:`.cases` holds the cases (data), their verdicts (:class:`~.cases.CaseFinding`) and the reports
(a table, JUnit XML, HTML, the exit status), without ROS 2; :mod:`.runner` carries the cases out
over a :class:`~.runner.Link`; :mod:`.in_process` is the link to dynevent's machine in this process
or to an implementation behind the driver protocol; :mod:`dynevent.ros.probe` is the link over DDS.
Each verdict is held to what the judge (:mod:`dynevent.conformance.judge`) finds on the probe's
trace.
"""
