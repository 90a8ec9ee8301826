"""The shipped X-56A-class example aircraft (data/x56_like): generator, modes, mass properties.

* the generator is deterministic: two fresh interpreters write byte-identical files, and they are
  the committed ones (so the committed decks are what ``make_model.py`` makes);
* both configurations' modes against MYSTRAN on the committed structure and mass bulk data
  (all mass is CONM2, so lumped mass is the deck's mass in both solvers);
* mass properties (weight, CG, inertia about the CG) of both configurations against sums over the
  generator's CONM2 list done here with the parallel-axis theorem (independent of structures/);
* the mode table names the reference paper's kinds of mode;
* the truth-model hooks (tapered curved gear, engine springs, cables, suspension) give a deck that
  our solver reads, with the expected weight and six suspension modes.
"""
from __future__ import annotations

import subprocess
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from structures.bdf import read_model
from structures.bulk_text import card
from structures.massprops import mass_properties
from structures.modal import compute_modes
from test_mystran import needs_mystran, run_mystran

REPO = Path(__file__).resolve().parents[2]
FOLDER = REPO / "data" / "x56_like"
sys.path.insert(0, str(FOLDER))

import make_model as mm  # noqa: E402
from mode_names import classify_modes  # noqa: E402

FILES = ("x56_efew.bdf", "x56_fffw.bdf", "structure_x56.inc", "aero_x56.inc", "masses_efew.inc",
         "masses_fffw.inc", "mode_table.md")


@pytest.fixture(scope="module")
def modes():
    """Our modes of both committed decks (EIGRL ND = 34)."""
    return {c: compute_modes(read_model(FOLDER / f"x56_{c}.bdf")) for c in mm.CONFIGURATIONS}


def test_generator_is_deterministic(tmp_path):
    """Two runs in fresh interpreters (different hash seeds) write the same bytes, equal to the
    committed files."""
    for run, seed in (("a", "1"), ("b", "2")):
        subprocess.run([sys.executable, str(FOLDER / "make_model.py"), str(tmp_path / run)],
                       check=True, capture_output=True, env={"PYTHONHASHSEED": seed})
    for name in FILES:
        first = (tmp_path / "a" / name).read_bytes()
        assert first == (tmp_path / "b" / name).read_bytes(), name
        assert first == (FOLDER / name).read_bytes(), f"{name} differs from the committed file"


def _mystran_deck(folder: Path, configuration: str) -> Path:
    """SOL 103 deck with the committed structure and tank bulk data inlined (MYSTRAN warns on
    INCLUDE), 34 modes, DISP(PLOT) for the OP2."""
    bulk = [(FOLDER / name).read_text() for name in ("structure_x56.inc",
                                                     f"masses_{configuration}.inc")]
    text = ["SOL 103", "CEND", f"TITLE = X56 {configuration.upper()} MODES", "METHOD = 1",
            "DISP(PLOT) = ALL", "BEGIN BULK", *bulk, card("EIGRL", 1, None, None, 34), "ENDDATA"]
    path = folder / f"x56_{configuration}_103.bdf"
    path.write_text("\n".join(text) + "\n")
    return path


@needs_mystran
@pytest.mark.parametrize("configuration", mm.CONFIGURATIONS)
def test_modes_against_mystran(tmp_path, modes, configuration):
    """34 modes (6 rigid + 28 flexible) of each configuration. Measured: ours vs MYSTRAN within
    2.5e-8 on every flexible mode (MYSTRAN's OP2 eigenvalues are float32); asserted 1e-5, far
    inside the issue's 1 %. Rigid modes below 1e-3 Hz in both."""
    theirs = run_mystran(_mystran_deck(tmp_path, configuration))
    ours = np.asarray(modes[configuration]["frequency"].values, dtype=float)
    assert ours.size == theirs.size == 34
    assert np.all(np.abs(ours[:6]) < 1e-3) and np.all(np.abs(theirs[:6]) < 1e-3)
    np.testing.assert_allclose(ours[6:], theirs[6:], rtol=1e-5)


def _hand_sums(configuration: str) -> tuple[float, np.ndarray, np.ndarray]:
    """Weight (lb), CG (in) and inertia about the CG (lb in^2) of the generator's CONM2s."""
    grids = mm._grids(mm.ANALYSIS)
    items = mm.mass_items(mm.ANALYSIS, configuration)
    w = np.array([m.weight for m in items])
    xyz = np.array([np.add(grids[m.grid], m.offset) for m in items])
    cg = w @ xyz / w.sum()
    d = xyz - cg
    inertia = np.zeros((3, 3))
    for wi, di, m in zip(w, d, items):
        inertia += np.diag(m.inertia) + wi * (di @ di * np.eye(3) - np.outer(di, di))
    return float(w.sum()), cg, inertia


@pytest.mark.parametrize("configuration, weight_range", [("efew", (200.0, 250.0)),
                                                         ("fffw", (450.0, 480.0))])
def test_mass_properties_against_hand_sums(configuration, weight_range):
    props = mass_properties(read_model(FOLDER / f"x56_{configuration}.bdf"))
    weight, cg, inertia = _hand_sums(configuration)
    assert weight_range[0] <= weight <= weight_range[1]
    np.testing.assert_allclose(props.mass / mm.WTMASS, weight, rtol=1e-12)
    np.testing.assert_allclose(props.cg, cg, rtol=0, atol=1e-9)
    np.testing.assert_allclose(props.inertia / mm.WTMASS, inertia, rtol=1e-9, atol=1e-6)
    assert abs(cg[1]) < 1e-9                                  # symmetric aircraft


def test_tanks_are_the_only_difference():
    """Both configurations share every card but the tank CONM2s (same ids, other weights)."""
    efew, fffw = (mm.tank_masses(mm.ANALYSIS, c) for c in mm.CONFIGURATIONS)
    assert [m.eid for m in efew] == [m.eid for m in fffw]
    assert sum(m.weight for m in fffw) - sum(m.weight for m in efew) == pytest.approx(
        2 * (30.0 - 1.0) + 6 * (30.0 - 0.5))
    decks = [(FOLDER / f"x56_{c}.bdf").read_text().replace(c, "").replace(c.upper(), "")
             for c in mm.CONFIGURATIONS]
    assert decks[0] == decks[1]


#: Kinds of mode in the reference paper's Table 1 (GVT columns), per configuration, and the ones
#: our model does not have among its 34 modes: the EFEW's antisymmetric second and third bending
#: (its antisymmetric modes above AW1B up to 36 Hz are torsion, gear, boom and engine modes) and a
#: FFFW winglet mode (the full tanks make the winglets swing with the wing-tip torsion, and no
#: mode has them carrying most of the energy, see mode_names.WINGLET_SHARE).
PAPER_KINDS = {"efew": {"SW1B", "AW1B", "SW1T", "AW1T", "SW2B", "AMLGL", "SMLGL", "BoomH", "AW2B",
                        "SWL", "SW3B", "AW3B", "AMLGFA", "AW2T"},
               "fffw": {"SW1B", "AW1B", "SW1T", "AW1T", "SW2B", "AMLGL", "SMLGL", "BoomH", "SWL",
                        "SW3B", "NLGFA", "AW2T"}}
NOT_IN_MODEL = {"efew": {"AW2B", "AW3B"}, "fffw": {"SWL"}}


@pytest.mark.parametrize("configuration", mm.CONFIGURATIONS)
def test_mode_table_names_the_paper_kinds(modes, configuration):
    table = classify_modes(modes[configuration], configuration)
    names = [r["name"] for r in table]
    flexible = [r for r in table if r["name"] != "RB"]
    assert names[:6] == ["RB"] * 6
    assert names[6:8] == ["SW1B", "AW1B"]                     # as in the paper
    assert sum(r["frequency"] < 40.0 for r in flexible) >= 24
    assert PAPER_KINDS[configuration] - set(names) == NOT_IN_MODEL[configuration]
    assert {"SEL", "AEL", "NLGL", "BoomV"} <= set(names)       # engines, nose gear, boom
    assert all(abs(abs(r["symmetry"]) - 1.0) < 1e-6 for r in flexible)
    assert len(set(names[6:])) == len(names[6:])               # every flexible name is unique


def test_truth_hooks(tmp_path):
    """The truth generator's hooks: a deck our solver reads, 8 lb more (cables), the suspension's
    six rigid-body modes lifted off zero but far below the first flexible mode."""
    truth = replace(mm.ANALYSIS, main_gear_segments=4, main_gear_taper=0.6, main_gear_bow=1.5,
                    engine_mount=(2.0e4, 2.0e4, 4.0e4, 2.0e5, 2.0e5, 2.0e5), cable_weight=8.0,
                    suspension=2.0, property_factors=((111, "I1", 1.05),), mass_factors=((8301, 1.02),))
    texts = mm.deck_texts(truth)
    assert "CELAS2" in texts["structure_x56.inc"] and "SPC1" in texts["structure_x56.inc"]
    mm.write_model(tmp_path, truth)
    model = read_model(tmp_path / "x56_efew.bdf")
    weight = mass_properties(model).mass / mm.WTMASS
    root_wing = {m.eid: m.weight for m in mm.mass_items(mm.ANALYSIS, "efew")}[8301]
    assert weight == pytest.approx(_hand_sums("efew")[0] + 8.0 + 0.02 * root_wing, rel=1e-7)
    f = compute_modes(model, 10)["frequency"].values
    assert np.all(f[:6] < 1.0) and f[6] > 2.5
