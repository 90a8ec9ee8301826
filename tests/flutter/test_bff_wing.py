"""Symmetric body-freedom flutter (SBFF) of the project's own flying wing (data/bff_wing, issue 13).

The deck is a swept flying wing free in plunge and pitch (symmetric half model, AERO SYMXZ = +1):
its short period, slow at low speed because the static margin is small, rises with speed and
coalesces with the first symmetric wing bending. Everything below runs the project's one chain:
our modes (structures.modal), our doublet-lattice GAFs (aero, projected from the grid GAFs that
:func:`pipeline.chain.deck_grid_gaf` computes once for the shared aerodynamic grid) and the flutter
solvers on the deck's FLUTTER card (PK, Mach 0.2, sea level, 10 - 150 m/s).

Independent references:

* modes against MYSTRAN (SOL 103 on the same structure and mass cards), within the issue's 1 %;
* weight and CG against hand sums over the generator's CONM2 list;
* the direction of the SBFF speed change. The short period's frequency is, from the quasi-steady
  pitch equation of flight mechanics (Etkin & Reid, Dynamics of Flight, sec. 6.3, short-period
  approximation), omega_sp^2 ~ -M_alpha / I_yy = q S cbar C_L_alpha (x_np - x_cg) / (cbar I_yy):
  it rises with V, falls with the pitch inertia I_yy and with the static margin as the CG moves
  aft. SBFF is its coalescence with the first bending (Weisshaar & Zeiler, J. Aircraft 20(12),
  1983, on forward-swept aircraft; Chen, AIAA J. 38(9), 2000, BFF example), so a slower short
  period meets the bending at a higher speed: more pitch inertia or an aft CG (smaller, still
  positive, static margin) raise the SBFF speed and lower its frequency. To first order (the
  bending frequency fixed, the short period reaching a fixed share of it) V_SBFF ~
  sqrt(I_yy / (x_np - x_cg)); the size of the measured change is compared with that estimate.
"""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pipeline.chain import deck_grid_gaf, deck_modes, flutter_chain
from structures.bulk_text import card
from structures.massprops import mass_properties
from structures.bdf import read_model

REPO = Path(__file__).resolve().parents[2]
FOLDER = REPO / "data" / "bff_wing"
sys.path.insert(0, str(FOLDER))
sys.path.insert(0, str(REPO / "tests" / "structures"))

import make_deck as md  # noqa: E402
from test_mystran import needs_mystran, run_mystran  # noqa: E402

#: A crossing is the SBFF when it is an oscillatory flutter crossing (above this, Hz; the rigid
#: real-root instabilities at higher speed have ~0 Hz) with at least this rigid-body share of the
#: participation (%).
SBFF_MIN_HZ = 0.5
SBFF_RIGID_SHARE = 50.0
#: Quasi-steady neutral point of the planform (m aft of the centre-line leading edge): quarter
#: of the mean aerodynamic chord, x_le(y_mac) + cbar / 4 (Raymer, Aircraft Design, Fig. 7.3,
#: straight-tapered wing), y_mac = (b/6)(1 + 2 lambda)/(1 + lambda).
TAPER = md.C_TIP / md.C_ROOT
Y_MAC = md.HALF_SPAN / 3 * (1 + 2 * TAPER) / (1 + TAPER)
MAC = 2 / 3 * md.C_ROOT * (1 + TAPER + TAPER ** 2) / (1 + TAPER)
X_NP = md.leading_edge(Y_MAC) + MAC / 4


@pytest.fixture(scope="module")
def grid_gaf(tmp_path_factory):
    """Grid GAFs of the committed deck's aerodynamic grid, shared by every mass variant."""
    return deck_grid_gaf(FOLDER / "bff_wing.bdf")


def _solve(folder: Path, grid_gaf, **params) -> dict:
    """Modes, GAFs and p-k flutter of the deck with ``params`` (md.BFFParameters fields)."""
    deck = md.write_deck(folder / "bff.bdf", md.BFFParameters(**params))
    modes = deck_modes(deck)
    with pytest.warns(RuntimeWarning, match="outside the tabulated k range"):
        return flutter_chain(deck, modes, grid_gaf=grid_gaf)


def sbff(out: dict) -> tuple[float, float, float]:
    """(speed m/s, frequency Hz, rigid-body participation %) of the lowest-speed SBFF crossing."""
    part = out["participation"]
    rigid = part.participation.values[:, part.rigid.values].sum(axis=1)
    ok = (part.frequency.values > SBFF_MIN_HZ) & (rigid >= SBFF_RIGID_SHARE)
    assert ok.any(), "no body-freedom flutter crossing"
    i = np.flatnonzero(ok)[np.argmin(part.velocity.values[ok])]
    return float(part.velocity[i]), float(part.frequency[i]), float(rigid[i])


@pytest.fixture(scope="module")
def baseline(tmp_path_factory, grid_gaf):
    return _solve(tmp_path_factory.mktemp("base"), grid_gaf)


def _hand_mass(params: md.BFFParameters) -> tuple[float, np.ndarray, float]:
    """Mass (kg), CG (m) and pitch inertia about the CG (kg m^2) of the half model's CONM2s."""
    g = md.grids()
    items = md.mass_items(params)
    m = np.array([it.mass for it in items])
    xyz = np.array([np.add(g[it.grid], it.offset) for it in items])
    cg = m @ xyz / m.sum()
    d = xyz - cg
    return m.sum(), cg, float(m @ (d[:, 0] ** 2 + d[:, 2] ** 2) + sum(it.inertia[1] for it in items))


def test_generator_is_deterministic(tmp_path):
    """A fresh interpreter writes the committed deck byte for byte."""
    subprocess.run([sys.executable, str(FOLDER / "make_deck.py"), str(tmp_path / "bff.bdf")],
                   check=True, capture_output=True, env={"PYTHONHASHSEED": "3"})
    assert (tmp_path / "bff.bdf").read_bytes() == (FOLDER / "bff_wing.bdf").read_bytes()


def test_mass_properties_by_hand():
    """Our mass properties of the committed deck against the CONM2 sums (parallel axes)."""
    mass, cg, iyy = _hand_mass(md.ANALYSIS)
    props = mass_properties(read_model(FOLDER / "bff_wing.bdf"))
    assert props.mass == pytest.approx(mass, rel=1e-6)
    np.testing.assert_allclose(props.cg, cg, atol=1e-6)
    assert props.inertia[1, 1] == pytest.approx(iyy, rel=1e-6)
    assert mass == pytest.approx(md.ANALYSIS.body_mass + md.ANALYSIS.wing_mass, rel=1e-12)
    assert 0.03 < (X_NP - cg[0]) / MAC < 0.12          # a small positive static margin


def _mystran_deck(folder: Path) -> Path:
    text = ["SOL 103", "CEND", "TITLE = BFF WING MODES", "METHOD = 1", "SPC = 1",
            "DISP(PLOT) = ALL", "BEGIN BULK", *md.structure_bulk(md.ANALYSIS),
            card("EIGRL", 1, None, None, md.NMODES), "ENDDATA"]
    path = folder / "bff_103.bdf"
    path.write_text("\n".join(text) + "\n")
    return path


@needs_mystran
def test_modes_against_mystran(tmp_path):
    """Two rigid (plunge, pitch) and eight elastic modes of the committed structure. Asserted
    within the issue's 1 % (rigid modes below 1e-3 Hz in both)."""
    theirs = run_mystran(_mystran_deck(tmp_path))
    ours = np.asarray(deck_modes(FOLDER / "bff_wing.bdf")["frequency"].values, dtype=float)
    assert ours.size == theirs.size == md.NMODES
    assert np.all(np.abs(ours[:2]) < 1e-3) and np.all(np.abs(theirs[:2]) < 1e-3)
    np.testing.assert_allclose(ours[2:], theirs[2:], rtol=1e-2)
