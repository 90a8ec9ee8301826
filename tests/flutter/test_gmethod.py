"""Chen's g-method (flutter.gmethod) against analytic, exact-pencil and Nastran references."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from scipy.optimize import fsolve
from scipy.special import kv

from aero.strip import section_gaf
from flutter.gmethod import GProblem, g_solve, g_solve_many
from flutter.crossings import drift_roots, resolved_damping
from flutter.kmethod import k_solve
from flutter.pk import pk_solve
from flutter.results import FLUTTER_KINDS
from flutter.system import ModalSystem, StructuralDamping
from flutter_nastran import DATA, bah_flutter_502, bah_qhh_dataset, f06_modes_used, first_crossing
from structures.common.errors import InputError
from test_pk_typical_section import A, B, RHO, gaf, section

F06 = DATA / "bah_plane" / "bah_plane.f06"


# ----------------------------------------------------------------------------- typical section
@pytest.fixture(scope="module")
def section_sweep():
    V = np.linspace(0.05, 3.2, 64)
    return V, g_solve(section(), gaf, V, density=RHO, mach=0.0, refc=2 * B)


def _flutter(ds):
    i = int(np.flatnonzero(ds.crossing_kind.values == "flutter")[0])
    return float(ds.crossing_velocity[i]), float(ds.crossing_frequency[i]), i


def test_section_flutter_equals_pk_k_and_theodorsen(section_sweep):
    """At g = 0 the g-method is exact: its flutter point is p-k's and the k-method's (tolerances of
    tests/flutter/test_pk_typical_section.py) and Hodges & Pierce's U/(b w_theta) ~ 2.17-2.18 at
    w/w_theta ~ 0.65."""
    V, ds = section_sweep
    assert ds.attrs["method"] == "G"
    Vg, fg, i = _flutter(ds)
    assert bool(ds.crossing_converged[i])
    pk = pk_solve(section(), gaf, V, density=RHO, mach=0.0, refc=2 * B)
    Vp, fp, _ = _flutter(pk)
    assert abs(Vg / Vp - 1) < 1e-3 and abs(fg / fp - 1) < 1e-3
    kd = k_solve(section(), gaf, np.linspace(0.05, 1.5, 3000), density=RHO, mach=0.0, refc=2 * B)
    j = int(np.argmin(np.abs(kd.crossing_velocity.values - Vg)))
    assert abs(float(kd.crossing_velocity[j]) / Vg - 1) < 2e-3
    assert abs(float(kd.crossing_frequency[j]) / fg - 1) < 2e-3
    assert 2.17 * 0.98 <= Vg <= 2.18 * 1.02
    assert abs(2 * np.pi * fg / 0.65 - 1) < 0.03


def test_section_divergence_analytic(section_sweep):
    """Divergence U_D / (b w_theta) = sqrt(mu r^2 / (1 + 2a)) = 2.828 (H&P eq. 5.44), frequency 0."""
    _, ds = section_sweep
    dv = ds.crossing_kind.values == "divergence"
    assert dv.sum() == 1
    U_D = np.sqrt(20.0 * 0.24 / (1 + 2 * A))
    assert abs(float(ds.crossing_velocity[dv][0]) / U_D - 1) < 1e-3
    assert float(ds.crossing_frequency[dv][0]) == 0.0


def test_section_density_sweep_crosses_at_the_velocity_sweep_density(section_sweep):
    """A PKNL-like density sweep at the flutter speed found at rho = 1 crosses at rho = 1."""
    _, ds = section_sweep
    Vg, fg, _ = _flutter(ds)
    rho = np.linspace(0.65, 1.55, 10)
    dd = g_solve(section(), gaf, Vg, density=rho, mach=0.0, refc=2 * B, sweep="density")
    assert dd.attrs["sweep"] == "density" and dd.sizes["density"] == 10
    rc = dd.crossing_density.values[dd.crossing_kind.values == "flutter"]
    assert rc.size == 1 and abs(rc[0] - RHO) < 1e-3


@pytest.mark.parametrize("kind", ["hysteretic", "viscous"])
def test_structural_damping_in_vacuo(kind):
    """Vanishing air: hysteretic K (1 + i g_s) gives p = i w0 sqrt(1 + i g_s), so g = -g_s / a^2
    and w = w0 a with a^2 = (1 + sqrt(1 + g_s^2)) / 2; modal viscous b = g_s w0 gives
    p = w0 (-g_s/2 + i sqrt(1 - g_s^2/4))."""
    gs = 0.03
    sys_ = section(StructuralDamping(g=gs, kind=kind))
    ds = g_solve(sys_, gaf, [1e-4, 2e-4], density=1e-9, mach=0.0, refc=2 * B)
    omega, _ = sys_.in_vacuo()
    if kind == "hysteretic":
        a2 = (1 + np.sqrt(1 + gs ** 2)) / 2
        w, g = omega * np.sqrt(a2), -gs / a2 * np.ones(2)
    else:
        c = np.sqrt(1 - gs ** 2 / 4)
        w, g = omega * c, -gs / c * np.ones(2)
    np.testing.assert_allclose(ds.frequency.isel(velocity=0).values * 2 * np.pi, w, rtol=1e-6)
    np.testing.assert_allclose(ds.damping.isel(velocity=0).values, g, rtol=1e-6)
    assert bool(ds.converged.all())


def test_unknown_option_and_sweep():
    with pytest.raises(InputError, match=r"unknown options \['tol'\]"):
        g_solve(section(), gaf, [1.0], density=RHO, mach=0.0, refc=2 * B, tol=1e-6)
    with pytest.raises(InputError, match="unknown sweep"):
        g_solve(section(), gaf, [1.0], density=RHO, mach=0.0, refc=2 * B, sweep="mach")


def _theodorsen_laplace(s, a, b):
    """Theodorsen's section GAF at complex p_bar = s (independent of aero.strip): BAH eqs.
    5-311/5-312 with ik -> s and C(k) -> C(s) = K1(s) / (K0(s) + K1(s)) (R. T. Jones' generalized
    Theodorsen function; C(ik) = H1 / (H1 + i H0)); F = q Q u, u = [h, alpha], F = [-L, M]."""
    C = kv(1, s) / (kv(0, s) + kv(1, s))
    pi = np.pi
    L_h = pi * s * s + 2 * pi * C * s
    L_a = b * (pi * s - pi * a * s * s + 2 * pi * C * (1 + (0.5 - a) * s))
    M_h = b * (pi * a * s * s + 2 * pi * (a + 0.5) * C * s)
    M_a = b * b * (-pi * (0.5 - a) * s - pi * (0.125 + a * a) * s * s
                   + 2 * pi * (a + 0.5) * C * (1 + (0.5 - a) * s))
    return np.array([[-2 * L_h, -2 * L_a], [2 * M_h, 2 * M_a]])


def test_free_section_damped_root_second_order():
    """A free (unsprung) Theodorsen section has a heavily damped oscillatory rigid-body root. Against
    the exact root of det[M p_bar^2 - (rho b^2/2) Q(p_bar)] = 0 with the generalized Theodorsen
    function, the g-method's error is of second order in the damping: relative error in p below
    0.1 (Re p / Im p)^2 and falling at least 2.5x per doubling of the mass ratio. Measured: 3.6e-2,
    8.7e-3, 2.3e-3, 8.4e-4 at mu = 20, 40, 80, 160 (g = -1.58 ... -0.40); p-k's Q^R + p_bar Q^I/k
    gives g -2.10 for the exact -1.58 at mu = 20 (the g-method -1.70)."""
    assert np.abs(_theodorsen_laplace(0.3j, A, B) - section_gaf(0.3, A, B)).max() < 1e-12
    errs = []
    for mu in (20.0, 40.0, 80.0, 160.0):
        m = mu * np.pi * RHO * B * B
        M = np.array([[m, -0.5 * m * B], [-0.5 * m * B, 0.4 * m * B * B]])
        p, *_ = GProblem(ModalSystem(M, np.zeros((2, 2))), gaf, refc=2 * B).roots(1.0, RHO, 0.0)
        x = p[p.imag > 1e-3]
        assert x.size == 1
        x = x[0] * B / 1.0

        def det(y):
            d = np.linalg.det(M * (y[0] + 1j * y[1]) ** 2
                              - 0.5 * RHO * B * B * _theodorsen_laplace(y[0] + 1j * y[1], A, B)) / m ** 2
            return [d.real, d.imag]

        y = fsolve(det, [x.real, x.imag], xtol=1e-12)
        exact = y[0] + 1j * y[1]
        assert abs(exact.imag - x.imag) < 0.5 * exact.imag   # the same root
        err = abs(x - exact) / abs(exact)
        assert err < 0.1 * (exact.real / exact.imag) ** 2
        errs.append(err)
    assert np.all(np.array(errs[:-1]) / np.array(errs[1:]) > 2.5)


# ----------------------------------------------------------------------------- quasi-steady GAFs
def _exact_roots(M, K, Q0, Q1, Q2, b, rho, V):
    """Eigenvalues p (Im p >= 0) of the exact pencil [(V/b)^2 (M - h Q2) p_bar^2 - (V/b)^2 h Q1
    p_bar + K - q Q0], h = rho b^2 / 2, written as a companion matrix in p_bar."""
    n = M.shape[0]
    h, s = 0.5 * rho * b * b, b / V
    A2, A1, A0 = M - h * Q2, -h * Q1, s * s * K - h * Q0
    Ai = np.linalg.inv(A2)
    lam = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-Ai @ A0, -Ai @ A1]])) * V / b
    return lam[lam.imag >= 0]


@pytest.fixture(scope="module")
def quasi_steady():
    rng = np.random.default_rng(3)
    M, K = np.diag([1.0, 2.0, 1.5]), np.diag([4.0, 25.0, 100.0])
    return M, K, rng.normal(size=(3, 3)), rng.normal(size=(3, 3)), 0.5 * rng.normal(size=(3, 3))


def _poly_gaf(Q0, Q1, Q2):
    return lambda mach, k: Q0 + 1j * k[:, None, None] * Q1 + (1j * k[:, None, None]) ** 2 * Q2


def test_quasi_steady_exact(quasi_steady):
    """Q(p_bar) = Q0 + p_bar Q1 is linear in p_bar: the damping perturbation is exact, so every
    g-method root (complex and real) is an eigenvalue of the exact pencil to 1e-6."""
    M, K, Q0, Q1, _ = quasi_steady
    b, rho = 0.5, 1.0
    for V in (1.0, 3.0, 6.0):
        p, *_ = GProblem(ModalSystem(M, K), _poly_gaf(Q0, Q1, 0 * Q1), refc=2 * b).roots(V, rho, 0.0)
        ex = _exact_roots(M, K, Q0, Q1, 0 * Q1, b, rho, V)
        assert p.size == ex.size
        for x in p:
            assert np.min(np.abs(ex - x)) <= 1e-6 * abs(x)
    ds = g_solve(ModalSystem(M, K), _poly_gaf(Q0, Q1, 0 * Q1), [1.0, 3.0], density=rho, mach=0.0,
                 refc=2 * b)
    ex = _exact_roots(M, K, Q0, Q1, 0 * Q1, b, rho, 3.0)
    for x in ds.eigenvalue.values[1]:
        assert np.min(np.abs(ex - x)) <= 1e-6 * abs(x)


def test_local_solve_converges_to_the_exact_roots(quasi_steady):
    """GProblem.correct (inverse iteration and a secant on k, no sweep), started 3 % off each exact
    root of the quasi-steady pencil (where the g-method is exact) with a crude vector (the exact
    one plus 20 % noise), lands on that root to 1e-8; real guesses stay real."""
    M, K, Q0, Q1, _ = quasi_steady
    b, rho, V = 0.5, 1.0, 3.0
    prob = GProblem(ModalSystem(M, K), _poly_gaf(Q0, Q1, 0 * Q1), refc=2 * b)
    ex = _exact_roots(M, K, Q0, Q1, 0 * Q1, b, rho, V)
    s = b / V
    rng = np.random.default_rng(5)
    guesses, vectors = [], []
    for x in ex:
        k = max(x.imag * s, 0.0)
        lam_k, U_k, _ = prob.eig(np.array([k]), V, rho, 0.0)
        j = int(np.argmin(np.abs(lam_k[0] - x * s)))
        guesses.append(x * s * (1.03 if x.imag == 0 else 1.0 + 0.03j))
        vectors.append(U_k[0, j] + 0.2 * rng.normal(size=3))
    real = np.array([x.imag == 0 for x in ex])
    guesses = np.where(real, np.real(guesses) + 0j, guesses)
    vectors = np.array(vectors)
    p, _, _, ok, out = prob.correct(guesses, vectors, vectors.conj(), V, rho, 0.0)
    assert ok.all() and not out.any()
    np.testing.assert_allclose(p / s, ex, rtol=1e-8)
    assert np.all((p.imag == 0) == real) and 0 < real.sum() < real.size


def test_quasi_steady_second_order_error(quasi_steady):
    """With Q2 != 0 the first-order expansion misses g^2 Q2 (g = p_bar - ik): the error is visible
    and, for small Q2, proportional to Q2 (first-order eigenvalue perturbation of the dropped term).
    Measured with Q2 as drawn (V = 3): relative errors 3e-2 and 6e-3 on the real roots, 5e-6 on
    the oscillatory ones."""
    M, K, Q0, Q1, Q2 = quasi_steady
    b, rho, V = 0.5, 1.0, 3.0
    errs = []
    for scale in (1.0, 0.01, 0.005):
        p, *_ = GProblem(ModalSystem(M, K), _poly_gaf(Q0, Q1, scale * Q2), refc=2 * b).roots(V, rho, 0.0)
        ex = _exact_roots(M, K, Q0, Q1, scale * Q2, b, rho, V)
        errs.append(np.array([np.min(np.abs(ex - x)) / abs(x) for x in np.sort_complex(p)]))
    assert errs[0].max() > 1e-3
    np.testing.assert_allclose(errs[1] / errs[2], 2.0, rtol=0.05)


# ----------------------------------------------------------------------------- Nastran bah_plane
@pytest.fixture(scope="module")
def bah():
    case = bah_flutter_502()
    gaf_b, gm, gk, rho, mach, V = (case[key] for key in ("gaf", "gm", "gk", "rho", "mach", "V"))
    summaries = {s["point"]: s for s in case["summaries"]}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ds = g_solve(ModalSystem(np.diag(gm), np.diag(gk)), gaf_b, V, density=rho, mach=mach)
    return dict(ds=ds, V=V, summaries=summaries, caught=[str(w.message) for w in caught],
                refc=gaf_b.attrs["refc"])


def _short_period(ds):
    """The rigid root (in-vacuo modes 1-2) that oscillates at the first speed."""
    f0 = ds.frequency.isel(velocity=0).sel(root=[1, 2]).values
    return int(np.argmax(f0)) + 1


def test_bah_elastic_flutter_matches_f06(bah):
    ref = [(r, first_crossing(s)) for r, s in bah["summaries"].items()]
    ref = [(r, c) for r, c in ref if c is not None and c["frequency"] > 0]
    assert len(ref) == 1
    root_ref, c = ref[0]
    ds = bah["ds"]
    i = [j for j in range(ds.sizes["crossing"]) if ds.crossing_root.values[j] == root_ref][0]
    assert ds.crossing_kind.values[i] == "flutter" and bool(ds.crossing_converged[i])
    assert abs(float(ds.crossing_velocity[i]) / c["velocity"] - 1) < 0.005
    assert abs(float(ds.crossing_frequency[i]) / c["frequency"] - 1) < 0.005


def test_bah_roots_above_k_table_warn_and_flag(bah):
    """Roots 9-10 need k > 10 (the table's end) at low speed: one warning each, not converged."""
    assert any(m.startswith("g-method: root 10 needs k=2") for m in bah["caught"])
    assert sum("root 9 needs" in m for m in bah["caught"]) == 1
    assert not bool(bah["ds"].converged.sel(root=10).isel(velocity=0))
    assert bool(bah["ds"].converged.sel(root=4).all())


def test_bah_plunge_root_near_zero(bah):
    """The other rigid root (plunge / flight path) stays near p = 0 next to the short period."""
    ds = bah["ds"]
    sp = _short_period(ds)
    plunge = 3 - sp
    low = ds.velocity.values <= 200.0
    p_sp = np.abs(ds.eigenvalue.sel(root=sp).values[low])
    p_pl = np.abs(ds.eigenvalue.sel(root=plunge).values[low])
    assert np.all(p_pl < 0.01 * p_sp)


@pytest.mark.xfail(strict=True, reason=(
    "measured: g-method short period 0.080 Hz, g -2.67 at 30 m/s (Nastran 0.090 Hz, -2.29) and "
    "0.360 Hz, g -2.93 at 146 m/s (Nastran 0.412, -2.45): 11-13 % in f, 17-20 % in g. The root "
    "has |g| ~ k (p_bar ~ k(-1.3 + i)), farther from the axis than the branch point of the "
    "aerodynamics at p_bar = 0, so the first-order expansion about ik is outside its radius of "
    "convergence; linear interpolation gives 0.083 Hz, g -2.57. Nastran's PK point 2 is p-k's "
    "approximation, not the exact root: the p-method on the default rational fit (fit error "
    "1.1 %) and the elastic aircraft's flight mechanics agree with each other (|p| within 3 %) "
    "and are 12-17 % below Nastran's |p| (tests/flutter/test_rigid_roots_bah.py); the g-method's "
    "|p| lies 10-15 % above the p-method's. Dropping the -i g dQ^R/dk term from the g-method "
    "reproduces Nastran's PK (0.0898 Hz, g -2.29)."))
def test_bah_short_period_matches_f06(bah):
    """Short period within 5 % in frequency and 10 % in g of Nastran's PK point 2, 30-200 m/s."""
    ds = bah["ds"]
    rows = bah["summaries"][2]["rows"]
    sel = (rows[:, 2] >= 30.0) & (rows[:, 2] <= 200.0)
    ours = ds.sel(velocity=rows[sel, 2], method="nearest").sel(root=_short_period(ds))
    np.testing.assert_allclose(ours.frequency.values, rows[sel, 4], rtol=0.05)
    np.testing.assert_allclose(ours.damping.values, rows[sel, 3], rtol=0.10)


def test_bah_no_unstable_root_below_flutter(bah):
    """No resolved root of ours has g > 1e-3 below the elastic flutter speed and the only crossing
    is root 4's; every root converged there except roots 9-10 above the k table. The plunge drift
    root (|p| b / V < k_min = 0.001, flutter.crossings.drift_roots) turns slightly unstable from
    377 m/s (g 1.7e-3 ... 5.3e-2 at 0.0016-0.0037 Hz, as p-k's root 2: 0.9e-3 ... 1.0e-2 at the
    same frequencies); it is below the tables' resolution and gives no crossing."""
    ds = bah["ds"]
    assert ds.crossing_root.values.tolist() == [4]
    Vf = float(ds.crossing_velocity.values[ds.crossing_root.values == 4][0])
    below = ds.where(ds.velocity < Vf, drop=True)
    p, V = below.eigenvalue.values, below.velocity.values
    drift = drift_roots(p, V, 0.5 * float(bah["refc"]), np.full(V.size, 0.001),
                        below.root.values <= 2)
    assert np.nanmax(resolved_damping(below.damping.values, drift)) <= 1e-3
    conv = ds.converged.where(ds.velocity < Vf, drop=True).sel(root=slice(1, 8))
    assert bool(conv.all())


def test_bah_linear_interpolation_same_flutter_no_drift_crossing(bah):
    """With Q interpolated linearly in k (jumps of dQ/dk at the tabulated k) the only crossing is
    still root 4's elastic flutter, within 0.15 % of the cubic one; the plunge root starts as the
    drift root (|p| b / V < k_min) although the sweep does not see it (it lies below the sweep's
    first k > 0): before the first point's locally solved rigid roots joined the candidates, root 2
    started on a k ~ k_min root and crossed at 363 m/s (0.0013 Hz)."""
    gm, gk, _ = f06_modes_used(F06)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ds = g_solve(ModalSystem(np.diag(gm), np.diag(gk)), bah_qhh_dataset(), bah["V"],
                     density=float(bah["ds"].density[0]), mach=float(bah["ds"].mach[0]),
                     interpolation="linear")
    assert ds.crossing_root.values.tolist() == [4]
    cubic = bah["ds"].crossing_velocity.values[bah["ds"].crossing_root.values == 4][0]
    assert abs(float(ds.crossing_velocity[0]) / cubic - 1) < 1.5e-3
    p0 = ds.eigenvalue.sel(root=2).values[0]
    assert abs(p0) * 0.5 * float(bah["refc"]) / bah["V"][0] < 1e-3


def test_many_cases_forked_equal_in_process():
    """Two cases (densities) on two forked workers give the in-process numbers (1e-12)."""
    V = np.linspace(1.0, 3.0, 12)
    cases = [(V, 1.0, 0.0), (V, 0.8, 0.0)]
    one = g_solve_many(section(), gaf, cases, refc=2 * B)
    two = g_solve_many(section(), gaf, cases, refc=2 * B, workers=2)
    for a, b in zip(one, two):
        np.testing.assert_allclose(b.eigenvalue.values, a.eigenvalue.values, rtol=1e-12, atol=1e-14)
        np.testing.assert_allclose(b.crossing_velocity.values, a.crossing_velocity.values, rtol=1e-12)
    assert one[1].crossing_velocity.values[0] > one[0].crossing_velocity.values[0]


# ----------------------------------------------------------------------------- X-56A-class example
@pytest.fixture(scope="module")
def x56_efew():
    """The shipped example's EFEW configuration (34 modes: 6 free-free rigid + 28 elastic) on the
    case's first matched line (Mach 0.130, 43 points, density sweep), solved by p-k and g."""
    from dataclasses import replace

    from pipeline.case import read_case
    from pipeline.chain import case_flutter, case_grid_gaf, configuration_modes

    case = read_case(DATA.parents[1] / "data" / "x56_like" / "case.toml")
    one = replace(case.flutter, matched=replace(case.flutter.matched, mach=(0.13,)))
    config = next(c for c in case.configurations if c.name == "efew")
    modes, _ = configuration_modes(config)
    grid = case_grid_gaf(replace(case, flutter=one), config)
    out = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # high modes above the k table
        for solver in ("pk", "g"):
            run = replace(case, flutter=replace(one, solver=solver))
            out[solver] = case_flutter(run, config, modes, grid_gaf=grid)["results"][0][1]
    return out, modes.frequency.values


def _x56_crossing(ds, rigid_hz_f0, rigid: bool, f_lo: float, f_hi: float):
    """The first flutter crossing of a root that starts from a rigid (or elastic) mode with a
    frequency in [f_lo, f_hi] Hz: (velocity, frequency, kind)."""
    f0, hits = rigid_hz_f0, []
    for j in range(ds.sizes["crossing"]):
        r = int(ds.crossing_root.values[j])
        if ds.crossing_kind.values[j] in FLUTTER_KINDS and (f0[r - 1] < 0.05) == rigid and \
                f_lo <= float(ds.crossing_frequency[j]) <= f_hi:
            hits.append((float(ds.crossing_velocity[j]), float(ds.crossing_frequency[j]),
                         str(ds.crossing_kind.values[j])))
    assert hits, (ds.crossing_root.values, ds.crossing_frequency.values)
    return min(hits)


@pytest.mark.slow
def test_x56_body_freedom_and_wing_flutter_match_pk(x56_efew):
    """The g-method finds the symmetric body-freedom flutter of the free-free X-56A-class aircraft
    (a root that starts from a rigid-body mode, ~2.0 Hz at ~1667 in/s) and the wing flutter near
    7 Hz at p-k's speed and frequency within 1 % (both methods are exact at g = 0; p-k
    interpolates Q linearly in k, the g-method by cubic splines). Before the rigid roots started
    from the quasi-steady branches (flutter.gtrack), the short period started as a real root and
    the SBFF was missed. Measured: g 1667.6 in/s 2.027 Hz vs p-k 1667.4 / 2.026; wing 1676.1 /
    7.201 vs 1677.1 / 7.175. Every g-method crossing converged, and the short period is an
    oscillatory root at the first point (0.52 Hz; quasi-steady -0.404 + 3.264i rad/s). The SBFF
    is labelled body-freedom flutter (flutter.summary), the wing flutter plain flutter."""
    out, f0 = x56_efew
    g, pk = out["g"], out["pk"]
    assert g.attrs["method"] == "G"
    for rigid, lo, hi in ((True, 1.5, 2.5), (False, 6.0, 8.0)):
        Vg, fg, kind = _x56_crossing(g, f0, rigid, lo, hi)
        Vp, fp, _ = _x56_crossing(pk, f0, rigid, lo, hi)
        assert abs(Vg / Vp - 1) < 0.01 and abs(fg / fp - 1) < 0.01, (rigid, Vg, fg, Vp, fp)
        assert kind == ("body_freedom_flutter" if rigid else "flutter")
    assert bool(g.crossing_converged.all())
    rigid_roots = g.root.values[f0 < 0.05]
    first = g.isel({g.attrs["sweep"]: 0}).sel(root=rigid_roots)
    assert np.max(first.frequency.values) == pytest.approx(0.52, abs=0.01)
