"""``python -m dynevent``: the same as the ``dynevent`` command."""

from __future__ import annotations

import sys

from dynevent.tools.cli import main

sys.exit(main())
