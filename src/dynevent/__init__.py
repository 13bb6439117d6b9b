"""dynevent: the sans-IO reference implementation of the Open-RMF Dynamic Event protocol."""

from __future__ import annotations

__version__ = "0.1.0.dev0"

#: Where the project lives; the documentation is under ``docs/`` there.
HOME = "https://github.com/dynevent/dynevent"
#: The documentation, as the command line's help points at it.
DOCS = HOME + "/blob/main/docs"
