"""``python -m dynevent.conformance.driver``: the reference driver's path in 0.1.0, kept for the
scripts of implementations that run it there.  The driver lives with the vectors now
(:mod:`dynevent.conformance.vectors.driver`); this runs it."""

from __future__ import annotations

from dynevent.conformance.vectors.driver import main

__all__ = ["main"]

if __name__ == "__main__":
    raise SystemExit(main())
