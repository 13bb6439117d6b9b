"""Conformance: the vectors (the JSON files beside this module), their runner and the driver protocol.

:mod:`~dynevent.conformance.vectors` loads and runs the vectors against dynevent or any
implementation speaking :mod:`~dynevent.conformance.driver`'s protocol (its parts:
:mod:`~dynevent.conformance.files`, :mod:`~dynevent.conformance.diff`,
:mod:`~dynevent.conformance.runner`, :mod:`~dynevent.conformance.report`);
:mod:`~dynevent.conformance.records` reads and writes the JSON records they share with traces.
"""
