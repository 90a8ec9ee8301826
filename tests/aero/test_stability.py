"""Stability derivatives from the VLM / DLM (aero.stability) against lifting-surface and strip
theory, the downwash-lag estimate, an independent path through splines and FE modes, and the
rigid-body short period of Nastran's bah_plane PK (FLUTTER 502)."""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from aero.model import BASIC, AeroModel, read_aero_model
from aero.panels import BoxMesh
from aero.stability import flexible_derivatives, longitudinal_inertia, stability_derivatives
from aero.vlm import steady_aic
from aero_decks import BAH, DATA
from flutter.short_period import short_period
from structures.common.errors import InputError
from test_vlm import rectangle, tuck

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "flutter"))
from flutter_nastran import column, f06_flutter_summaries  # noqa: E402

BAH_F06 = DATA / "bah_plane" / "bah_plane.f06"
RHO_502, MACH_502 = 1.225, 0.2          # FLUTTER 502: FLFACT 4 (density) and 5 (Mach)
#: bah_plane's CONM2 cards (grid, mass, x basic); CONM2 100 also carries I22 = 2e5 kg m^2 and all
#: structural elements are massless, so mass, CG and I_yy follow by hand.
BAH_CONM2 = [(1, 7864.8, 0.0), (7, 1364.8, 1.126), (8, 2305.2, 2.751), (9, 949.2, 0.7034),
             (10, 768.4, 0.6725), (11, 153.68, 0.5060), (12, 1364.8, -0.7709),
             (13, 2305.2, -2.053), (14, 949.2, -0.8050), (15, 768.4, -0.7740),
             (16, 153.68, -0.7091)]


def rectangle_model(aspect: float, nspan: int = 20, nchord: int = 10):
    """Half of a flat rectangular wing of chord 1 (SYMXZ = +1, basic = aerodynamic frame) and its
    half area."""
    mesh, area = rectangle(aspect, nspan, nchord)
    return AeroModel(filename="rectangle", aero_frame=BASIC, refc=1.0, rhoref=1.0, velocity=None,
                     symxz=1, symxy=0, panels=(), splines=(), mesh=mesh,
                     mach_k=np.zeros((0, 2))), area


def test_large_aspect_ratio_lift_slope():
    """A 20 rectangle at M 0: C_L_alpha within 2 % of Tuck's lifting-surface value (5.433 per rad;
    measured 5.475, +0.8 %) and below lifting line's 2 pi A / (A + 2) = 5.712 by 3-6 % (the
    elliptic-loading formula over-predicts rectangles, tests/aero/test_vlm.py)."""
    model, area = rectangle_model(20.0)
    d = stability_derivatives(model, 0.0, [0.25, 0.0, 0.0], reference_area=area)
    assert d.cl_alpha == pytest.approx(tuck(20.0), rel=0.02)
    assert 0.94 < d.cl_alpha / (2 * np.pi * 20.0 / 22.0) < 0.97
    assert d.reference_area == area and d.reference_chord == 1.0


def test_moment_reference_shift_and_pitch_rate_strip_values():
    """About the quarter chord of a straight rectangle C_m_alpha ~ 0 (|C_m_alpha| < 1 % of
    C_L_alpha: the aerodynamic centre); moving the reference point aft by dx changes C_m_alpha
    by C_L_alpha dx / c and C_L_q by -2 C_L_alpha dx / c exactly. A pitch rate about the quarter
    chord is an angle of attack q c / (2 V) at the 3/4-chord point (thin-airfoil / strip theory),
    so C_L_q(c/4) = C_L_alpha within 2 % and C_L_q(3c/4) ~ 0. Default S = the boxes' planform."""
    model, area = rectangle_model(20.0)
    qc = stability_derivatives(model, 0.0, [0.25, 0.0, 0.0])
    aft = stability_derivatives(model, 0.0, [0.75, 0.0, 0.0])
    assert qc.reference_area == pytest.approx(area, rel=1e-12)
    assert abs(qc.cm_alpha) < 0.01 * qc.cl_alpha
    assert aft.cm_alpha - qc.cm_alpha == pytest.approx(0.5 * qc.cl_alpha, rel=1e-10)
    assert aft.cl_q - qc.cl_q == pytest.approx(-qc.cl_alpha, rel=1e-10)
    assert aft.cl_alpha == pytest.approx(qc.cl_alpha, rel=1e-12)
    assert qc.cl_q == pytest.approx(qc.cl_alpha, rel=0.02)
    assert abs(aft.cl_q) < 0.01 * qc.cl_alpha
    assert qc.cm_q < 0


def test_alphadot_derivatives_converge_at_small_k():
    """The alpha-dot derivatives at k = 1e-4 and 1e-3 agree within 1 % (remainder O(k ln k)):
    A 8 rectangle and bah_plane."""
    model, _ = rectangle_model(8.0)
    bah = read_aero_model(BAH)
    for am, ref in ((model, [0.25, 0.0, 0.0]), (bah, [0.1, 3.1, 0.0])):
        a = stability_derivatives(am, 0.2, ref)
        b = stability_derivatives(am, 0.2, ref, k_alphadot=1e-3)
        assert b.cm_alphadot == pytest.approx(a.cm_alphadot, rel=0.01)
        assert b.cl_alphadot == pytest.approx(a.cl_alphadot, rel=0.02)


@pytest.fixture(scope="module")
def bah():
    from structures.bdf import read_model
    from structures.massprops import mass_properties

    am = read_aero_model(BAH)
    props = mass_properties(read_model(BAH))
    return am, props, stability_derivatives(am, MACH_502, props.cg)


def test_bah_mass_and_pitch_inertia_by_hand(bah):
    """Mass, CG and I_yy about the CG from the CONM2 list by hand."""
    am, props, _ = bah
    m = np.array([c[1] for c in BAH_CONM2])
    x = np.array([c[2] for c in BAH_CONM2])
    x_cg = (m * x).sum() / m.sum()
    mass, iyy = longitudinal_inertia(props, am)
    assert mass == pytest.approx(m.sum(), rel=1e-12)
    assert props.cg[0] == pytest.approx(x_cg, rel=1e-9)
    assert iyy == pytest.approx(2.0e5 + (m * (x - x_cg) ** 2).sum(), rel=1e-9)


def test_bah_tail_alphadot_is_the_downwash_lag(bah):
    """The alpha-dot derivatives of wing + tail = those of the wing alone + the lag of the wing's
    downwash at the tail (Etkin & Reid ch. 5): the tail feels the downwash of alpha(t - l_t/V),
    so with L_eps = the tail lift per unit wing alpha (steady VLM, tail at zero incidence,
    negative) C_L_alphadot,tail = -2 (L_eps / q S) l_t / c and C_m_alphadot,tail =
    2 (L_eps / q S) (l_t / c)^2, l_t from the CG to the tail's area centroid of load points.
    Measured: C_m_alphadot -8.55 (DLM) against -1.06 - 7.62 = -8.69 (1.6 %); C_L_alphadot -0.302
    against -2.754 + 2.428 = -0.326."""
    am, props, d = bah
    mesh = am.mesh
    tail = np.asarray(mesh.panel_id) == 901
    fields = ("corners", "doublet_in", "doublet_out", "collocation", "normal", "area", "chord",
              "span", "panel_id", "box_id")
    wing = dataclasses.replace(am, mesh=BoxMesh(**{f: getattr(mesh, f)[~tail] for f in fields}))
    alone = stability_derivatives(wing, MACH_502, props.cg, reference_area=d.reference_area)
    nz = np.asarray(mesh.normal)[:, 2]
    dcp = np.linalg.solve(steady_aic(mesh, MACH_502, symxz=am.symxz), np.where(tail, 0.0, -nz))
    l_eps = (dcp * mesh.area * nz)[tail].sum() / d.reference_area
    load_x = 0.5 * (mesh.doublet_in[tail, 0] + mesh.doublet_out[tail, 0])
    arm = (load_x * mesh.area[tail]).sum() / mesh.area[tail].sum() \
        - am.aero_frame.from_basic(props.cg)[0]
    c = d.reference_chord
    assert d.cm_alphadot == pytest.approx(alone.cm_alphadot + 2 * l_eps * (arm / c) ** 2, rel=0.05)
    assert d.cl_alphadot == pytest.approx(alone.cl_alphadot - 2 * l_eps * arm / c,
                                          abs=0.05 * abs(alone.cl_alphadot))


def test_bah_derivatives_equal_the_modal_quasi_steady_forces(bah):
    """Independent path: our FE rigid modes (structures.modal, mass-normalised) through the
    SPLINE2 splines and aero.gaf give Q(k) of plunge and pitch; the quasi-steady p-method on them,
    [p^2 I - q_dyn (Q0 + (p b / V) Q1)] u = 0 with Q1 = Im Q(k = 1e-4) / 1e-4, has the short period
    of the derivatives with the alpha-dot terms on the pitch rate (flutter.short_period), within
    0.1 % at 30 and 146 m/s (measured 1e-7: same aerodynamics, rigid motion either way)."""
    from aero.gaf import generalized_aero_forces
    from structures.bdf import read_model
    from structures.modal import compute_modes

    am, props, d = bah
    modes = compute_modes(read_model(BAH), 2)
    q = generalized_aero_forces(am, modes, [MACH_502], [0.0, 1e-4])["Q"].values[0]
    q0, q1 = q[0].real, q[1].imag / 1e-4
    b = am.refc / 2.0
    mass, iyy = longitudinal_inertia(props, am)
    v = np.array([30.0, 146.0])
    ours = short_period(d, mass, iyy, RHO_502, v, alphadot="pitch_rate")
    for i, vel in enumerate(v):
        qd = 0.5 * RHO_502 * vel ** 2
        companion = np.block([[np.zeros((2, 2)), np.eye(2)], [qd * q0, qd * b / vel * q1]])
        p = np.linalg.eigvals(companion)
        p = p[np.argmax(p.imag)]
        assert p == pytest.approx(ours["eigenvalue"].values[i, 0], rel=1e-3)


def nastran_point_2(vmax: float = 200.0):
    """Nastran's PK point 2 (the short period) of FLUTTER 502 at V <= vmax: V, f, g."""
    table = next(s for s in f06_flutter_summaries(BAH_F06)
                 if s["point"] == 2 and s["mach"] == pytest.approx(MACH_502))
    v = column(table, "velocity")
    keep = v <= vmax
    return v[keep], column(table, "frequency")[keep], column(table, "damping")[keep]


def test_bah_rigid_short_period_against_nastran_at_low_dynamic_pressure(bah):
    """Nastran's PK point 2 at the F06 speeds 30-117 m/s (q <= 8.4 kPa): the rigid aircraft's
    short period with the alpha-dot terms on the pitch rate -- the quasi-steady truncation the
    modal methods share -- within the issue's 5 % in frequency and 10 % in g. Measured
    -0.5..+2.9 % in f and -4.7..-8.5 % in g; above 117 m/s the wing's flexibility, absent from a
    rigid aircraft, takes Nastran's short period down in frequency (next test)."""
    am, props, d = bah
    v, f, g = nastran_point_2(117.0)
    assert v.size == 7
    mass, iyy = longitudinal_inertia(props, am)
    ds = short_period(d, mass, iyy, RHO_502, v, alphadot="pitch_rate")
    np.testing.assert_allclose(ds["frequency"].values[:, 0], f, rtol=0.05)
    np.testing.assert_allclose(ds["damping"].values[:, 0], g, rtol=0.10)


@pytest.fixture(scope="module")
def bah_flexible(bah):
    """Our 8 modes of bah_plane (2 rigid, 6 elastic) and the flexible derivatives at q = 0 and at
    every F06 speed of FLUTTER 502 up to 200 m/s."""
    from structures.bdf import read_model
    from structures.modal import compute_modes

    am, props, _ = bah
    modes = compute_modes(read_model(BAH), 8)
    v, f, g = nastran_point_2(200.0)
    derivs = flexible_derivatives(am, modes, MACH_502, props.cg,
                                  np.concatenate([[0.0], 0.5 * RHO_502 * v ** 2]))
    return modes, derivs, (v, f, g)


def flexible_short_period(bah, derivs, v, alphadot):
    """Short-period root (root 1) at each speed, one set of derivatives per speed."""
    am, props, _ = bah
    mass, iyy = longitudinal_inertia(props, am)
    return short_period(list(derivs), mass, iyy, RHO_502, v, alphadot=alphadot).sel(root=1)


def test_bah_flexible_short_period_against_nastran_30_to_200(bah, bah_flexible):
    """The issue's check: Nastran's PK point 2 at every F06 speed in 30-200 m/s (12 speeds),
    within 5 % in frequency and 10 % in g, by the elastic aircraft's derivatives (six wing modes in
    quasi-static equilibrium) with the alpha-dot terms on the pitch rate. Measured -0.59..-0.75 %
    in f and -4.3..-4.5 % in g. At q = 0 the flexible derivatives are the rigid ones."""
    _, derivs, (v, f, g) = bah_flexible
    rigid = bah[2]
    for name in ("cl_alpha", "cm_alpha", "cl_q", "cm_q", "cl_alphadot", "cm_alphadot"):
        assert getattr(derivs[0], name) == pytest.approx(getattr(rigid, name), rel=1e-10)
    assert v.size == 12 and v.min() == 30.0
    roots = flexible_short_period(bah, derivs[1:], v, "pitch_rate")
    np.testing.assert_allclose(roots["frequency"].values, f, rtol=0.05)
    np.testing.assert_allclose(roots["damping"].values, g, rtol=0.10)


def test_bah_flexible_derivatives_against_the_modal_p_method(bah, bah_flexible):
    """Independent path for the elastic part: the quasi-steady p-method on all 8 modes through the
    splines (aero.gaf), the elastic modes with their inertia, at 146 m/s: the flexible-derivative
    short period within 2 % in f and g (the quasi-static elastic modes neglect
    (f_sp / f_1)^2 = (0.41 / 2.45)^2 = 2.8 % of their response; measured 0.3 %)."""
    from aero.gaf import generalized_aero_forces

    am, _, _ = bah
    modes, derivs, (v, _, _) = bah_flexible
    i = int(np.argmin(np.abs(v - 146.0)))
    q = generalized_aero_forces(am, modes, [MACH_502], [0.0, 1e-4])["Q"].values[0]
    q0, q1 = q[0].real, q[1].imag / 1e-4
    qd, b, n = 0.5 * RHO_502 * v[i] ** 2, am.refc / 2.0, q0.shape[0]
    stiffness = np.diag((2 * np.pi * modes["frequency"].values) ** 2)
    companion = np.block([[np.zeros((n, n)), np.eye(n)],
                          [-(stiffness - qd * q0), qd * b / v[i] * q1]])
    p = np.linalg.eigvals(companion)
    p = p[(p.imag > 0) & (np.abs(p) < 2 * np.pi * 1.0)]        # below the first wing mode
    assert p.size == 1
    ours = flexible_short_period(bah, [derivs[1 + i]], [v[i]], "pitch_rate").isel(velocity=0)
    assert ours["frequency"].item() == pytest.approx(p[0].imag / (2 * np.pi), rel=0.02)
    assert ours["damping"].item() == pytest.approx(2 * p[0].real / p[0].imag, rel=0.02)


@pytest.mark.xfail(strict=True, reason=(
    "the flight-mechanics alpha-dot (on alpha' = q - h''/V) does not reach the issue's 5 % / 10 % "
    "against Nastran's PK: f is 14.7 % low and g 10.1 % high at 30 m/s (rigid), -15..-24 % and "
    "+11..+25 % (flexible): the extra Z_alpha M_alphadot / V = the p_bar^2 term of the plunge "
    "column, which Nastran's p-k (Q at k = Im p_bar) and the quasi-steady p-method leave out; "
    "the short period is near critical damping (zeta 0.75), so its damped frequency is sensitive. "
    "See the report of issue 13."))
@pytest.mark.parametrize("flexible", [False, True])
def test_bah_flight_mechanics_alphadot_against_nastran_30_to_200(bah, bah_flexible, flexible):
    am, props, d = bah
    _, derivs, (v, f, g) = bah_flexible
    roots = flexible_short_period(bah, derivs[1:] if flexible else [d] * v.size, v, "alpha")
    np.testing.assert_allclose(roots["frequency"].values, f, rtol=0.05)
    np.testing.assert_allclose(roots["damping"].values, g, rtol=0.10)


def test_bad_input(bah):
    am, props, _ = bah
    with pytest.raises(InputError, match=r"k_alphadot=0\.5"):
        stability_derivatives(am, 0.2, props.cg, k_alphadot=0.5)
    with pytest.raises(InputError, match=r"Mach number 1\.1"):
        stability_derivatives(am, 1.1, props.cg)


def test_flexible_derivatives_bad_input(bah, bah_flexible):
    am, props, _ = bah
    modes = bah_flexible[0]
    with pytest.raises(InputError, match=r"dynamic pressures \[-1\.0\]"):
        flexible_derivatives(am, modes, 0.2, props.cg, [-1.0])
    with pytest.raises(InputError, match=r"no mode at or above rigid_hz"):
        flexible_derivatives(am, modes.isel(mode=[0, 1]), 0.2, props.cg, [100.0])
