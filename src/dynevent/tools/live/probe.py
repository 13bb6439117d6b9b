"""``dynevent probe`` over ROS 2: the probe's cases (:mod:`dynevent.conformance.probe.runner`) run against
a live server through the ROS binding's link (:class:`dynevent.ros.probe.RosLink`), with a progress
line on a terminal, the findings printed and the reports written (:func:`dynevent.files.write_text`);
Ctrl-C or SIGTERM stops it, with the findings of the cases that ended."""

from __future__ import annotations

import contextlib
from collections.abc import Callable

from dynevent import files
from dynevent.conformance.judge.trace import TraceWriter
from dynevent.conformance.probe import cases as probe_cases
from dynevent.conformance.probe import runner as probe_runner
from dynevent.conformance.probe.cases import Case
from dynevent.conformance.probe.runner import Options
from dynevent.errors import FileError, ProbeError
from dynevent.interrupts import Interrupted, interruptible
from dynevent.ros.graph import no_server_text
from dynevent.ros.probe import RosLink
from dynevent.ros.spinning import Session
from dynevent.tools._progress import Progress
from dynevent.tools.live import flush_output, offline, see_the_whole_graph

__all__ = ["ProbeInterrupted", "main", "run"]


def main(options: Options, cases: list[Case], say: Callable[[str], None]) -> int:
    """``dynevent probe``: run the cases, print the findings, write the reports; the exit status."""
    # the whole list runs what DDS can (docs/probe.md says which it leaves out); a choice is told why
    chosen = len(cases) < len(probe_cases.CASES)
    cases = probe_runner.runnable(cases, RosLink, options, say if chosen else lambda _: None)
    if not cases:
        say("no case left to run")
        return probe_cases.EXIT_USAGE
    progress = Progress("dynevent probe", len(cases), interval=0.0)
    say = progress.above(say)
    trace = _open_trace(options)  # kept in memory too: the judge reads every record of the exchange
    with contextlib.ExitStack() as closing:  # the ROS close-down last: no report waits on the middleware
        try:
            ran = run(cases, options, say, progress.show, trace=trace, closing=closing)
        except ProbeInterrupted as stop:
            progress.close()
            if stop.findings:
                say(probe_cases.format_findings(stop.findings).rstrip("\n"))
            say(f"{stop.name}: stopped after {len(stop.findings)} of {len(cases)} case(s); the rest not run")
            return 128 + stop.signal
        finally:
            trace.close()
        progress.close()
        if ran is None:
            return probe_cases.EXIT_USAGE
        findings, took = ran
        status = probe_runner.conclude(findings, trace.text(), options, say, files.write_text)[0]
        say(probe_runner.took(took, options))  # its bound, checkable
        return status


class ProbeInterrupted(Interrupted):
    """Ctrl-C or SIGTERM during a probe run: ``findings`` are those of the cases that ended before."""

    def __init__(self, signum: int, findings: list[probe_cases.CaseFinding]) -> None:
        super().__init__(signum)
        self.findings = list(findings)


def run(
    cases: list[Case],
    options: Options,
    say: Callable[[str], None],
    progress: Callable[[str], None] | None = None,
    *,
    trace: TraceWriter | None = None,
    closing: contextlib.ExitStack | None = None,
) -> tuple[list[probe_cases.CaseFinding], float] | None:
    """Carry out ``cases`` against the robot over DDS, writing every record of the exchange to
    ``trace``; the findings and the seconds the run took on the link's clock, from the server found
    to the last case's end, or None when no server was found.  The node stops spinning when the
    cases end (nothing more reaches ``trace``); its close-down (:meth:`Session.close`, bounded) is
    left to ``closing`` where given, to come after the report, else done here."""
    see_the_whole_graph()
    offline(say)
    session = Session("dynevent_probe", options.ros_args)
    link = RosLink(session.node, options.fleet, options.robot, trace)
    with contextlib.ExitStack() as here:
        (closing or here).callback(session.close, link.destroy)
        (closing or here).callback(flush_output)  # first: what was printed reaches its reader
        return _run(session, link, cases, options, say, progress)


def _run(
    session: Session,
    link: RosLink,
    cases: list[Case],
    options: Options,
    say: Callable[[str], None],
    progress: Callable[[str], None] | None,
) -> tuple[list[probe_cases.CaseFinding], float] | None:
    if options.introspection:
        link.introspect()
    session.start()
    findings: list[probe_cases.CaseFinding] = []
    try:
        with interruptible():
            if not link.wait_for_server(options.server_wait):
                say(no_server_text(session.node, options.fleet, options.robot, options.server_wait))
                return None
            began = link.clock()
            probe_runner.run_cases(link, options, cases, say, progress, findings)
        return findings, link.clock() - began
    except Interrupted as stop:
        raise ProbeInterrupted(stop.signal, findings) from None
    finally:
        session.spinner.stop()


def _open_trace(options: Options) -> TraceWriter:
    """The trace of the run: kept in memory for the judge, and written to ``--trace`` when given."""
    try:
        return TraceWriter(options.trace, fleet=options.fleet, robot=options.robot, keep=True, tap="client")
    except FileError as exc:
        raise ProbeError(str(exc)) from None
