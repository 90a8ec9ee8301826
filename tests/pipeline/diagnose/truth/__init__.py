"""Truth generator of the diagnose blind study (issue 14): hidden effects in synthetic test data.

Never imported by ``pipeline/``, and never importing ``pipeline.diagnose`` (only ``study.py``
runs the workflow, through its public names): the truth effects are built this package's own
way (``effects.py``), richer than the workflow's library.

``make_case(structure, kind, seed, out) -> Path`` writes a case (``generate.py``) for
``STRUCTURES`` = ("x56": the shipped example, "frame": a glider-like frame, ``frame.py``) and
``TRUTH_KINDS`` = the library's kinds + ("none", "outside").
"""
from .generate import KINDS, STRUCTURES, TRUTH_KINDS, make_case

__all__ = ["KINDS", "STRUCTURES", "TRUTH_KINDS", "make_case"]
