"""Symmetric body-freedom flutter (SBFF) of the project's own flying wing (data/bff_wing, issue 13).

The deck is a swept flying wing free in plunge and pitch (symmetric half model, AERO SYMXZ = +1):
its short period, slow at low speed because the static margin is small, rises with speed and
coalesces with the first symmetric wing bending. Everything below runs the project's one chain:
our modes (structures.modal), our doublet-lattice GAFs (aero, projected from the grid GAFs that
:func:`pipeline.chain.deck_grid_gaf` computes once for the shared aerodynamic grid) and the flutter
solvers on the deck's FLUTTER card (PK, Mach 0.2, sea level, 10 - 150 m/s).

Independent references:

* modes against MYSTRAN (SOL 103 on the same structure and mass cards), within the issue's 1 %;
* weight, CG and pitch inertia against hand sums over the generator's CONM2 list;
* the rigid short period of flight mechanics (stability derivatives of aero.stability,
  flutter.short_period) at low speed, against the g-method's and the p-method's;
* the direction of the SBFF speed change, from the physics of the mechanism. The short period's
  frequency is, from the quasi-steady pitch equation of flight mechanics (Etkin & Reid, Dynamics
  of Flight, 3rd ed., ch. 6, short-period approximation),
  omega_sp^2 ~ -M_alpha / I_yy = q S cbar C_L_alpha (x_np - x_cg) / (cbar I_yy): it rises with V
  and falls with the pitch inertia I_yy and with the static margin as the CG moves aft. SBFF is
  its coalescence with the first wing bending (the mechanism of Weisshaar & Zeiler, J. Aircraft
  20(12), 1983, and of Chen's BFF example, AIAA J. 38(9), 2000; their parametric figures were not
  at hand here, so the expected direction is argued from this mechanism), so a slower short
  period meets the bending at a higher speed: more pitch inertia or an aft CG (smaller, still
  positive, static margin) raise the SBFF speed and lower its frequency. To first order (the
  bending frequency fixed, the short period reaching a fixed share of it) V_SBFF ~
  sqrt(I_yy / (x_np - x_cg)); the size of the measured change is compared with that estimate.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from aero.model import read_aero_model
from aero.rfa import fit_rfa
from aero.stability import longitudinal_inertia, stability_derivatives
from flutter.gmethod import g_solve
from flutter.pmethod import p_solve
from flutter.results import is_flutter
from flutter.summary import BFF_SHARE
from flutter.short_period import short_period
from flutter.solve import modal_system
from flutter.system import StructuralDamping
from pipeline.chain import deck_grid_gaf, deck_modes, flutter_chain
from structures.bdf import read_model
from structures.bulk_text import card
from structures.common.nastran import read_pynastran
from structures.massprops import mass_properties

REPO = Path(__file__).resolve().parents[2]
FOLDER = REPO / "data" / "bff_wing"
sys.path.insert(0, str(REPO / "tests" / "structures"))

from test_mystran import needs_mystran, run_mystran  # noqa: E402

# the generator under a name of its own: tests/data/practitioner_wing has a make_deck.py too
_spec = importlib.util.spec_from_file_location("bff_wing_make_deck", FOLDER / "make_deck.py")
md = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = md   # (dataclasses look their module up there)
_spec.loader.exec_module(md)

#: Modes above ~30 Hz need k beyond the table (1.5) at the lowest speeds; the solvers warn and
#: mark those points not converged. They take no part in the SBFF.
pytestmark = pytest.mark.filterwarnings("ignore:.*outside the tabulated k range:RuntimeWarning")
#: The SBFF is the slowest oscillatory (above this, Hz: a static pitch instability of the
#: flexible aircraft has ~0 Hz) flutter crossing whose rigid-body modes take at least
#: flutter.summary.BFF_SHARE of the participation.
SBFF_MIN_HZ = 0.5
#: Quasi-steady neutral point of the planform (m aft of the centre-line leading edge): quarter
#: of the mean aerodynamic chord, x_le(y_mac) + cbar / 4 (Raymer, Aircraft Design, Fig. 7.3,
#: straight-tapered wing), y_mac = (b/6)(1 + 2 lambda)/(1 + lambda).
TAPER = md.C_TIP / md.C_ROOT
Y_MAC = md.HALF_SPAN / 3 * (1 + 2 * TAPER) / (1 + TAPER)
MAC = 2 / 3 * md.C_ROOT * (1 + TAPER + TAPER ** 2) / (1 + TAPER)
X_NP = md.leading_edge(Y_MAC) + MAC / 4


@pytest.fixture(scope="module")
def grid_gaf():
    """Grid GAFs of the committed deck's aerodynamic grid, shared by every mass variant."""
    return deck_grid_gaf(FOLDER / "bff_wing.bdf")


def _solve(folder: Path, grid_gaf, **params) -> dict:
    """Modes, GAFs and p-k flutter of the deck with ``params`` (md.BFFParameters fields)."""
    deck = md.write_deck(folder / "bff.bdf", md.BFFParameters(**params))
    return flutter_chain(deck, deck_modes(deck), grid_gaf=grid_gaf)


def sbff(out: dict) -> tuple[float, float, float]:
    """(speed m/s, frequency Hz, rigid-body participation %) of the lowest-speed SBFF crossing."""
    part = out["participation"]
    rigid = part.participation.values[:, part.rigid.values].sum(axis=1)
    ok = (part.frequency.values > SBFF_MIN_HZ) & (rigid >= BFF_SHARE)
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
    iyy = m @ (d[:, 0] ** 2 + d[:, 2] ** 2) + sum(it.inertia[1] for it in items)
    return m.sum(), cg, float(iyy)


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
    """Two rigid (plunge, pitch) and eight elastic modes of the committed structure. Measured: the
    elastic ones within 1.5e-8 (MYSTRAN's OP2 eigenvalues are float32); asserted within the
    issue's 1 % (rigid modes below 1e-3 Hz in both)."""
    theirs = run_mystran(_mystran_deck(tmp_path))
    ours = np.asarray(deck_modes(FOLDER / "bff_wing.bdf")["frequency"].values, dtype=float)
    assert ours.size == theirs.size == md.NMODES
    assert np.all(np.abs(ours[:2]) < 1e-3) and np.all(np.abs(theirs[:2]) < 1e-3)
    np.testing.assert_allclose(ours[2:], theirs[2:], rtol=1e-2)


def test_sbff_is_found_and_is_body_freedom(baseline):
    """Baseline (body at x = 0.70 m, I22 = 1.5 kg m^2): the short period is a slow, damped
    oscillation at low speed; the first flutter crossing is the SBFF, between the short period's
    and the in-vacuo bending frequency, with the rigid-body modes carrying most of the motion and
    classified body-freedom flutter in the summary; the wing's own bending-torsion flutter is far
    above it. Measured (p-k): short period 1.06 Hz, g -1.24 at 20 m/s; SBFF 40.83 m/s, 2.56 Hz,
    rigid share 83 %; first bending in vacuo 4.07 Hz; wing flutter 111.5 m/s, 11.3 Hz."""
    modes = baseline["modes"]
    f_bend = float(modes["frequency"][2])
    assert np.all(modes["frequency"].values[:2] < 1e-3) and 3.0 < f_bend < 6.0
    ds = baseline["results"][0][1]
    i20 = int(np.argmin(np.abs(ds.velocity.values - 20.0)))
    f_sp = float(ds.frequency[i20, 1])
    assert 0.5 < f_sp < 1.3 and float(ds.damping[i20, 1]) < -0.3       # the short period
    v, f, rigid = sbff(baseline)
    assert 30.0 < v < 50.0 and f_sp < f < f_bend and rigid > 70.0
    first = min((e for e in baseline["summary"] if is_flutter(e["kind"])),
                key=lambda e: e["velocity"])
    assert first["velocity"] == pytest.approx(v, rel=1e-9)
    assert first["kind"] == "body_freedom_flutter"
    flutter = np.array([is_flutter(k) for k in ds.crossing_kind.values])
    wing = flutter & (ds.crossing_frequency.values > 2 * f_bend)
    assert wing.any() and ds.crossing_velocity.values[wing].min() > 2.5 * v


def _relative_change(v0: float, v1: float) -> float:
    return v1 / v0 - 1.0


def _static_margin(params: md.BFFParameters) -> float:
    """(x_np - x_cg) / cbar with the quasi-steady quarter-MAC neutral point ``X_NP``."""
    return (X_NP - _hand_mass(params)[1][0]) / MAC


def _estimate(p0: md.BFFParameters, p1: md.BFFParameters) -> float:
    """First-order relative change of V_SBFF, sqrt(I_yy / static margin) (module docstring)."""
    i0, i1 = _hand_mass(p0)[2], _hand_mass(p1)[2]
    return float(np.sqrt(i1 * _static_margin(p0) / (i0 * _static_margin(p1)))) - 1.0


@pytest.fixture(scope="module")
def variants(tmp_path_factory, baseline, grid_gaf):
    """p-k chain results of the study's variants (the baseline is I22 1.5, x 0.70)."""
    folder = tmp_path_factory.mktemp("variants")
    out = {(1.5, 0.70): baseline}
    for inertia, x in ((1.0, 0.70), (2.0, 0.70), (1.5, 0.65), (1.5, 0.72)):
        out[inertia, x] = _solve(folder / f"{inertia}_{x}", grid_gaf, body_pitch_inertia=inertia,
                                 body_x=x)
    return out


def _params(key) -> md.BFFParameters:
    return md.BFFParameters(body_pitch_inertia=key[0], body_x=key[1])


def _short_period_hz(out: dict, velocity: float) -> float:
    """Short-period frequency (Hz) of the g-method (exact damping off g = 0) at ``velocity``,
    tracked from 4 m/s: the oscillatory one of the two rigid-body roots."""
    V = np.arange(4.0, velocity + 1.0, 2.0)
    ds = g_solve(modal_system(out["modes"], StructuralDamping()), out["gaf"], V,
                 density=md.RHOREF, mach=md.MACH)
    f = ds.frequency.values[-1, :2]
    assert np.count_nonzero(f > 0.2) == 1, f
    return float(f.max())


def test_short_period_scales_as_flight_mechanics(variants):
    """At 20 m/s (half the SBFF speed) the short period of every variant against the quasi-steady
    omega_sp ~ sqrt(static margin / I_yy) (module docstring), as ratios to the baseline's, within
    10 %. Measured (g-method): 1.06 Hz at the baseline (0.50 Hz at 10 m/s); ratios within 0.7 %
    (inertia) and 7.4 % (CG) of the estimate (the vortex lattice puts the neutral point at 0.29 MAC,
    a little aft of the quarter-MAC estimate)."""
    base = (1.5, 0.70)
    f0 = _short_period_hz(variants[base], 20.0)
    assert 0.8 < f0 < 1.3
    for key in variants:
        if key == base:
            continue
        p0, p1 = _params(base), _params(key)
        expected = np.sqrt(_static_margin(p1) * _hand_mass(p0)[2]
                           / (_static_margin(p0) * _hand_mass(p1)[2]))
        assert _short_period_hz(variants[key], 20.0) / f0 == pytest.approx(expected, rel=0.10)


def test_short_period_three_ways(baseline):
    """The baseline's short period at 4 - 10 m/s (dynamic pressure <= 61 Pa: the rigid
    aircraft) by the g-method, the p-method (4-lag Roger fit) and flight mechanics
    (aero.stability derivatives from our VLM / DLM about the CG, flutter.short_period with the
    alpha-dot terms on the pitch rate, the modal truncation) agree within the issue's 5 % in
    frequency and 10 % in g. Measured at 4 / 10 m/s: g-method 0.197 / 0.499 Hz, g -1.24 / -1.22;
    p-method 0.200 / 0.507 Hz, g -1.21 / -1.20; flight mechanics 0.206 / 0.514 Hz, g -1.26 (4.6 %
    above the g-method at 4 m/s: the derivatives are the k -> 0 limit, this short period lives at
    k ~ 0.105)."""
    deck = FOLDER / "bff_wing.bdf"
    aero = read_aero_model(read_pynastran(deck))
    props = mass_properties(read_model(deck))
    mass, iyy = longitudinal_inertia(props, aero)
    V = np.arange(4.0, 11.0, 2.0)
    fm = short_period(stability_derivatives(aero, md.MACH, props.cg), mass, iyy, md.RHOREF, V,
                      alphadot="pitch_rate")
    system = modal_system(baseline["modes"], StructuralDamping())
    g = g_solve(system, baseline["gaf"], V, density=md.RHOREF, mach=md.MACH)
    p = p_solve(system, baseline["gaf"], V, density=md.RHOREF, mach=md.MACH, fit=fit_rfa,
                fit_options={"k_max": 0.6, "npair": 0})
    ref_f, ref_g = g.frequency.values[:, 1], g.damping.values[:, 1]
    assert np.all(ref_f > 0.15) and np.all(ref_g < -1.0)
    for f, damping in ((p.frequency.values[:, 1], p.damping.values[:, 1]),
                       (fm.frequency.values[:, 0], fm.damping.values[:, 0])):
        np.testing.assert_allclose(f, ref_f, rtol=0.05)
        np.testing.assert_allclose(damping, ref_g, rtol=0.10)


def test_rigid_roots_are_named(baseline):
    """The chain names the baseline's rigid-body roots: root 1 the plunge, root 2 the short
    period. Root 2 (p = -2.05 + 3.14i rad/s at 10 m/s, 0.50 Hz, g -1.30) has 96.0 % plunge, 3.9 %
    pitch participation (a slow short period plunges the mass-normalised aircraft more than it
    pitches it): flutter.rigid_roots names it by its longitudinal (plunge + pitch) share."""
    labels = [str(x) for x in baseline["results"][0][1]["root_label"].values[:2]]
    assert labels == ["plunge", "short period"]


def _check_trend(variants, keys):
    """SBFF speed up and frequency down along ``keys``; the speed's relative change within a
    factor 4 of the first-order estimate."""
    points = [sbff(variants[key]) for key in keys]
    for (v0, f0, _), (v1, f1, _), k0, k1 in zip(points, points[1:], keys, keys[1:]):
        assert v1 > v0 and f1 < f0
        estimate = _estimate(_params(k0), _params(k1))
        assert estimate / 4 < _relative_change(v0, v1) < 4 * estimate


def test_sbff_speed_rises_with_pitch_inertia(variants):
    """I22 of the centre body 1.0 -> 1.5 -> 2.0 kg m^2 (aircraft I_yy 2.98 -> 3.48 -> 3.98 per
    half): SBFF speed up, frequency down at each step. Measured (p-k): 35.8 m/s 2.91 Hz ->
    40.8 m/s 2.56 Hz -> 48.5 m/s 2.23 Hz, +13.9 % and +18.9 % against the estimate's +8.0 % and
    +6.9 % (the estimate ignores the bending root's softening as it couples)."""
    _check_trend(variants, [(1.0, 0.70), (1.5, 0.70), (2.0, 0.70)])


def test_sbff_speed_rises_as_the_cg_moves_aft(variants):
    """Centre body at x = 0.65 -> 0.70 -> 0.72 m (aircraft CG 0.767 -> 0.797 -> 0.809 m, static
    margin 12.0 -> 7.5 -> 5.7 % MAC): SBFF speed up, frequency down at each step. Measured
    (p-k): 38.2 m/s 2.94 Hz -> 40.8 m/s 2.56 Hz -> 43.1 m/s 2.32 Hz, +6.9 % and +5.6 % against
    the estimate's +24 % and +14 % (the flexible swept wing moves the neutral point with speed,
    which the rigid estimate ignores). Further aft (x = 0.75 m) the coupled root turns real
    (static pitch instability of the flexible aircraft, 58.6 m/s) instead of fluttering."""
    _check_trend(variants, [(1.5, 0.65), (1.5, 0.70), (1.5, 0.72)])


def _sbff_of(ds, modes) -> float:
    """SBFF speed of a solver's sweep (:func:`sbff` on its participation)."""
    from pipeline.chain import flutter_participation

    return sbff({"participation": flutter_participation([({}, ds)], modes)})[0]


@pytest.fixture(scope="module")
def g_baseline(baseline):
    """The g-method on the baseline's modes and GAFs over the deck's FLUTTER velocities."""
    system = modal_system(baseline["modes"], StructuralDamping())
    return g_solve(system, baseline["gaf"], np.asarray(md.VELOCITIES), density=md.RHOREF,
                   mach=md.MACH)


def test_g_method_and_pk_agree_on_the_sbff(baseline, g_baseline):
    """Both are exact at g = 0: SBFF speeds within 1 % (measured 40.826 m/s both)."""
    assert g_baseline.attrs["method"] == "G"
    assert _sbff_of(g_baseline, baseline["modes"]) == pytest.approx(sbff(baseline)[0], rel=0.01)


def test_g_and_p_methods_agree_on_the_sbff(baseline, g_baseline):
    """The issue's must-show: g-method and p-method SBFF speeds within 1 %. The p-method's rational
    fit (aero.rfa) has four real lags (Roger form, no complex pairs: 0.4 s instead of 29 s) over
    k <= 0.6, which covers the SBFF's k ~ 0.13 and the wing flutter's ~ 0.21; its fit error must
    be under the issue's 2 % (measured 0.12 %). Measured SBFF: 40.848 m/s (p-method), 40.826 m/s
    (g-method and p-k); with three complex pairs as well (fit error 6e-6), 40.826 m/s."""
    system = modal_system(baseline["modes"], StructuralDamping())
    p = p_solve(system, baseline["gaf"], np.asarray(md.VELOCITIES), density=md.RHOREF,
                mach=md.MACH, fit=fit_rfa, fit_options={"k_max": 0.6, "npair": 0})
    assert p.attrs["method"] == "P-RFA" and p.attrs["rfa_fit_error"] < 0.02
    assert _sbff_of(p, baseline["modes"]) == pytest.approx(
        _sbff_of(g_baseline, baseline["modes"]), rel=0.01)
