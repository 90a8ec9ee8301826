"""Truth generator of the diagnose blind study (issue 14): hidden effects in synthetic test data.

Never imported by ``pipeline/``, and never importing ``pipeline.diagnose`` (only ``study.py``
runs the workflow, through its public names): the truth effects are built this package's own
way (``effects.py``), richer than the workflow's library.

``make_case(structure, kind, seed, out) -> Path`` writes a case (``generate.py``) for
``STRUCTURES`` = ("x56": the shipped example, "frame": a glider-like frame, ``frame.py``,
"wingbox": the public Goland wing box whose truth MYSTRAN solves, ``wingbox.py``, "windy":
the public WINDY wind-tunnel wing, a stick model, ``windy.py``) and
``TRUTH_KINDS`` = the library's kinds + ("none", "outside") (``STRUCTURE_KINDS``: those each
structure can hold).
"""
from .generate import KINDS, STRUCTURE_KINDS, STRUCTURES, TRUTH_KINDS, make_case

__all__ = ["KINDS", "STRUCTURE_KINDS", "STRUCTURES", "TRUTH_KINDS", "make_case"]
