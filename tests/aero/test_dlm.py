"""Doublet-lattice AICs (aero.dlm.dlm_aic): a direct loop-based reference of the same formulas,
independent checks of the kernel and of its sign conventions, k -> 0 consistency, quartic vs
parabolic, XZ symmetry, mesh checks and bad input.

References: Albano & Rodden 1969 (AIAA J. 7(2)) "A&R", Rodden, Taylor & McIntosh 1998 (J. Aircraft
35(5)) "RTM", Desmarais 1982 (AIAA J. 20(10)) for the 12-term approximation of the kernel integrals.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from aero.dlm import check_mesh_for_k, dlm_aic
from aero.panels import caero1_boxes, concat, mirror_xz
from aero.vlm import steady_aic
from structures.common.errors import InputError

A12 = [0.000319759140, -0.000055461471, 0.002726074362, 0.005749551566, 0.031455895072,
       0.106031126212, 0.406838011567, 0.798112357155, -0.417749229098, 0.077480713894,
       -0.012677284771, 0.001787032960]
B12 = 0.009054814793
SAMPLES = {"quartic": [-1.0, -0.5, 0.0, 0.5, 1.0], "parabolic": [-1.0, 0.0, 1.0]}


# ---------------------------------------------------------------------------------------------
# Direct, unoptimised reference: one receiver, one sender, one sample point at a time.
# ---------------------------------------------------------------------------------------------
def ref_integrals(u1, k1):
    """I1 and 3*I2 from the Desmarais sum (RTM eqs. for u1 >= 0; A&R symmetry for u1 < 0)."""
    if u1 < 0.0:
        i1_0, i2_0 = ref_integrals(0.0, k1)
        i1, i2 = ref_integrals(-u1, k1)
        return 2.0 * i1_0.real - np.conj(i1), 2.0 * i2_0.real - np.conj(i2)
    i0 = j0 = 0.0
    for n in range(1, 13):
        pn = B12 * 2.0 ** n
        term = A12[n - 1] * np.exp(-pn * u1)
        i0 += term / (pn + 1j * k1)
        j0 += term * (1.0 + (pn + 1j * k1) * u1) / (pn + 1j * k1) ** 2
    root = np.sqrt(1.0 + u1 * u1)
    i1 = np.exp(-1j * k1 * u1) * (1.0 - u1 / root - 1j * k1 * i0)
    i2_3 = np.exp(-1j * k1 * u1) * ((2.0 + 1j * k1 * u1) * (1.0 - u1 / root)
                                     - u1 / root ** 3 - 1j * k1 * i0 + k1 * k1 * j0)
    return i1, i2_3


def ref_kernel(x0, r1, mach, wv, integrals=ref_integrals):
    """Incremental numerators K1 e^{-i w x0} - K10 and K2 e^{-i w x0} - K20 (A&R eqs. 11-12)."""
    b2 = 1.0 - mach * mach
    R = np.sqrt(x0 * x0 + b2 * r1 * r1)
    phase = np.exp(-1j * wv * x0)
    k10 = -1.0 - x0 / R
    k20 = 2.0 + x0 / R * (2.0 + b2 * r1 * r1 / R ** 2)
    if r1 == 0.0:                       # on the doublet line's streamwise extension: limits
        k1 = -2.0 if x0 > 0.0 else 0.0
        return k1 * phase - k10, 0.0
    k1 = wv * r1
    u1 = (mach * R - x0) / (b2 * r1)
    i1, i2_3 = integrals(u1, k1)
    ex = np.exp(-1j * k1 * u1)
    root = np.sqrt(1.0 + u1 * u1)
    kk1 = -i1 - mach * r1 / R * ex / root
    kk2 = (i2_3 + 1j * k1 * mach ** 2 * r1 ** 2 / R ** 2 * ex / root
           + mach * r1 / R * ((1.0 + u1 * u1) * b2 * r1 ** 2 / R ** 2 + 2.0
                              + mach * r1 * u1 / R) * ex / root ** 3)
    return kk1 * phase - k10, kk2 * phase - k20


def ref_span_integral(coef, ybar, zbar, e, power):
    """int_-e^e sum_m coef_m eta^m / ((eta - ybar)^2 + zbar^2)^power d eta."""
    if power == 1 and abs(zbar) <= 1e-3 * e:            # planar: Hadamard finite part
        a, b = -e - ybar, e - ybar                        # t = eta - ybar
        total = 0.0
        for m, cm in enumerate(coef):
            for p in range(m + 1):                        # eta^m = sum C(m,p) ybar^(m-p) t^p
                w = float(math.comb(m, p)) * ybar ** (m - p)
                if p == 0:
                    part = -1.0 / b + 1.0 / a
                elif p == 1:
                    part = np.log(abs(b / a))
                else:
                    part = (b ** (p - 1) - a ** (p - 1)) / (p - 1)
                total = total + cm * w * part
        return total
    if power == 2 and abs(zbar) <= 1e-3 * e:
        return 0.0
    out = 0.0
    for m, cm in enumerate(coef):
        def f(eta, m=m):
            return eta ** m / ((eta - ybar) ** 2 + zbar ** 2) ** power
        pts = [ybar] if -e < ybar < e else None
        val = quad(f, -e, e, points=pts, epsabs=0.0, epsrel=1e-12, limit=400)[0]
        out = out + cm * val
    return out


def ref_horseshoe(p, nrm, a, b, chord, beta):
    """Normalwash per unit dCp of one horseshoe vortex (vector Biot-Savart, x stretched)."""
    s = np.array([1.0 / beta, 1.0, 1.0])
    p, a, b = p * s, a * s, b * s
    x = np.array([1.0, 0.0, 0.0])
    v = np.zeros(3)
    r1, r2 = p - a, p - b
    c = np.cross(r1, r2)
    if c @ c > 1e-20 * (r1 @ r1) * (r2 @ r2):
        v += c / (c @ c) * ((b - a) @ (r1 / np.linalg.norm(r1) - r2 / np.linalg.norm(r2)))
    for q, sign in ((b, 1.0), (a, -1.0)):
        r = p - q
        h = np.cross(x, r)
        if h @ h > 1e-20 * (r @ r):
            v += sign * h / (h @ h) * (1.0 + r[0] / np.linalg.norm(r))
    return 0.5 * chord * (nrm @ v) / (4.0 * np.pi)


def ref_dlm(mesh, mach, ks, refc, method, symxz=0):
    """D(k) by loops over receivers, senders (and their images) and sample points."""
    beta = np.sqrt(1.0 - mach * mach)
    sig = np.array(SAMPLES[method])
    vander = np.vander(sig, increasing=True)
    senders = [(1.0, mesh)] + ([(-float(symxz), mirror_xz(mesh))] if symxz else [])
    out = np.zeros((len(ks), mesh.n, mesh.n), dtype=complex)
    for kk, k in enumerate(ks):
        wv = k / (0.5 * refc)
        for i in range(mesh.n):
            p, nr = mesh.collocation[i], mesh.normal[i]
            for factor, snd in senders:
                for j in range(mesh.n):
                    a, b = snd.doublet_in[j], snd.doublet_out[j]
                    ns, chord = snd.normal[j], snd.chord[j]
                    steady = ref_horseshoe(p, nr, a, b, chord, beta)
                    mid = 0.5 * (a + b)
                    e = 0.5 * np.hypot(b[1] - a[1], b[2] - a[2])
                    ye = np.array([0.0, b[1] - a[1], b[2] - a[2]]) / (2.0 * e)
                    tanl = (b[0] - a[0]) / (2.0 * e)
                    d = p - mid
                    ybar, zbar = d @ ye, d @ ns
                    p1, p2 = [], []
                    for s in sig:
                        eta = s * e
                        off = p - (mid + eta * ye + eta * tanl * np.array([1.0, 0, 0]))
                        dk1, dk2 = ref_kernel(off[0], np.hypot(off[1], off[2]), mach, wv)
                        p1.append(dk1 * (nr @ ns))
                        p2.append(dk2 * (off @ nr) * (off @ ns))
                    c1 = np.linalg.solve(vander, np.array(p1)) / e ** np.arange(sig.size)
                    c2 = np.linalg.solve(vander, np.array(p2)) / e ** np.arange(sig.size)
                    inc = -chord / (8.0 * np.pi) * (ref_span_integral(c1, ybar, zbar, e, 1)
                                                    + ref_span_integral(c2, ybar, zbar, e, 2))
                    out[kk, i, j] += factor * (steady + inc)
    return out


def small_mesh():
    """Swept tapered wing (3 x 2 boxes), a dihedral outer panel, a vertical fin and a tail
    slightly above the wing plane: planar, near, far and non-planar pairs, x0 of both signs."""
    wing = caero1_boxes(100, [0, 0.2, 0], 1.2, [0.4, 1.6, 0], 0.9, np.linspace(0, 1, 4),
                        [0, 0.4, 1.0])
    outer = caero1_boxes(200, [0.4, 1.6, 0], 0.9, [0.7, 2.6, 0.35], 0.6, [0, 1], [0, 0.5, 1])
    fin = caero1_boxes(300, [2.0, 0.0, 0.1], 0.8, [2.4, 0.0, 1.1], 0.5, [0, 0.5, 1], [0, 1])
    tail = caero1_boxes(400, [2.2, 0.0, 0.3], 0.6, [2.4, 0.9, 0.3], 0.4, [0, 0.5, 1], [0, 1])
    return concat([wing, outer, fin, tail])


def rel_err(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


# ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("method", ["quartic", "parabolic"])
@pytest.mark.parametrize("mach, symxz", [(0.45, 0), (0.0, 0), (0.7, 1), (0.3, -1)])
def test_matches_direct_reference(method, mach, symxz):
    """Vectorised, chunked, threaded AIC = loop reference of the same formulas to 1e-10
    (relative to max |D|) on a planar + non-planar mesh, three k values."""
    mesh = small_mesh()
    ks = [0.05, 0.6, 1.8]
    fast = dlm_aic(mesh, mach, ks, refc=1.1, method=method, symxz=symxz, chunk_size=2)
    ref = ref_dlm(mesh, mach, ks, 1.1, method, symxz)
    assert rel_err(fast, ref) < 1e-10


def test_kernel_against_quadrature():
    """K1, K2 increments with the Desmarais sum against the same formulas with I1, I2 integrated
    adaptively (scipy quad): this is the error of the 12-term approximation itself. Measured on
    these points: at most 5.6e-5 (K1) and 4.0e-4 (K2, which carries 3 I2 and k1^2 J0) absolute,
    on numerators up to |K2| ~ 6; we require 1e-4 and 6e-4."""
    def exact(u1, k1):
        out = []
        for p in (1.5, 2.5):
            f = (lambda u, p=p: np.cos(k1 * u) / (1 + u * u) ** p,
                 lambda u, p=p: -np.sin(k1 * u) / (1 + u * u) ** p)
            val = sum(s * quad(g, u1, 60.0, limit=400, epsabs=1e-12)[0] for s, g in
                      zip((1.0, 1j), f))
            tail = sum(s * quad(g, 60.0, np.inf, weight=w, wvar=k1, limit=400)[0]
                       for s, g, w in zip((1.0, -1j), (lambda u, p=p: (1 + u * u) ** -p,) * 2,
                                          ("cos", "sin"))) if k1 > 0 else \
                quad(lambda u, p=p: (1 + u * u) ** -p, 60.0, np.inf)[0]
            out.append(val + tail)
        return out[0], 3.0 * out[1]

    for x0, r1, mach, wv in [(1.0, 0.5, 0.5, 2.0), (-1.0, 0.7, 0.5, 2.0), (0.3, 1.0, 0.8, 0.7),
                             (2.0, 0.1, 0.3, 3.0), (-0.2, 0.05, 0.0, 1.0), (4.0, 2.0, 0.6, 0.4),
                             (0.5, 3.0, 0.5, 4.0)]:
        approx = ref_kernel(x0, r1, mach, wv)
        direct = ref_kernel(x0, r1, mach, wv, integrals=exact)
        assert abs(approx[0] - direct[0]) < 1e-4
        assert abs(approx[1] - direct[1]) < 6e-4


@pytest.mark.parametrize("mach", [0.0, 0.6])
def test_steady_kernel_equals_horseshoe(mach):
    """Sign conventions: -chord/(8 pi) int (K10 T1/r1^2 + K20 T2*/r1^4) d eta over the doublet line
    (A&R eq. 16 at k = 0 with RTM's P = -(K - K0) T sign) equals the horseshoe normalwash of
    aero.vlm for non-planar pairs (receiver on a fin, above a dihedral box, ...), to 1e-8
    (quadrature accuracy). This fixes the sign of the unsteady increment relative to the
    steady part."""
    snd = caero1_boxes(1, [0.2, 0.3, 0.1], 0.8, [0.5, 1.3, 0.45], 0.6, [0, 1], [0, 1])
    rec = concat([caero1_boxes(2, [1.5, 0.8, -0.4], 0.5, [1.7, 0.9, 1.2], 0.5, [0, 1], [0, 1]),
                  caero1_boxes(3, [-0.5, 0.6, 0.9], 0.5, [-0.3, 1.4, 0.8], 0.5, [0, 1], [0, 1]),
                  caero1_boxes(4, [0.9, -0.6, 0.0], 0.5, [1.2, -1.4, 0.6], 0.5, [0, 1], [0, 1])])
    b2 = 1.0 - mach ** 2
    a, b = snd.doublet_in[0], snd.doublet_out[0]
    e = 0.5 * np.hypot(*(b - a)[1:])
    ye = np.array([0.0, *(b - a)[1:]]) / (2 * e)
    tanl = (b - a)[0] / (2 * e)
    mid, ns = 0.5 * (a + b), snd.normal[0]
    vlm = steady_aic(concat([snd, rec]), mach)[1:, 0]
    for i in range(rec.n):
        p, nr = rec.collocation[i], rec.normal[i]

        def integrand(eta):
            off = p - (mid + eta * ye + eta * tanl * np.array([1.0, 0, 0]))
            r2 = off[1] ** 2 + off[2] ** 2
            R = np.sqrt(off[0] ** 2 + b2 * r2)
            k10 = -1.0 - off[0] / R
            k20 = 2.0 + off[0] / R * (2.0 + b2 * r2 / R ** 2)
            return k10 * (nr @ ns) / r2 + k20 * (off @ nr) * (off @ ns) / r2 ** 2

        val = -snd.chord[0] / (8 * np.pi) * quad(integrand, -e, e, epsabs=0, epsrel=1e-12)[0]
        assert val == pytest.approx(vlm[i], rel=1e-8, abs=1e-12)


def test_nonplanar_increment_against_direct_integration():
    """A wing box and a vertical-fin box sending to each other: the polynomial-fit increment
    against adaptive integration of the exact incremental numerator (same kernel formulas) along
    the doublet line. Halving the box span must shrink the error by the fit's order, 2^5 for the
    quartic (we require >= 20x) and 2^3 for the parabola (>= 6x); measured quartic errors at
    span 0.125 are 1e-8 and 7e-7 of the increment (we require < 2e-6)."""
    mach, k, refc = 0.5, 0.5, 1.0
    wv = k / (0.5 * refc)
    errors = {"quartic": [], "parabolic": []}
    for h in (0.5, 0.25, 0.125):
        wing = caero1_boxes(1, [0.0, 0.1, 0.0], 0.5, [0.1, 0.1 + h, 0.0], 0.5, [0, 1], [0, 1])
        fin = caero1_boxes(2, [1.0, 0.3, 0.2], 0.5, [1.1, 0.3, 0.2 + h], 0.5, [0, 1], [0, 1])
        mesh = concat([wing, fin])
        d0 = steady_aic(mesh, mach)
        for method in errors:
            inc = dlm_aic(mesh, mach, [k], refc=refc, method=method)[0] - d0
            errs = []
            for i, j in ((1, 0), (0, 1)):
                a, b = mesh.doublet_in[j], mesh.doublet_out[j]
                e = 0.5 * np.hypot(*(b - a)[1:])
                ye = np.array([0.0, *(b - a)[1:]]) / (2 * e)
                tanl = (b - a)[0] / (2 * e)
                mid, ns = 0.5 * (a + b), mesh.normal[j]
                p, nr = mesh.collocation[i], mesh.normal[i]

                def integrand(eta, part):
                    off = p - (mid + eta * ye + eta * tanl * np.array([1.0, 0, 0]))
                    r2 = off[1] ** 2 + off[2] ** 2
                    dk1, dk2 = ref_kernel(off[0], np.sqrt(r2), mach, wv)
                    val = dk1 * (nr @ ns) / r2 + dk2 * (off @ nr) * (off @ ns) / r2 ** 2
                    return val.real if part == 0 else val.imag

                direct = -mesh.chord[j] / (8 * np.pi) * (
                    quad(integrand, -e, e, args=(0,), epsrel=1e-12)[0]
                    + 1j * quad(integrand, -e, e, args=(1,), epsrel=1e-12)[0])
                errs.append(abs(inc[i, j] - direct) / abs(direct))
            errors[method].append(errs)
    q, p = np.array(errors["quartic"]), np.array(errors["parabolic"])
    assert np.all(q[:-1] / q[1:] > 20.0)
    assert np.all(p[:-1] / p[1:] > 6.0)
    assert np.all(q[-1] < 2e-6)


def test_zero_frequency_is_steady_and_small_k_is_linear():
    """D(0) = D_steady (to round-off) and |D(k) - D_steady| ~ c k for k in 1e-3..1e-2: the log-log
    slope fitted over four k is 1 within 0.02 (the leading increment is i k times a real matrix)."""
    mesh = small_mesh()
    d0 = steady_aic(mesh, 0.45)
    assert rel_err(dlm_aic(mesh, 0.45, [0.0], refc=1.0)[0], d0) < 1e-13
    ks = np.geomspace(1e-3, 1e-2, 4)
    d = dlm_aic(mesh, 0.45, ks, refc=1.0)
    err = np.abs(d - d0).max(axis=(1, 2))
    slope = np.polyfit(np.log(ks), np.log(err), 1)[0]
    assert slope == pytest.approx(1.0, abs=0.02)


@pytest.fixture(scope="module")
def plunging_wing():
    """Lift of a rectangular AR-12 wing (half model, symxz=+1, 6 x 36 square boxes, M 0) in
    plunge h/b = 1, per k, both methods, normalised by its quasi-steady value -2 pi i k ... (the
    steady-lattice lift for w/V = i k): a 3-D lift-deficiency ratio."""
    mesh = caero1_boxes(1, [0, 0, 0], 1.0, [0, 6, 0], 1.0, np.linspace(0, 1, 37),
                        np.linspace(0, 1, 7))
    ks = np.array([0.05, 0.3, 1.0])
    lift0 = np.linalg.solve(steady_aic(mesh, 0.0, symxz=1), np.ones(mesh.n)) @ mesh.area
    out = {}
    for method in ("quartic", "parabolic"):
        d = dlm_aic(mesh, 0.0, ks, refc=1.0, method=method, symxz=1)
        out[method] = np.array([np.linalg.solve(d[i], np.ones(mesh.n)) @ mesh.area
                                for i in range(ks.size)]) / lift0
    return ks, out


def theodorsen_ratio(k):
    """Theodorsen plunge lift pi k^2 - 2 pi i k C(k) (Bisplinghoff, Ashley & Halfman eq. 5-311,
    h/b = 1) over its quasi-steady value -2 pi i k."""
    from scipy.special import hankel2
    c = hankel2(1, k) / (hankel2(1, k) + 1j * hankel2(0, k))
    return (np.pi * k * k - 2j * np.pi * k * c) / (-2j * np.pi * k)


def test_plunge_lift_follows_theodorsen_trend(plunging_wing):
    """Sign and size of the unsteady increment: the 3-D lift-deficiency ratio behaves like
    Theodorsen's 2-D one (real part falls with k, lag at small k, apparent-mass lead at k = 1) and
    stays within 0.12 of it (measured 0.06-0.10: finite wings have less lift deficiency than 2-D
    sections). A wrong sign of the increment moves the ratio above 1."""
    ks, out = plunging_wing
    r = out["quartic"]
    assert np.all(np.diff(r.real) < 0.0)
    assert r[0].imag < 0.0 < r[-1].imag
    assert np.all(np.abs(r - theodorsen_ratio(ks)) < 0.12)


def test_quartic_and_parabolic(plunging_wing):
    """Both methods share the steady part and approximate the same numerator: the plunge lift
    agrees to 5e-4 at k = 0.05 (measured 1.3e-4) and differs by more than 1 % at k = 1 (measured
    2.9 %), where the numerator varies faster along the boxes than a parabola can follow."""
    ks, out = plunging_wing
    diff = np.abs(out["quartic"] - out["parabolic"]) / np.abs(out["quartic"])
    assert diff[0] < 5e-4
    assert diff[-1] > 0.01
    mesh = small_mesh()
    d0 = steady_aic(mesh, 0.45)
    for method in ("quartic", "parabolic"):
        assert rel_err(dlm_aic(mesh, 0.45, [0.0], refc=1.0, method=method)[0], d0) < 1e-13


@pytest.mark.parametrize("symxz", [1, -1])
def test_half_model_equals_mirrored_full_model(symxz):
    """Half model with symxz = +-1 equals the full model (left half defined right-to-left, so its
    normals point down) under symmetric / antisymmetric loading, to 1e-10, several k."""
    fs, fc = np.linspace(0, 1, 4), np.linspace(0, 1, 3)
    right = caero1_boxes(100, [0, 0.0, 0], 1.5, [0.6, 3, 0.4], 0.8, fs, fc)
    left = caero1_boxes(200, [0, 0.0, 0], 1.5, [0.6, -3, 0.4], 0.8, fs, fc)
    ks = [0.1, 0.8, 2.0]
    full = dlm_aic(concat([right, left]), 0.5, ks, refc=1.5)
    half = dlm_aic(right, 0.5, ks, refc=1.5, symxz=symxz)
    n = right.n
    # dCp_left = -symxz dCp_right in the left boxes' own (downward) normal
    expect = full[:, :n, :n] - symxz * full[:, :n, n:]
    assert rel_err(half, expect) < 1e-10
    # and the left receivers see minus (symmetric) / plus (antisymmetric) the right normalwash
    left_rows = full[:, n:, :n] - symxz * full[:, n:, n:]
    assert rel_err(-symxz * left_rows, expect) < 1e-10


def test_chunking_and_threads_do_not_change_results():
    mesh = small_mesh()
    base = dlm_aic(mesh, 0.6, [0.3, 1.2], refc=1.0, workers=1)
    for kwargs in ({"chunk_size": 1}, {"chunk_size": 1000}, {"workers": 3}):
        assert rel_err(dlm_aic(mesh, 0.6, [0.3, 1.2], refc=1.0, **kwargs), base) < 1e-14


def test_each_k_matches_single_k_calls():
    mesh = small_mesh()
    ks = [0.2, 0.9, 2.5]
    many = dlm_aic(mesh, 0.5, ks, refc=1.0)
    for i, k in enumerate(ks):
        assert rel_err(many[i], dlm_aic(mesh, 0.5, k, refc=1.0)[0]) < 1e-14


def test_check_mesh_for_k():
    """0.08 V/f rule (box chord < 0.08 * 2 pi b / k) and aspect ratio in [0.25, 4]."""
    fine = caero1_boxes(11, [0, 0, 0], 1.0, [0, 1, 0], 1.0, np.linspace(0, 1, 11),
                        np.linspace(0, 1, 11))
    assert check_mesh_for_k(fine, 0.5, 0.5, 1.0) == []                    # limit 0.50 > 0.1
    msgs = check_mesh_for_k(fine, 0.5, 6.0, 1.0)                          # limit 0.042 < 0.1
    assert len(msgs) == 1 and "CAERO1 11" in msgs[0] and "0.08 V/f" in msgs[0]
    slender = caero1_boxes(12, [0, 0, 0], 1.0, [0, 1, 0], 1.0, [0, 1], np.linspace(0, 1, 11))
    msgs = check_mesh_for_k(slender, 0.5, 0.1, 1.0)
    assert len(msgs) == 1 and "aspect ratio" in msgs[0] and "CAERO1 12" in msgs[0]


@pytest.mark.parametrize("mach", [1.0, 1.5, -0.2])
def test_mach_out_of_range(mach):
    with pytest.raises(InputError, match=r"outside \[0, 1\).*M >= 1"):
        dlm_aic(small_mesh(), mach, [0.1], refc=1.0)


def test_unknown_method_lists_valid():
    with pytest.raises(InputError, match=r"unknown doublet-lattice method 'cubic'.*quartic.*"
                                         r"parabolic"):
        dlm_aic(small_mesh(), 0.5, [0.1], refc=1.0, method="cubic")


@pytest.mark.parametrize("k", [[-0.1], [0.1, -1e-3], [np.nan], []])
def test_bad_reduced_frequency(k):
    with pytest.raises(InputError, match="k >= 0"):
        dlm_aic(small_mesh(), 0.5, k, refc=1.0)


def test_collocation_on_a_side_edge_line_raises():
    """A coplanar panel whose strip mid-line lies on another panel's box edge line: the planar
    kernel's finite part is singular there (as in Nastran); we fail loudly naming the boxes."""
    wing = caero1_boxes(1, [0, 0, 0], 1.0, [0, 2, 0], 1.0, [0, 0.5, 1], [0, 1])
    tail = caero1_boxes(9, [3, 0.5, 0], 1.0, [3, 1.5, 0], 1.0, [0, 1], [0, 1])    # mid-line y = 1
    with pytest.raises(InputError, match=r"singular for receiving box (1|2|9) and sending box (1|2|9).*Fix"):
        dlm_aic(concat([wing, tail]), 0.5, [0.3], refc=1.0)


def test_bad_refc_and_chunk():
    with pytest.raises(InputError, match="REFC"):
        dlm_aic(small_mesh(), 0.5, [0.1], refc=0.0)
    with pytest.raises(InputError, match="chunk_size"):
        dlm_aic(small_mesh(), 0.5, [0.1], refc=1.0, chunk_size=0)


def test_sincos_table_rotation_accuracy():
    """aero.dlm_kernel.sincos (table + 2-term rotation, used for every phase) against np.cos and
    np.sin: error at most 4 eps (1 + |x|) (measured 3.1 eps (1 + |x|), i.e. the rounding of
    x / h), for |x| up to 7e3."""
    from aero.dlm_kernel import sincos
    x = np.concatenate([np.linspace(-50.0, 50.0, 100001), [0.0, -0.0, 1e-300, 1e3, -7e3]])
    c, s = sincos(x)
    tol = 4.0 * np.finfo(float).eps * (1.0 + np.abs(x))
    assert np.all(np.abs(c - np.cos(x)) <= tol)
    assert np.all(np.abs(s - np.sin(x)) <= tol)


def test_block_geometry_matches_direct_formulas():
    """The cancellation-free forms used per (receiver, point) pair equal the A&R eq. 11-12
    expressions evaluated directly (u1, sqrt(1 + u1^2), 1 - |u1|/sqrt(1 + u1^2), M r1/R/
    sqrt(1 + u1^2), exp(-p_n |u1|)), including points on the doublet line's streamwise
    extension (r1 = 0) and both signs of x0; relative 1e-13 (the Desmarais terms 2e-12 + 1e-74
    absolute: they are formed by repeated squaring from a floor of 1e-37 every third square)."""
    from aero.dlm_kernel import DESMARAIS_P, Scratch, block_geometry, point_factors
    rng = np.random.default_rng(3)
    mach = 0.7
    b2 = 1.0 - mach * mach
    r1 = np.concatenate([rng.uniform(0.01, 3.0, 40), [0.0, 0.0, 1e-3]])
    x0 = np.concatenate([rng.uniform(-4.0, 4.0, (3, 40)), [[0.5, -0.5, 2.0]] * 3], axis=1)
    geo = block_geometry(x0, point_factors(r1, mach, np.array([0.7])), mach, Scratch())
    R = np.sqrt(x0 ** 2 + b2 * r1 ** 2)
    ok = r1 > 0.0
    u1 = (mach * R[:, ok] - x0[:, ok]) / (b2 * r1[ok])
    root = np.sqrt(1.0 + u1 * u1)
    np.testing.assert_allclose(geo["R"], R, rtol=1e-14)
    np.testing.assert_allclose(geo["q1"], 1.0 + x0 / R, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(geo["rmx"][:, ok], b2 * r1[ok] * root, rtol=1e-13)
    np.testing.assert_allclose(geo["f"][:, ok], 1.0 - np.abs(u1) / root, rtol=1e-11, atol=1e-14)
    np.testing.assert_allclose(geo["A"][:, ok], mach * r1[ok] / R[:, ok] / root, rtol=1e-13)
    np.testing.assert_array_equal(geo["neg"][:, ok], u1 < 0.0)
    en = np.exp(-DESMARAIS_P[:, None, None] * np.abs(u1)[None])
    # documented: relative 2^11 eps from the squares, terms below 1e-74 raised to <= 1e-74
    assert np.all(np.abs(geo["en"][:, :, ok] - en) <= 2e-12 * en + 1.01e-74)   # (1e-37)^2
    # on the line's extension: Desmarais terms 0 (<= 1e-74), f = 0, u1 < 0 downstream only
    assert np.all(geo["en"][:, :, ~ok] <= 1.01e-74) and np.all(geo["f"][:, ~ok] == 0.0)
    np.testing.assert_array_equal(geo["neg"][:, ~ok], x0[:, ~ok] > 0.0)


def test_mirror_strips_share_kernel_values_exactly():
    """A full-span model (left half defined right-to-left, dihedral, and a pair of canted fins):
    receiving strips whose mirror strip exists reuse its kernel values at the mirrored sending
    points (aero.dlm._mirror_pairs). The AIC still equals the loop reference to 1e-10 (planar and
    non-planar pairs, three k), and equals the evaluation of the same mesh with the pairing
    disabled to 1e-14 (the reuse is exact: r1 and x0 are bitwise the same)."""
    from aero import dlm as dlm_module
    fs, fc = [0.0, 0.4, 1.0], [0.0, 0.5, 1.0]
    right = caero1_boxes(100, [0, 0.0, 0], 1.2, [0.5, 2.0, 0.3], 0.7, fs, fc)
    left = caero1_boxes(200, [0, 0.0, 0], 1.2, [0.5, -2.0, 0.3], 0.7, fs, fc)
    fin_r = caero1_boxes(300, [1.5, 0.8, 0.05], 0.6, [1.8, 1.0, 0.9], 0.4, [0, 0.5, 1], [0, 1])
    fin_l = caero1_boxes(400, [1.5, -0.8, 0.05], 0.6, [1.8, -1.0, 0.9], 0.4, [0, 0.5, 1], [0, 1])
    mesh = concat([right, left, fin_r, fin_l])
    ks = [0.1, 0.7, 1.6]
    strips = dlm_module._strips(mesh)
    snd = dlm_module._senders(mesh, np.array(SAMPLES["quartic"]), np.array(ks))
    assert len(dlm_module._mirror_pairs(mesh, strips, [(1.0, snd)])) == len(strips) // 2
    fast = dlm_aic(mesh, 0.6, ks, refc=1.2)
    assert rel_err(fast, ref_dlm(mesh, 0.6, ks, 1.2, "quartic")) < 1e-10
    original = dlm_module._mirror_pairs
    try:
        dlm_module._mirror_pairs = lambda mesh, strips, senders: [(i,) for i in range(len(strips))]
        unpaired = dlm_aic(mesh, 0.6, ks, refc=1.2)
    finally:
        dlm_module._mirror_pairs = original
    assert rel_err(fast, unpaired) < 1e-14
