"""Benchmarks of dynevent against peer implementations of the same rules (see bench/run.py)."""
