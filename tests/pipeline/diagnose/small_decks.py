"""Small decks and helpers shared by the tests of the candidate-effect library and of adding an
effect to a model (test_effects, test_apply, test_apply_decks)."""
from pathlib import Path

import numpy as np

from structures.bulk_text import card
from structures.modal import compute_modes

X56 = Path(__file__).resolve().parents[3] / "data" / "x56_like" / "x56_efew.bdf"


def small_deck(tmp_path, name, cards, params=()):
    """A SOL 103 deck of the given cards (tuples for :func:`structures.bulk_text.card`) and
    PARAM lines, written to ``tmp_path / name``."""
    text = "SOL 103\nCEND\nBEGIN BULK\n" + "".join(p + "\n" for p in params)
    text += "\n".join(card(*c) for c in cards) + "\nENDDATA\n"
    path = tmp_path / name
    path.write_text(text)
    return path


def elastic(model, n):
    """Elastic frequencies [Hz] among the model's n lowest modes."""
    ds = compute_modes(model, n)
    f = ds["frequency"].values
    return f[ds["rigid_motion"].values == ""]


def pick(cands, kind, label_part=""):
    """The first candidate of ``kind`` whose label contains ``label_part``."""
    return next(c for c in cands if c.kind == kind and label_part in c.label)


def quadratic_frequencies(k, m):
    """Frequencies [Hz] of a 2-DOF system by the closed-form roots of det(K - lam M) = 0."""
    a = m[0] * m[1]
    b = -(k[0][0] * m[1] + k[1][1] * m[0])
    c = k[0][0] * k[1][1] - k[0][1] ** 2
    disc = np.sqrt(b * b - 4 * a * c)
    lam = np.array([(-b - disc) / (2 * a), (-b + disc) / (2 * a)])
    return np.sqrt(np.clip(lam, 0, None)) / (2 * np.pi)


def hinge_deck(tmp_path, m2, m3, i3):
    """Clamped grid 1 carrying grids 2 (x = 0.3, mass m2) and 3 (coincident with 1, mass m3,
    inertia i3) on RBE2 10; a bar 1-4 (clamped at 4) gives k_ref."""
    return small_deck(tmp_path, "hinge.bdf", [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, None, 0.3, 0.0, 0.0),
        ("GRID", 3, None, 0.0, 0.0, 0.0), ("GRID", 4, None, 0.0, 1.0, 0.0, None, 123456),
        ("RBE2", 10, 1, 123456, 2, 3), ("CONM2", 21, 2, None, m2),
        ("CONM2", 22, 3, None, m3, 0.0, 0.0, 0.0, None, i3, 0.0, i3, 0.0, 0.0, i3),
        ("CBAR", 31, 41, 1, 4, 0.0, 0.0, 1.0), ("PBAR", 41, 51, 1e-3, 2e-7, 4e-7, 3e-7),
        ("MAT1", 51, 7.0e10, None, 0.33)])
