"""Peer implementations of the Dynamic Event server rules that the benchmark workloads exercise.

All three share :mod:`bench.peers.rules` (the decisions, written once in plain
Python) and differ in what holds the phase: plain attributes (:mod:`.floor`),
a ``transitions`` machine (:mod:`.with_transitions`) or a
``python-statemachine`` machine (:mod:`.with_statemachine`).  They speak the
common form of :mod:`bench.peers.script`, into which dynevent's outputs are
also translated, so that ``tests/project/test_bench_peers.py`` can check that every
peer decides as dynevent does.
"""
