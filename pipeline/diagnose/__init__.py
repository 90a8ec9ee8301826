"""Diagnose: find where simulation and measurement disagree and name the missing effect.

:func:`diagnose` (:mod:`pipeline.diagnose.workflow`) on :class:`ConfigurationData` with
:class:`DiagnoseSettings` (:mod:`pipeline.diagnose.preflight`) returns a :class:`DiagnoseResult` (:mod:`pipeline.diagnose.result`);
the candidate effects (:data:`KINDS`) are in :mod:`pipeline.diagnose.effects`.
"""
from pipeline.diagnose.effects import KINDS
from pipeline.diagnose.preflight import ConfigurationData, DiagnoseSettings, preflight
from pipeline.diagnose.result import DiagnoseResult
from pipeline.diagnose.workflow import diagnose

__all__ = ["diagnose", "preflight", "DiagnoseSettings", "ConfigurationData", "DiagnoseResult",
           "KINDS"]
