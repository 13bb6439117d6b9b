"""dynevent: the sans-IO reference implementation of the Open-RMF Dynamic Event protocol."""

from __future__ import annotations

__version__ = "0.1.0.dev0"
