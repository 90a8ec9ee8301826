"""Diagnose: find where simulation and measurement disagree and name the missing effect.

:func:`diagnose` (:mod:`pipeline.diagnose.workflow`) on :class:`ConfigurationData` with
:class:`DiagnoseSettings` returns a :class:`DiagnoseResult` (:mod:`pipeline.diagnose.result`);
the candidate effects (:data:`KINDS`) are in :mod:`pipeline.diagnose.effects`.
"""
from pipeline.diagnose.effects import KINDS
from pipeline.diagnose.result import DiagnoseResult
from pipeline.diagnose.workflow import ConfigurationData, DiagnoseSettings, diagnose, preflight

__all__ = ["diagnose", "preflight", "DiagnoseSettings", "ConfigurationData", "DiagnoseResult",
           "KINDS"]
