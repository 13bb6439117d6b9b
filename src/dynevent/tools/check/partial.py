"""Moved to :mod:`dynevent.conformance.judge.partial`.

This name keeps working, with a DeprecationWarning, for one release.
"""

from dynevent._moved import moved_module

moved_module(__name__)
