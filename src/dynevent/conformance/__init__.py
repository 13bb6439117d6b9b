"""Conformance: what holds an implementation to docs/spec.md, in three parts, each a folder.

- :mod:`~dynevent.conformance.vectors` (``dynevent vectors``): the vectors, one JSON file per spec
  section with their schema, in that folder; reading them (``files``), matching an answer
  (``diff``), running them in process or against any program speaking the driver protocol
  (``runner``, ``driver``) and reporting (``report``, ``xml_report``).
- :mod:`~dynevent.conformance.probe` (``dynevent probe``): a client that breaks the protocol on
  purpose; its cases, their verdicts and reports (``cases``), carrying them out over a link
  (``runner``), and the link to a server in this process or behind a driver (``in_process``).
- :mod:`~dynevent.conformance.judge` (``dynevent check``): judging what a server did from what was
  seen of it, replaying a recording beside the machine (``replay``), and judging a server's
  clients (``clients``).

The vectors and the judge import neither each other nor the probe; the probe imports both (it runs
a driver through the vectors' runner, writes its JUnit XML with the vectors' ``xml_report``, and has
its trace judged).  Beside the folders lie the modules no one part owns, which import none of the
three: :mod:`~dynevent.conformance.records` (inputs, outputs and configurations as JSON records,
shared by the vectors' driver protocol and the judge's traces), :mod:`~dynevent.conformance.received`
(the mirrors of received messages, for the ROS binding and the recordings' reader) and
:mod:`~dynevent.conformance.explain` (``dynevent explain``: why a goal would be refused).
"""
