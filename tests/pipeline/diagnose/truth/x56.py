"""The shipped X-56A-class example as a blind-study structure.

The analysis decks are the shipped model's (``data/x56_like/make_model.py``, ``ANALYSIS``), both
configurations (EFEW, FFFW); the sensors are the shipped GVT's (``make_truth.sensors()``, 120
translations); the truth starts from the structure and tank cards alone (no aerodynamics: the
GVT does not need them). The shipped folder is read, never written.
"""
from __future__ import annotations

import sys
from pathlib import Path

from structures.bulk_text import card

TRUTH_DIR = Path(__file__).resolve().parents[4] / "data" / "x56_like" / "truth"
sys.path.insert(0, str(TRUTH_DIR))

import make_truth  # noqa: E402  (puts data/x56_like on sys.path)
import make_model  # noqa: E402

UNITS = make_truth.UNITS
N_TEST = make_truth.N_TEST
CONFIGURATIONS = make_model.CONFIGURATIONS
measured_mass = make_truth.measured_mass


def sensors() -> list[tuple[int, int]]:
    """The shipped GVT's 120 translations (analysis grid, component 1..3)."""
    return [(g, c) for g, c, _ in make_truth.sensors()]


def write_analysis(folder: Path) -> dict[str, Path]:
    """The analysis decks (with their includes) in ``folder``: {configuration: deck}."""
    written = make_model.write_model(folder, make_model.ANALYSIS)
    return {c: written[f"x56_{c}.bdf"] for c in CONFIGURATIONS}


def write_structure(folder: Path, configuration: str) -> Path:
    """A structure-and-masses-only deck of a configuration (the truth's starting point)."""
    params = make_model.ANALYSIS
    lines = ["SOL 103", "CEND", "METHOD = 1", "BEGIN BULK", *make_model.structure_bulk(params),
             *make_model.masses_bulk(params, configuration),
             card("EIGRL", 1, None, None, 6 + N_TEST + 8), "ENDDATA"]
    path = Path(folder) / f"structure_{configuration}.bdf"
    path.write_bytes(("\n".join(lines) + "\n").encode("ascii"))
    return path
