"""Shared test configuration: hypothesis profiles.

``ci`` (the default) keeps ``bash .ci/run`` well under ten minutes on two
cores; ``deep`` runs many more and longer examples.  Choose with the
``DYNEVENT_HYPOTHESIS_PROFILE`` environment variable.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci",
    max_examples=100,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    print_blob=True,
)
settings.register_profile(
    "deep",
    max_examples=5_000,
    deadline=None,
    stateful_step_count=200,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
    print_blob=True,
)
settings.register_profile("dev", max_examples=20, deadline=None)
settings.load_profile(os.environ.get("DYNEVENT_HYPOTHESIS_PROFILE", "ci"))
