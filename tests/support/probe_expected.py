"""What the probe's cases find against ``dynevent serve`` and its deliberately broken variants: the
same over DDS (tests/ros/test_ros_probe.py) and in process (tests/conformance/probe/test_probe_in_process.py).
Not a test module."""

from __future__ import annotations

#: What the rmf_ros2 mode of serve reproduces of rmf_ros2, case by case: the D-number the probe names.
RMF_ROS2_FAILS = {
    "request.event_type_0": "D7",
    "request.event_type_unknown": "D7",
    "request.cancel_idle": "D8",
    "next.id_zero": "D10",
    "next.id_chosen": "D10",
    "next.stateless_id": "D10",
    "next.id_stale": "D10",
    "next.status_after_child": "D2",
    "cancel.wrong_id": "D8",
    "cancel.running_child": "D28",
}

#: The cases rmf_ros2 mode leaves ``info``: it offers no description service (D17), which the spec leaves
#: open.
RMF_ROS2_INFO = ("describe.query", "describe.after_child", "describe.after_the_run")


#: Each deliberately broken server (dynevent.testing.broken) and the cases that must catch it.
BROKEN = {
    # a goal for the run before the wrap is stale too
    "accepts_stale_seq": {
        "request.seq_stale": "fail", "request.seq_future": "fail", "request.seq_stale_next": "fail",
        "request.seq_future_next": "fail", "cancel.seq_stale": "fail", "cancel.seq_future": "fail",
        "begin.seq_wrap": "fail",
    },
    # a server that checks the seq of a FINISHED only would pass every case but these
    "accepts_stale_next": {"request.seq_stale_next": "fail", "request.seq_future_next": "fail"},
    "accepts_stale_cancel": {"cancel.seq_stale": "fail", "cancel.seq_future": "fail"},
    "accepts_cancel_after_the_run": {"finished.cancel_after": "fail"},
    "accepts_unknown_category": {"request.category_unknown": "fail"},
    # the judge labels what it finds as the divergence rmf_ros2 showed it as: a NEXT accepted while busy
    # as D1, a FINISHED as D30
    "accepts_when_busy": {"next.busy": "fail (D1)", "next.busy_finished": "fail (D30)"},
    # the CANCEL that ends a child after next.busy and cancel.wrong_id goes unanswered too (R19.1)
    "never_answers_cancel": {
        "next.busy": "fail", "next.busy_finished": "fail", "cancel.wrong_id": "fail",
        "cancel.seq_stale": "fail", "cancel.seq_future": "fail", "cancel.running_child": "fail",
        "cancel.both_answered": "fail", "action.cancel_waiting": "fail",
        # in process: the clean-up CANCEL of the child the resume started, and the CANCEL of a deferred one
        "interrupt.deferred_start": "fail", "interrupt.cancel_deferred": "fail",
    },
    # every case that runs a child to its end waits for an answer that never comes (R19.1)
    "hangs_next": {
        "next.runs_a_child": "fail", "next.id_zero": "fail", "next.id_chosen": "fail", "next.race": "fail",
        "stubborn.clamp_notice": "fail", "next.stateless_id": "missing", "next.status_after_child": "missing",
        "feedback.log_seq": "missing", "describe.after_child": "missing", "action.cancel_answered": "missing",
    },
    # R8.4 after a completed child, and after a cancelled one
    "running_after_child": {"next.status_after_child": "fail (D2)", "cancel.running_child": "fail (D2)"},
    # the cases that hold a child's start feedback to its id (R6.4): the judge, whose statuses name the
    # child as its NEXT does, files it under the feedback's rule, not as a child numbered otherwise (D10,
    # R6.2, the rule of the cases that number children), and keeps the child's id for the clean-up's
    # CANCEL of cancel.wrong_id
    "wrong_feedback_id": {"next.runs_a_child": "fail", "next.race": "fail"},
    # the cases after it go by the run the FINISHED ended, its success the run's end (R11.1); the next
    # run begins while finished.ends_the_run waits for the INACTIVE, before the query after the end
    "ignores_finished": {"finished.ends_the_run": "fail", "describe.after_the_run": "missing"},
    "ignores_clamp": {"stubborn.clamp_notice": "fail (D11)"},
    # before any child the run's first id is the current one: describe.query passes
    "query_names_the_first_id": {"describe.after_child": "fail"},
}  # fmt: skip


#: Defects only the cases that interrupt the robot's task catch, which the probe runs over a link that
#: can interrupt it (in process, the driver protocol; over DDS with --interrupt-command and
#: --resume-command, else it leaves them out).
INTERRUPTS_IN_PROCESS = {
    "ignores_interrupt": dict.fromkeys(
        ["interrupt.deferred_start", "interrupt.cancel_deferred", "interrupt.action_cancel_deferred"], "fail"
    ),
}

#: Defects no case looks for, and what the judge over the probe's exchange finds of each.
UNSEEN_BY_CASES = {
    # runs 1, 3, 5: the first run is not the wrap's 4294967295, so the wrap case cannot run
    "skips_seq": ({"begin.seq_wrap": "missing"}, "R3.1 begin_seq"),
}

#: Defects only the in-process probe meets: dynevent serve's binding drops a feedback after its goal's
#: answer (the goal handle is gone), where a server of another make may send it.  No case's script
#: looks for it: the judge over every record finds it in the records of each case that runs a child to
#: its answer, and fails those cases on R19.1.
JUDGED_IN_PROCESS = {
    "feedback_after_answer": dict.fromkeys(
        [
            "next.runs_a_child",
            "next.id_zero",
            "next.id_chosen",
            "next.stateless_id",
            "next.busy",
            "next.busy_finished",
            "next.race",
            "feedback.log_seq",
            "stubborn.clamp_notice",
            "cancel.wrong_id",
            "cancel.seq_stale",
            "cancel.seq_future",
            "cancel.running_child",
            "cancel.both_answered",
            "action.cancel_waiting",
            "action.cancel_running",
            "action.cancel_answered",
        ],
        "fail",
    ),
}
