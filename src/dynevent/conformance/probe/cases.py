"""``dynevent probe``'s cases, verdicts and reports, without ROS 2.

A case is data: an id (``section.name``), what it checks, the rules of
docs/spec.md it tests, what it needs of the server (an active run, a child
it can run), and the divergences of docs/divergences.md whose way of
breaking it shows.  :mod:`dynevent.conformance.probe.runner` carries each case out over a link (in
process, through the driver protocol, or over DDS with :mod:`dynevent.ros.probe`) and gives a
:class:`CaseFinding` per case; this module selects
cases, lists them, and reports findings (a table, JUnit XML) and the exit
status, so that ``dynevent probe --list`` needs no ROS.

Verdicts: ``pass``; ``fail`` (a rule broken); ``info`` (behaviour the spec
leaves open); ``missing`` (the case could not be reached, e.g. no run began
in time).  No case checks a SHOULD of the spec, so there is no verdict for a
difference it allows.  A failure whose way of breaking
docs/divergences.md records for rmf_ros2 names its D-number; with
``--known rmf_ros2`` such a failure is shown as ``known`` and does not fail
the run.
"""

from __future__ import annotations

import enum
import fnmatch
import html
import json
import re
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence

import attrs

from dynevent.conformance.judge import check_trace, divergences
from dynevent.conformance.judge.trace import Finding as JudgeFinding
from dynevent.conformance.vectors.xml_report import xml_document, xml_safe
from dynevent.descriptions.reading import GoToPlace, read
from dynevent.errors import DyneventError
from dynevent.wire.vocab import Violation

__all__ = [
    "CASES",
    "EXIT_FAILED",
    "EXIT_NOT_RUN",
    "EXIT_OK",
    "EXIT_USAGE",
    "KNOWN",
    "KNOWN_MISSING",
    "LIVE_CANNOT_SHOW",
    "UNTRACEABLE",
    "Case",
    "CaseFinding",
    "Judged",
    "Verdict",
    "causes_text",
    "exit_status",
    "format_findings",
    "format_list",
    "judge_exchange",
    "judge_verdicts",
    "judged_summary",
    "junit_xml",
    "matches",
    "not_run_summary",
    "place_of_run",
    "probe_summary",
    "report",
    "select",
]


class Verdict(enum.Enum):
    """What became of one case."""

    PASS = "pass"
    FAIL = "fail"
    INFO = "info"
    MISSING = "missing"


@attrs.frozen
class Case:
    """One probe case: ``needs`` is ``"status"`` (a status on the graph), ``"run"`` (an active
    dynamic event, WAITING), ``"place"`` (a place to send the robot to, for a NEXT the server must
    refuse for another reason only) or ``"child"`` (an active run and a place).
    ``trace_shows_failure`` says whether ``dynevent check``, reading the probe's ``--trace``, can see
    the case's failure too (not when a passive observer cannot tell the failure from a moment the spec
    allows)."""

    id: str
    title: str
    rules: tuple[str, ...]
    needs: str = "run"
    divergences: tuple[str, ...] = ()
    trace_shows_failure: bool = True
    #: the case interrupts the robot's task (R14), a task input no client sends: it runs over a link
    #: that can (in process, the driver protocol), and is left out over one that cannot (DDS)
    interrupts: bool = False

    @property
    def section(self) -> str:
        return self.id.split(".", 1)[0]


@attrs.frozen
class CaseFinding:
    """A case's verdict, what the spec expects and what was seen, the messages exchanged, and the
    D-number when the failure is one docs/divergences.md records; ``known`` when ``--known`` covers
    it; ``absent`` when the failure is a message that did not come within the timeout (a wait the
    spec does not bound: the judge finds a message missing only where the trace ends without it)."""

    case: Case
    verdict: Verdict
    expected: str = ""
    seen: str = ""
    messages: tuple[str, ...] = ()
    divergence: str | None = None
    known: bool = False
    seconds: float = 0.0
    absent: bool = False  # the failure is a message that did not come within the timeout
    expected_missing: bool = False  # missing, as --allow-missing or --known said it may be
    #: not run because the link lost, delayed or reordered what the case sent or waited for: what the
    #: judge finds in its records may be the link's doing, and is reported, uncertain
    by_link: bool = False
    #: why a failure: ``"judge"`` (the judge's finding on the case's records, :func:`judge_verdicts`),
    #: or what the case's own script saw that a trace cannot carry (a key of :data:`UNTRACEABLE`);
    #: empty where nothing failed it (kept where the link then made the case not run)
    cause: str = ""
    #: why a failure the judge finds in the case's records may be the link's doing (an earlier case's
    #: goal, sent before this case began, was accepted during it): then the case is not run, saying so
    doubt: str = ""


@attrs.frozen
class Judged:
    """A finding of the judge ``dynevent check`` runs, over every record of the probe's exchange, that
    no case's verdict already says: in which case's records it lies (``""`` before the first), its
    ``label`` (the divergence the deployed server showed it as, an open item of the judge, or
    ``"?"``), ``known`` when ``--known`` covers that divergence, and ``uncertain`` for an open item:
    what a client's view of the exchange cannot settle, reported and not counted."""

    case: str
    finding: JudgeFinding
    label: str
    known: bool = False
    by_link: bool = False  # it lies in the records of a case the link kept from running

    @property
    def uncertain(self) -> bool:
        return self.label in divergences.OPEN_ITEMS or self.by_link

    @property
    def counts(self) -> bool:
        """Whether it fails the run: neither known nor uncertain."""
        return not (self.known or self.uncertain)

    def line(self) -> str:
        """One line: where, the rule and code, what was seen, what was expected, and how it counts."""
        finding = self.finding
        how = f"known ({self.label})" if self.known else "uncertain" if self.uncertain else "fail"
        where = self.case or "before the first case"
        return (
            f"{where}: {how}: {finding.rule} {finding.code}: {finding.message} (expected: {finding.expected})"
        )


#: A trace record's goal UUID.
_GOAL_UUID = re.compile(r'"goal_uuid"\s*:\s*"([0-9a-f]{32})"')


def judge_exchange(text: str, findings: Sequence[CaseFinding], known: Iterable[str] = ()) -> list[Judged]:
    """What the judge finds in the probe's trace ``text`` beside the cases' verdicts: every finding
    but those of a rule a case that holds it failed on (its verdict says so already); ``known`` are
    the divergences ``--known`` covers (:data:`KNOWN`)."""
    covered = frozenset(known)
    failed = {  # a wait in vain is the judge's to decide where the trace shows what never came
        finding.case.id: set(finding.case.rules)
        for finding in findings
        if finding.verdict is Verdict.FAIL and not _waited(finding)
    }
    case_at: list[str] = [""]
    goal_at: list[str] = [""]  # the goal a line's record names
    sent_in: dict[str, str] = {}  # the case whose records hold a goal's request
    current = ""
    for line in text.splitlines():
        if line.startswith("# case "):
            current = line.removeprefix("# case ")
        case_at.append(current)
        uuid = _GOAL_UUID.search(line) if line.startswith("{") else None
        goal_at.append(uuid[1] if uuid else "")
        if uuid and '"type":"goal"' in line.replace(" ", ""):
            sent_in.setdefault(uuid[1], current)
    judged = []
    for finding in check_trace(text, "the probe's exchange").findings:
        at = finding.line if 0 < finding.line < len(case_at) else 0
        # a late record of a goal belongs to the case that sent it, not to the case it fell in
        case = sent_in.get(goal_at[at], case_at[at])
        if finding.rule in failed.get(case, ()):
            continue
        divergence = divergences.label(finding)
        judged.append(Judged(case, finding, divergence, known=divergence in covered))
    return judged


#: The judge's findings that say a message never came (by the trace's end): a case that waited in vain
#: for one is the judge's to decide (:func:`judge_verdicts`).
NEVER_CAME = frozenset({Violation.ANSWER_MISSING.code, Violation.RESPONSE_MISSING.code})


def _waited(finding: CaseFinding) -> bool:
    """A case its script failed for a wait in vain (``absent``), where its records may show what
    never came: the judge's to decide when they do."""
    return finding.verdict is Verdict.FAIL and finding.absent and finding.case.trace_shows_failure


def judge_verdicts(
    text: str, findings: Sequence[CaseFinding], known: Iterable[str] = ()
) -> tuple[list[CaseFinding], list[Judged]]:
    """The cases' verdicts, the judge's (:func:`judge_exchange`, over the probe's trace ``text``): a
    case carried out whose own records hold a finding of the judge on one of its rules, or on R19.1
    (every goal answered exactly once, which each case holds its goals to), fails with that finding
    (``cause`` ``"judge"``), its divergence and whether ``known`` covers it, and so does a case whose
    script waited in vain (``absent``) where its records show what never came (an answer a step owed,
    or, in a trace that ends heard out, a response); a case's script fails it only for what a trace
    cannot carry (:data:`UNTRACEABLE`).  An uncertain finding (an open item of
    the judge) fails no case; a case whose ``doubt`` says the link may have caused what the judge
    found is not run, saying so, and its findings are uncertain.  The findings, and what the judge
    found that no case's verdict says: the section beside the cases."""
    judged = judge_exchange(text, findings, known)

    def mine_of(scripted: CaseFinding, items: list[Judged]) -> list[Judged]:
        case = scripted.case
        if not case.trace_shows_failure or not (
            scripted.verdict in (Verdict.PASS, Verdict.INFO) or _waited(scripted)
        ):
            return []
        rules = {*case.rules, "R19.1"}
        mine = [
            item
            for item in items
            if item.case == case.id and not item.uncertain and item.finding.rule in rules
        ]
        if _waited(scripted) and not any(item.finding.code in NEVER_CAME for item in mine):
            return []  # the trace does not show what the case waited for never came: its wait stands
        return mine

    disturbed = {finding.case.id for finding in findings if finding.by_link}
    disturbed |= {finding.case.id for finding in findings if finding.doubt and mine_of(finding, judged)}
    judged = [attrs.evolve(item, by_link=True) if item.case in disturbed else item for item in judged]
    taken: set[int] = set()
    verdicts = []
    for scripted in findings:
        finding = scripted
        if scripted.doubt and scripted.case.id in disturbed and not scripted.by_link:
            finding = attrs.evolve(
                scripted, verdict=Verdict.MISSING, seen=f"{scripted.doubt} (the judge found: "
                f"{_first_of(scripted, judged)})", by_link=True,
            )  # fmt: skip
        elif mine := sorted(mine_of(scripted, judged), key=lambda item: item.known):
            # one that --known does not cover first: a known divergence never hides a failure beside it
            first = mine[0].finding
            divergence = mine[0].label if mine[0].label.startswith("D") else None
            said = [
                f"the judge: {item.finding.rule} {item.finding.code}: {item.finding.message}" for item in mine
            ]
            rule = f"({first.rule})"
            expected = first.expected if first.expected.endswith(rule) else f"{first.expected} {rule}"
            finding = attrs.evolve(
                scripted, verdict=Verdict.FAIL, expected=expected,
                seen=f"the judge: {first.message}", divergence=divergence, known=mine[0].known,
                messages=(*scripted.messages, *said), cause="judge", absent=False,
            )  # fmt: skip
            taken.update(id(item) for item in mine)
        elif _waited(scripted):  # its wait stands, and says the rest of what it failed on its rules
            rules = set(scripted.case.rules)
            taken.update(
                id(item) for item in judged if item.case == scripted.case.id and item.finding.rule in rules
            )
        verdicts.append(finding)
    return verdicts, [item for item in judged if id(item) not in taken]


def _first_of(scripted: CaseFinding, judged: Sequence[Judged]) -> str:
    """The first of the judge's findings on ``scripted``'s rules in its own records, in a few words."""
    rules = {*scripted.case.rules, "R19.1"}
    for item in judged:
        if item.case == scripted.case.id and item.finding.rule in rules:
            return f"{item.finding.rule} {item.finding.code}"
    return "-"


#: Every case, in the order they run (the ones that end a run come last).
CASES: tuple[Case, ...] = (
    Case("status.latched", "a late subscriber receives the robot's status (transient-local)",
         ("R1.4", "R2.2"), needs="status"),
    Case("status.waiting", "an active run's status is WAITING with the run's seq", ("R2.1", "R2.2", "R3.1"),
         divergences=("D26",)),
    Case("describe.query", "the description query answers with the run's description, status and id",
         ("R16.2",), trace_shows_failure=False),
    Case("request.seq_stale", "a FINISHED for an earlier run is refused", ("R4.2",)),
    Case("request.seq_future", "a FINISHED for a run that has not begun is refused", ("R4.2",)),
    Case("request.seq_stale_next", "a NEXT for an earlier run is refused", ("R4.2",), needs="child"),
    Case("request.seq_future_next", "a NEXT for a run that has not begun is refused", ("R4.2",),
         needs="child"),
    Case("request.event_type_0", "a goal of event_type 0 is refused", ("R4.4",), divergences=("D7",)),
    Case("request.event_type_unknown", "a goal of event_type 4 is refused", ("R4.5",), divergences=("D7",)),
    # which categories a server supports is its configuration, which a trace tapped at a client lacks
    Case("request.category_unknown", "a NEXT of a category the robot does not support is refused", ("R4.7",),
         trace_shows_failure=False),
    Case("request.description_not_json", "a NEXT whose description is not JSON is refused", ("R4.9",)),
    # a field category's schema binds every server that supports the category (R4.18), but which ones it
    # supports is its configuration, which a trace tapped at a client lacks
    Case("request.description_invalid", "a NEXT whose description fits no form of its field category's "
         "schema is refused", ("R4.10", "R4.18"), trace_shows_failure=False),
    Case("request.stubborn_nan", "a NEXT whose stubborn period is NaN is refused", ("R4.11",), needs="place",
         divergences=("D12",)),
    Case("request.cancel_idle", "a CANCEL while no child runs is refused", ("R4.13",), divergences=("D8",)),
    # the deployed adapter numbers children itself (D10): the id a NEXT names runs only where it is the
    # adapter's next (the lab's recalibration run: it was not)
    Case("next.runs_a_child", "a NEXT runs its child: accepted, feedback with its id, one answer",
         ("R6.2", "R6.4", "R7.1", "R8.1", "R8.2", "R19.1"), needs="child", divergences=("D10",)),
    # right after the first child: a server that publishes no status at a child's end fails here on R8.4,
    # before the cases that wait in vain for the WAITING status they start from leave the rest not run
    Case("next.status_after_child", "after a child ends the status is WAITING with its id",
         ("R2.2", "R8.4", "R2.3"),
         needs="child", divergences=("D2",), trace_shows_failure=False),
    Case("next.id_zero", "a NEXT with id 0 runs child status.id + 1 (the server numbers it)",
         ("R6.2", "R20.1"), needs="child", divergences=("D10",)),
    Case("next.id_chosen", "a NEXT's own id (above the run's highest) names its child", ("R6.2",),
         needs="child", divergences=("D10",)),
    Case("next.stateless_id", "right after a child ends, a NEXT with the status's id + 1 runs",
         ("R20.1", "R20.2", "R6.2"), needs="child", divergences=("D10",)),
    Case("next.id_stale", "a NEXT whose id is not above the run's highest is refused", ("R4.12",),
         needs="child", divergences=("D10",)),
    Case("next.busy", "a NEXT while a child runs is refused", ("R4.6",), needs="child"),
    Case("next.busy_finished", "a FINISHED while a child runs is refused", ("R4.6",), needs="child",
         divergences=("D30",)),
    Case("next.race", "two NEXTs at once: one child runs, the other NEXT is refused or aborted, each "
         "answered once", ("R4.16", "R5.2", "R19.2", "R19.1", "R6.2", "R6.4"), needs="child",
         divergences=("D10",)),
    Case("feedback.log_seq", "log entries are numbered one by one per robot, across children, in known tiers",
         ("R7.2", "R7.3"), needs="child", divergences=("D9",)),
    # after a child: a server that answers the run's first id (the current one before any child) fails
    Case("describe.after_child", "after a child ends, the description query names the child's id, the "
         "run's current one", ("R16.2",), needs="child", trace_shows_failure=False),
    Case("stubborn.clamp_notice", "a stubborn period below the minimum is clamped with a warning in the "
         "start feedback", ("R12.2",), needs="child", divergences=("D11",)),
    Case("cancel.wrong_id", "a CANCEL naming another event is refused", ("R4.14",), needs="child",
         divergences=("D8",)),
    Case("cancel.seq_stale", "a CANCEL of the running child for an earlier run is refused", ("R4.2",),
         needs="child"),
    Case("cancel.seq_future", "a CANCEL of the running child for a run that has not begun is refused",
         ("R4.2",), needs="child"),
    Case("cancel.running_child", "a CANCEL of the running child ends it: both goals answered once, "
         "then WAITING standby", ("R9.3", "R8.2", "R8.3", "R19.1", "R8.4", "R2.2"), needs="child",
         divergences=("D28",)),
    Case("cancel.both_answered", "two CANCELs of the running child wait for its end and are both "
         "answered with its result", ("R9.3", "R4.16", "R8.3", "R19.1"), needs="child", divergences=("D1",)),
    Case("action.cancel_queued", "an action-level cancel sent as its NEXT is accepted is accepted, and "
         "the NEXT answered canceled: 'cancelled while not running' where it had not started, else at "
         "its child's end", ("R10.1", "R10.3", "R8.2"), needs="child", divergences=("D31",)),
    Case("action.cancel_waiting", "an action-level cancel of a CANCEL that waits for the child's end is "
         "accepted and answers it canceled 'cancelled while not running'; the child's cancellation goes "
         "on, its NEXT answered at the early end", ("R10.2", "R10.1", "R8.2"), needs="child"),
    Case("action.cancel_running", "an action-level cancel of the running NEXT is accepted and the NEXT "
         "answered canceled", ("R10.3", "R8.2"), needs="child", divergences=("D31",)),
    Case("action.cancel_answered", "an action-level cancel of an answered goal is refused", ("R10.5",),
         needs="child"),
    # the task interrupted (a task input: no trace record says so, and the judge cannot tell a child that
    # started from one deferred: what it finds in their records is in its own section)
    Case("interrupt.deferred_start", "while the task is interrupted, a NEXT's child waits (feedback "
         "queued); the resume starts it", ("R14.2", "R6.3", "R14.5", "R14.3"), needs="child",
         trace_shows_failure=False, interrupts=True),
    Case("interrupt.cancel_deferred", "a CANCEL of a child the interruption deferred answers it and its "
         "NEXT at once, canceled", ("R9.4", "R8.2", "R8.3"), needs="child", trace_shows_failure=False,
         interrupts=True),
    Case("interrupt.action_cancel_deferred", "an action-level cancel of a NEXT whose child the "
         "interruption deferred answers it at once, canceled", ("R10.4", "R8.2"), needs="child",
         trace_shows_failure=False, interrupts=True),
    Case("finished.ends_the_run", "FINISHED ends the run: succeeded, completed, then INACTIVE",
         ("R11.1", "R11.2", "R2.2", "R4.16")),
    # right after a run's end, before the next run begins (the query is no trace record)
    Case("describe.after_the_run", "between a run's end and the next run's begin, the description query "
         "answers not running, every field empty", ("R16.1",), needs="status", trace_shows_failure=False),
    Case("finished.next_after", "a NEXT after the run ended is refused", ("R4.3",), needs="place"),
    Case("finished.cancel_after", "a CANCEL after the run ended is refused", ("R4.3",), needs="status"),
    Case("finished.finished_after", "a FINISHED after the run ended is refused", ("R4.3",), needs="status"),
    Case("begin.seq_wrap", "after run 4294967295 the next run is run 0, and a goal for 4294967295 is "
         "refused", ("R3.2", "R3.1", "R4.2")),
)  # fmt: skip


#: What a trace of the exchange cannot carry, for which a case's own script fails it beside the judge
#: (every other failure is the judge's finding on the case's records, :func:`judge_verdicts`):
#: docs/probe.md lists them.  tests/conformance/probe/test_probe_cases.py holds the runner to them.
UNTRACEABLE: dict[str, str] = {
    "timeout": "a message that did not come within --timeout, where the trace does not show it owed: "
    "the spec sets no time within which a server sends anything, so the judge finds a message missing "
    "only where the trace ends without it, and only what the machine owes by then: an answer a step "
    "owed (R19.1's answer_missing), and, where the probe heard the server out (the trace's end record, "
    "written within the deadline over a link that showed no loss or lateness), a response to a request "
    "(response_missing) and the answer a queued goal's start owes; a case that waited in vain for one "
    "of those fails with the judge's finding.  What no step owes by a time, "
    "a child's end (the robot's) and the status or feedback it brings, and a status or begin, which the "
    "next one may take the place of on its topic (each keeps one message), is the probe's own bound (a "
    "case whose message came after it is not run, saying so)",
    "transport": "how the transport offers a topic, and what a subscription made late received: a trace "
    "records the messages of one subscription, not how topics are offered",
    "configuration": "which categories, and which descriptions, the server takes: its configuration, "
    "which a trace taken at a client lacks, so that the judge cannot tell a refused NEXT from one a "
    "configuration refuses",
    "query": "the description query's answer (R16): a service call, of which a trace holds no record",
    "interrupt": "whether the robot's task was interrupted (R14): a task input, of which a trace holds no "
    "record, so that the judge cannot tell a child started from one whose start the interruption "
    "deferred (R6.3); the case interrupted it, and fails a NEXT's first feedback other than queued",
    "start": "when the server started a goal it had accepted (the transport's handle_accepted moment, "
    "R5: no message marks it): a second CANCEL, accepted while the child ran, that is answered idle "
    "(R9.1) may have started after the child's end, where the probe sent it with the first and heard "
    "both accepted before the end; and a CANCEL cancelled at the action level after the link handed it "
    "over leaves the child's cancellation going on (R10.2), where one cancelled before its start "
    "lets the child run on (R10.1), the same answers on the wire",
    "robot": "what the server asked of its robot (an effect for the adapter, such as stopping the child "
    "a CANCEL names, R9.3): a trace shows how the child ended, and a child that ends completed after a "
    "CANCEL may have ended before its robot was told",
    "status_after_end": "a status that still shows the child RUNNING, with its final status, after its "
    "answer (D2): a report of the child may carry any status (R7.1), and a trace taken at a client "
    "cannot tell such a status published after the child's end from one a report published before it "
    "that came late, where the probe asks for the status once it has heard the answer",
    "both_answered": "when a CANCEL's request reached the server, at a client's tap (the DDS link): "
    "a CANCEL of the running child refused before the client heard that child end may have reached "
    "the server after the end (a lossy link sends a lost request again, late), and the judge reads it "
    "so; the case reads the refusal against the order it heard the server's messages in and the "
    "server's stamps (DDS's source timestamps, which a trace does not hold), and is not run over a "
    "link that shows it lost messages.  Over the in-process and driver links, whose records are in "
    "the server's order, the judge decides (R4.16)",
    "log_seq": "whether a client's link lost a feedback on the way: at a client's tap (the DDS link) a "
    "log seq that skips within a child is not told from a feedback lost, and the judge reads it as an "
    "open item (`skips_or_lost`); the case fails it where the run showed no loss, and is not run where "
    "it did.  The in-process and driver links hear every feedback the server sends: there the judge "
    "decides (`skips`)",
}


def causes_text() -> str:
    """The causes a case's script fails a case for, as docs/probe.md lists them: those of
    :data:`UNTRACEABLE`, a Markdown item each."""
    lines = ["What a trace cannot carry:", ""]
    lines += [f"- `{name}`: {why}." for name, why in UNTRACEABLE.items()]
    return "\n".join(lines) + "\n"


_TASK_INPUT = "the input comes from the task or the robot (a {what}), never from a client: no probe sends it"
_NOTICE = "the output is a notice to the adapter ({what}), never on the wire: no client sees it missing"
_HOLD = "stubbornness is the robot's hold in traffic ({what}), the fleet adapter's, never on the wire"

#: The checks of the machine (docs/conformance.md's table of completeness) that no case catches when
#: switched off, each with why a live exchange cannot show it.  A reason that starts ``not yet:`` is
#: a gap of the probe's links, which a case could close; tests/conformance/test_completeness.py fails
#: for a check that is neither caught nor listed here, and for one listed here that a case catches.
LIVE_CANNOT_SHOW: dict[str, str] = {
    "R3.2": _NOTICE.format(what="SeqWrapped; the wrap itself is begin.seq_wrap's"),
    "R3.4": _TASK_INPUT.format(what="begin while a run is active"),
    "R4.1": _TASK_INPUT.format(what="shutdown, before which every goal is refused"),
    "R4.8": "the description limit is the server's configuration, which a client does not know",
    "R4.15": "a binding answers every goal request: one the machine neither accepts nor refuses is refused",
    "R5.1": "moving an accepted goal to executing is the binding's, seen by no client of the protocol",
    "R5.3": "a submitted goal (request and start in one step) is a binding's choice, not a client's",
    "R6.1": "a server's configuration does not change between a goal's acceptance and its start in a live "
    "exchange a client drives",
    "R7.1": "a child need not report progress: a server whose children never report shows the same exchange",
    "R7.2": _NOTICE.format(what="Log; the entry still reaches the feedback"),
    "R11.2": _NOTICE.format(what="DynamicEventFinished: the task moves on, and what next is the task's"),
    "R12.1": _HOLD.format(what="StubbornBegin"),
    "R12.4": _HOLD.format(what="StubbornHold, StubbornDelay"),
    "R12.5": _HOLD.format(what="StubbornEnd"),
    "R13.1": _TASK_INPUT.format(what="task cancel or kill"),
    "R13.2": _TASK_INPUT.format(what="task cancel or kill"),
    "R13.3": _TASK_INPUT.format(what="task cancel or kill"),
    "R13.4": _TASK_INPUT.format(what="task cancel or kill"),
    "R14.1": _NOTICE.format(what="InterruptChild: the child's interruption is the robot's"),
    "R14.2": _NOTICE.format(
        what="InterruptConfirmed; the deferred start is R6.3's, which the interrupt cases show"
    ),
    "R14.4": _NOTICE.format(what="ResumeChild: the child's resumption is the robot's"),
    "R15.1": _TASK_INPUT.format(what="shutdown"),
    "R15.2": _TASK_INPUT.format(what="shutdown"),
    "R16.2": "a server need not offer the description query (D17): one that gives no answer reads as one "
    "that offers none (info)",
    "R17.1": "rmf_ros2 mode reproduces rmf_ros2's divergences (docs/divergences.md): a server that checks "
    "what R17.1 leaves out follows the spec, which is no failure",
    "R17.5": "rmf_ros2 mode's status on every report is a divergence: a server without it follows the spec",
    "R17.7": "rmf_ros2 mode's feedback at a child's end diverges: a server without it follows the spec",
    "R18.1": _TASK_INPUT.format(what="shutdown, after which inputs are ignored"),
    "R18.2": "a transport gives no two goals one UUID, and an ignored input changes nothing a client sees",
    "R18.3": "an ignored input changes nothing a client sees: the Ignored output is the adapter's notice",
    "R18.4": "an ignored input changes nothing a client sees: the Ignored output is the adapter's notice",
    "R18.5": _TASK_INPUT.format(what="task signal or interruption while no run is active"),
    "R18.6": _TASK_INPUT.format(what="repeated interruption or resume"),
    "R18.7": _TASK_INPUT.format(what="repeated task signal"),
    "R18.8": _TASK_INPUT.format(what="drawn id, under id policy goal"),
    "R21.1": _TASK_INPUT.format(what="restart of the server's process"),
    "R21.2": _TASK_INPUT.format(what="restart of the server's process"),
    "R21.3": _TASK_INPUT.format(what="restart of the server's process"),
}

#: The divergences a ``--known`` name covers: every one docs/divergences.md records is rmf_ros2's.
KNOWN: dict[str, frozenset[str]] = {"rmf_ros2": frozenset(d for case in CASES for d in case.divergences)}

#: The cases a ``--known`` name expects to be missing, each with why: a fleet adapter reaches the seq
#: wrap only after four billion dynamic events; rmf_ros2 answers a CANCEL as soon as it has told the
#: child to stop (D1), so that no CANCEL waits for an action-level cancel to find (the lab, 2026-11-29).
KNOWN_MISSING: dict[str, frozenset[str]] = {
    "rmf_ros2": frozenset({"begin.seq_wrap", "action.cancel_waiting"})
}

#: The exit statuses of ``dynevent probe`` (docs/probe.md has the table).
EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_NOT_RUN = 0, 1, 2, 3


def place_of_run(description: str) -> str | None:
    """The place a run's description names for the robot, for the cases that send it somewhere: the
    first waypoint (by name) of a ``go_to_place`` estimate, as a task's dynamic event carries it
    (``{"estimate": {"category": "go_to_place", "description": ...}}``); None when it names none."""
    try:
        estimate = json.loads(description).get("estimate")
        if not isinstance(estimate, dict) or estimate.get("category") != "go_to_place":
            return None
        reading = read("go_to_place", estimate.get("description"))
    except (ValueError, AttributeError, DyneventError):
        return None
    assert isinstance(reading, GoToPlace)  # what read gives for go_to_place
    names = [place.waypoint for place in reading.one_of if isinstance(place.waypoint, str)]
    return names[0] if names else None


def select(patterns: Iterable[str] = ()) -> list[Case]:
    """The cases any pattern names (all when none): a case id or glob (``request.*``), a section
    (``cancel``), or a rule or rule glob (``R4.*``, ``R9.3``)."""
    wanted = list(patterns)
    if not wanted:
        return list(CASES)
    return [case for case in CASES if matches(case, wanted)]


def format_list(cases: Sequence[Case]) -> str:
    """The cases, a line each: id, rules, what it checks."""
    width = max((len(case.id) for case in cases), default=0)
    lines = [f"{case.id:{width}}  {case.title} ({', '.join(case.rules)})" for case in cases]
    return "\n".join([*lines, f"{len(cases)} case(s)"]) + "\n"


def _label(finding: CaseFinding) -> str:
    if finding.verdict is Verdict.MISSING and finding.expected_missing:
        return "missing (allowed)"
    if finding.verdict is Verdict.FAIL and finding.known:
        return f"known ({finding.divergence})"
    if finding.verdict is Verdict.FAIL and finding.divergence:
        return f"fail ({finding.divergence})"
    return finding.verdict.value


def format_findings(findings: Sequence[CaseFinding], judged: Sequence[Judged] = ()) -> str:
    """A line per case, the account of every failure, what the judge found beside the cases, and the
    counts."""
    width = max((len(finding.case.id) for finding in findings), default=0)
    opening = not_run_summary(findings)
    lines = [opening, ""] if opening else []
    lines += [
        f"{finding.case.id:{width}}  {_label(finding):14}  {finding.case.title}" for finding in findings
    ]
    for finding in findings:
        if finding.verdict in (Verdict.FAIL, Verdict.MISSING):
            lines.append("")
            lines.append(f"{finding.case.id} ({', '.join(finding.case.rules)}): {_label(finding)}")
            if finding.verdict is Verdict.MISSING:
                lines.append(f"  not run:  {finding.seen}")
            else:
                lines.append(f"  expected: {finding.expected}")
                lines.append(f"  seen:     {finding.seen}")
            lines.extend(f"  | {message}" for message in finding.messages)
    if judged:
        lines += ["", f"the judge, over every record of the exchange: {judged_summary(judged)}"]
        lines.extend(f"  {item.line()}" for item in judged)
    lines.append("")
    lines.append(probe_summary(findings))
    return "\n".join(lines) + "\n"


def judged_summary(judged: Sequence[Judged]) -> str:
    """``3 findings (1 known, 2 uncertain)``: what the judge found beside the cases."""
    known = sum(1 for item in judged if item.known)
    uncertain = sum(1 for item in judged if item.uncertain and not item.known)
    parts = [f"{known} known"] if known else []
    parts += [f"{uncertain} uncertain"] if uncertain else []
    return f"{len(judged)} finding(s)" + (f" ({', '.join(parts)})" if parts else "")


def exit_status(findings: Sequence[CaseFinding], judged: Sequence[Judged] = ()) -> int:
    """1 when a case failed or the judge found what no case did (a known divergence, or an uncertain
    finding, does not count); else 3 when a case was not run (missing) that no ``--allow-missing`` or
    ``--known`` expected; else 0.  A conformance run never passes what it did not test."""
    if any(finding.verdict is Verdict.FAIL and not finding.known for finding in findings):
        return EXIT_FAILED
    if any(item.counts for item in judged):
        return EXIT_FAILED
    if any(finding.verdict is Verdict.MISSING and not finding.expected_missing for finding in findings):
        return EXIT_NOT_RUN
    return EXIT_OK


def matches(case: Case, patterns: Iterable[str]) -> bool:
    """Does any pattern name ``case``: its id or a glob of it, its section, or one of its rules?"""
    names = (case.id, case.section, *case.rules)
    return any(fnmatch.fnmatchcase(name, pattern) for pattern in patterns for name in names)


def not_run_summary(findings: Sequence[CaseFinding]) -> str | None:
    """The line that opens a report when cases were not run: how many, and why, most frequent first;
    None when every case ran."""
    missing = [finding for finding in findings if finding.verdict is Verdict.MISSING]
    if not missing:
        return None
    reasons: dict[str, int] = {}
    for finding in missing:
        reasons[finding.seen] = reasons.get(finding.seen, 0) + 1
    why = "; ".join(
        f"{reason} ({count})" for reason, count in sorted(reasons.items(), key=lambda item: -item[1])
    )
    expected = sum(1 for finding in missing if finding.expected_missing)
    allowed = f", {expected} of them expected" if expected else ""
    return f"{len(missing)} of {len(findings)} case(s) not run{allowed}: {why}"


def junit_xml(findings: Sequence[CaseFinding], server: str = "", judged: Sequence[Judged] = ()) -> str:
    """The run as JUnit XML: a test case per probe case (``classname`` its section), a failure with
    the account, a skip for a missing case; each case's rules as a property.  What the judge found
    beside the cases is a second test suite, a test case per finding (``classname`` ``judge``)."""
    failures = sum(1 for finding in findings if finding.verdict is Verdict.FAIL and not finding.known)
    skipped = sum(1 for finding in findings if finding.verdict is Verdict.MISSING)
    suites = ET.Element("testsuites", name="dynevent probe", tests=str(len(findings)))
    suite = ET.SubElement(
        suites, "testsuite", name=server or "dynevent probe", tests=str(len(findings)),
        failures=str(failures), skipped=str(skipped),
    )  # fmt: skip
    for finding in findings:
        test = ET.SubElement(
            suite,
            "testcase",
            classname=finding.case.section,
            name=finding.case.id,
            time=f"{finding.seconds:.3f}",
        )
        properties = ET.SubElement(test, "properties")
        ET.SubElement(properties, "property", name="rules", value=" ".join(finding.case.rules))
        ET.SubElement(properties, "property", name="verdict", value=_label(finding))
        if finding.absent:
            ET.SubElement(properties, "property", name="absent", value="a message did not come in time")
        account = "\n".join([f"expected: {finding.expected}", f"seen: {finding.seen}", *finding.messages])
        if finding.verdict is Verdict.FAIL and not finding.known:
            ET.SubElement(test, "failure", message=f"{_label(finding)}: {finding.seen}").text = account
        elif finding.verdict is Verdict.MISSING:
            ET.SubElement(test, "skipped", message=finding.seen)
        elif finding.known:
            ET.SubElement(test, "system-out").text = f"known divergence {finding.divergence}\n{account}"
    if judged:
        counted = sum(1 for item in judged if item.counts)
        beside = ET.SubElement(
            suites, "testsuite", name="the judge, over every record", tests=str(len(judged)),
            failures=str(counted), skipped="0",
        )  # fmt: skip
        for item in judged:
            name = f"{item.finding.rule} {item.finding.code} (line {item.finding.line})"
            test = ET.SubElement(beside, "testcase", classname="judge", name=name)
            if item.counts:
                ET.SubElement(test, "failure", message=item.line(), type=item.finding.code)
            else:
                ET.SubElement(test, "system-out").text = item.line()
    return xml_document(suites)


def probe_summary(findings: Sequence[CaseFinding]) -> str:
    """The counts line: ``15 pass, 2 fail (2 of the failures known)``."""
    counts = {verdict: 0 for verdict in Verdict}
    for finding in findings:
        counts[finding.verdict] += 1
    known = sum(1 for finding in findings if finding.known)
    summary = ", ".join(f"{count} {verdict.value}" for verdict, count in counts.items() if count)
    return summary + (f" ({known} of the failures known)" if known else "")


def report(
    findings: Sequence[CaseFinding], server: str, *, html_form: bool = False, judged: Sequence[Judged] = ()
) -> str:
    """A report a person reads: a table of the cases, then per case its rules, verdict, what the spec
    expects, what was seen and every message sent and seen, then what the judge found beside the
    cases.  Markdown, or a self-contained HTML page."""
    title = f"dynevent probe: {server}"
    rows = [
        (finding.case.id, _label(finding), ", ".join(finding.case.rules), finding.case.title)
        for finding in findings
    ]
    if html_form:  # a page that parses, whatever a server said
        return xml_safe(_report_html(title, rows, findings, judged))
    opening = not_run_summary(findings)
    lines = [
        f"# {title}",
        "",
        *([opening, ""] if opening else []),
        probe_summary(findings),
        "",
        "| case | verdict | rules | checks |",
        "|---|---|---|---|",
    ]
    lines.extend(f"| `{case}` | {label} | {rules} | {_cell(text)} |" for case, label, rules, text in rows)
    for finding in findings:
        lines += ["", f"## `{finding.case.id}`: {_label(finding)}", "", finding.case.title + ".", ""]
        lines.extend(f"- {name}: {_cell(value)}" for name, value in _facts(finding))
        if finding.messages:
            lines += ["", "```", *finding.messages, "```"]
    if judged:
        lines += ["", f"## The judge, over every record: {judged_summary(judged)}", ""]
        lines.extend(f"- {_cell(item.line())}" for item in judged)
    return "\n".join(lines) + "\n"


def _facts(finding: CaseFinding) -> list[tuple[str, str]]:
    """What a report says of a case, in order: its rules, divergence, expected, seen and time."""
    facts = [("rules", f"{', '.join(finding.case.rules)} (docs/spec.md)")]
    if finding.divergence:
        facts.append(("divergence", f"{finding.divergence} (docs/divergences.md)"))
    if finding.verdict is Verdict.MISSING:
        facts.append(("not run", finding.seen or "-"))
    else:
        seen = "as expected" if finding.verdict is Verdict.PASS else finding.seen or "-"
        facts += [("expected", finding.expected or "-"), ("seen", seen)]
    return [*facts, ("time", f"{finding.seconds:.3f} s")]


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


_STYLE = (
    "body{font-family:sans-serif;margin:2em;max-width:70em}table{border-collapse:collapse}"
    "td,th{border:1px solid #ccc;padding:.3em .6em;text-align:left}pre{background:#f6f6f6;padding:.6em}"
    ".pass{background:#dfd}.fail{background:#fdd}.known{background:#ffd}.missing,.info{background:#eef}"
)


def _report_html(
    title: str,
    rows: list[tuple[str, str, str, str]],
    findings: Sequence[CaseFinding],
    judged: Sequence[Judged],
) -> str:
    escape = html.escape
    parts = [
        "<!DOCTYPE html>",
        f'<html lang="en"><head><meta charset="utf-8"><title>{escape(title)}</title>'
        f"<style>{_STYLE}</style></head><body>",
        f"<h1>{escape(title)}</h1>",
        *([f"<p><strong>{escape(opening)}</strong></p>"] if (opening := not_run_summary(findings)) else []),
        f"<p>{escape(probe_summary(findings))}</p>",
        "<table><tr><th>case</th><th>verdict</th><th>rules</th><th>checks</th></tr>",
    ]
    for case, label, rules, text in rows:
        css = label.split(" ", 1)[0]
        parts.append(
            f'<tr class="{escape(css)}"><td><a href="#{escape(case)}">{escape(case)}</a></td>'
            f"<td>{escape(label)}</td><td>{escape(rules)}</td><td>{escape(text)}</td></tr>"
        )
    parts.append("</table>")
    for finding in findings:
        parts.append(
            f'<h2 id="{escape(finding.case.id)}">{escape(finding.case.id)}: {escape(_label(finding))}</h2>'
        )
        parts.append(f"<p>{escape(finding.case.title)}.</p><ul>")
        parts.extend(f"<li>{name}: {escape(value)}</li>" for name, value in _facts(finding))
        parts.append("</ul>")
        if finding.messages:
            parts.append(f"<pre>{escape(chr(10).join(finding.messages))}</pre>")
    if judged:
        parts.append(
            f'<h2 id="judge">The judge, over every record: {escape(judged_summary(judged))}</h2><ul>'
        )
        parts.extend(f"<li>{escape(item.line())}</li>" for item in judged)
        parts.append("</ul>")
    parts.append("</body></html>")
    return "\n".join(parts) + "\n"
