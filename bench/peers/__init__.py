"""Peer implementations of the Dynamic Event server rules that the benchmark workloads exercise.

All three share :mod:`bench.peers.rules` (the decisions, input checks and whole
outputs, written once in plain Python over a data tuple) and differ in what
holds the phase: nothing but the data (:mod:`.tuples`, the same-outputs floor),
a ``transitions`` machine (:mod:`.with_transitions`) or a
``python-statemachine`` machine (:mod:`.with_statemachine`).  Their outputs are
the tuples :func:`bench.peers.script.plain` writes dynevent's outputs as, so
``tests/project/test_bench_peers.py`` compares them whole.
"""
