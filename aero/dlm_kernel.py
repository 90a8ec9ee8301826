"""Doublet-lattice incremental kernel: numerators at the sample points and span weights.

Notation and equations follow Albano & Rodden (1969), "A doublet-lattice method for calculating
lift distributions on oscillating surfaces in subsonic flows", AIAA J. 7(2) 279-285 (A&R), with the
kernel of Landahl (1967) and the quartic refinement of Rodden, Taylor & McIntosh (1998), "Further
refinement of the subsonic doublet-lattice method", J. Aircraft 35(5) 720-727 (RTM).

For a receiving point and a point of the sending doublet line, with x0 the streamwise offset
(receiver minus sender), r1 the offset in the y-z plane, beta^2 = 1 - M^2 and omega/V = k/b:

    R  = sqrt(x0^2 + beta^2 r1^2),  u1 = (M R - x0) / (beta^2 r1),  k1 = omega r1 / V
    K1 = -I1 - M r1 / R * exp(-i k1 u1) / sqrt(1 + u1^2)                          (A&R eq. 11)
    K2 = 3 I2 + i k1 M^2 r1^2/R^2 exp(-i k1 u1)/sqrt(1 + u1^2)
         + M r1/R [(1 + u1^2) beta^2 r1^2/R^2 + 2 + M r1 u1/R] exp(-i k1 u1)/(1 + u1^2)^(3/2)
    K10 = -1 - x0/R,  K20 = 2 + x0/R (2 + beta^2 r1^2/R^2)          (steady values, A&R eq. 12)
    I1 = int_u1^inf exp(-i k1 u)/(1+u^2)^(3/2) du,  I2 = int_u1^inf exp(-i k1 u)/(1+u^2)^(5/2) du

I1 and I2 use the 12-term exponential approximation of Desmarais (1982, NASA TP-2060 / AIAA J.
20(10)), 1 - u/sqrt(1+u^2) ~ sum_n a_n exp(-p_n u), p_n = b 2^n, as used by RTM, which gives
(u >= 0)

    I1  = exp(-i k1 u) [1 - u/sqrt(1+u^2) - i k1 I0]
    3I2 = exp(-i k1 u) [(2 + i k1 u)(1 - u/sqrt(1+u^2)) - u/(1+u^2)^(3/2) - i k1 I0 + k1^2 J0]
    I0  = sum a_n e^{-p_n u}/(p_n + i k1)
    J0  = sum a_n e^{-p_n u} (1 + (p_n + i k1) u)/(p_n + i k1)^2

and for u < 0 the symmetry I(u) = 2 Re I(0) - conj(I(-u)) (A&R; the integrands' real parts are
even and their imaginary parts odd in u). The incremental numerators are
P1 = -(K1 exp(-i omega x0/V) - K10) T1 and P2 = -(K2 exp(-i omega x0/V) - K20) T2* (RTM; the
minus sign is applied by aero.dlm) with T1 = n_r . n_s and T2* = (d . n_r)(d . n_s) (A&R eqs. 8-9;
d the receiver-minus-sender offset).

P1, P2 are interpolated along the doublet line (eta in [-e, e]) by a parabola through eta = -e,
0, e (A&R) or a quartic through eta = -e, -e/2, 0, e/2, e (RTM), and the interpolants are
integrated exactly against 1/r1^2 and 1/r1^4 (RTM's closed forms written here as the moment
recurrences of :func:`span_weights`). Two numerical choices are ours and documented:
a sending/receiving pair with |z| <= 1e-3 e is treated as planar (finite-part integral, no P2
term; RTM's near-planar case), and far pairs (ybar^2 + zbar^2 >= 16 e^2) integrate the 1/r1^4 term
with a 10-point Gauss-Legendre rule (error below 1e-15 there, since the poles are at least
Bernstein-ellipse parameter 7.8 away) instead of RTM's far-field series, avoiding the
cancellation of the closed form.
"""
from __future__ import annotations

import math

import numpy as np

__all__ = ["DESMARAIS_A", "DESMARAIS_P", "SAMPLES", "FIT", "NEAR_PLANAR", "FAR2", "Scratch",
           "sincos", "point_factors", "block_geometry", "incremental_k1", "incremental_k2",
           "span_weights"]

# Desmarais (1982) 12-term coefficients of 1 - u/sqrt(1+u^2) ~ sum a_n exp(-p_n u), p_n = b 2^n.
DESMARAIS_A = np.array([0.000319759140, -0.000055461471, 0.002726074362, 0.005749551566,
                        0.031455895072, 0.106031126212, 0.406838011567, 0.798112357155,
                        -0.417749229098, 0.077480713894, -0.012677284771, 0.001787032960])
DESMARAIS_P = 0.009054814793 * 2.0 ** np.arange(1, 13)

# Sample points along the doublet line (sigma = eta / e) and the matrices that map sample values
# to polynomial coefficients in sigma (RTM quartic, A&R parabolic).
SAMPLES = {"quartic": np.array([-1.0, -0.5, 0.0, 0.5, 1.0]),
           "parabolic": np.array([-1.0, 0.0, 1.0])}
FIT = {name: np.linalg.inv(np.vander(s, increasing=True)) for name, s in SAMPLES.items()}

NEAR_PLANAR = 1e-3         # |zbar| / e at or below which a pair is planar
FAR2 = 16.0                # (ybar^2 + zbar^2) / e^2 from which the 1/r^4 term uses Gauss-Legendre
_GL_X, _GL_W = np.polynomial.legendre.leggauss(10)

_NTAB = 16384
_H = 2.0 * np.pi / _NTAB
_COS_TAB, _SIN_TAB = np.cos(_H * np.arange(_NTAB)), np.sin(_H * np.arange(_NTAB))
_ROUND = 1.5 * 2.0 ** 52   # t + _ROUND - _ROUND rounds t to an integer (|t| < 2^51)


def _new(name, shape, dtype=float):
    """Default scratch provider: a fresh array (see :class:`Scratch`)."""
    return np.empty(shape, dtype=dtype)


class Scratch:
    """Reusable named work arrays (one instance per thread).

    ``scratch(name, shape, dtype)`` returns a C-contiguous view of a cached buffer, so that the
    kernel's per-block temporaries are allocated once instead of once per block (fresh large
    arrays cost page faults that took more time than the arithmetic). An array obtained under a
    name is valid until the same name is requested again.
    """

    def __init__(self):
        self._buf = {}

    def __call__(self, name, shape, dtype=float):
        size = math.prod(shape)
        buf = self._buf.get((name, np.dtype(dtype).str))
        if buf is None or buf.size < size:
            buf = np.empty(max(size, 1), dtype=dtype)
            self._buf[(name, np.dtype(dtype).str)] = buf
        return buf[:size].reshape(shape)


def sincos(x: np.ndarray, scratch=_new):
    """cos(x), sin(x) to ~3 eps (1 + |x|) (|x| < 1e15), several times faster than np.cos + np.sin.

    x = j h + d with h = 2 pi / 16384 and |d| <= h/2: table values of cos/sin(j h) rotated by d
    through cos d = 1 - d^2/2, sin d = d - d^3/6 (truncation below 6e-17 for |d| <= 1.9e-4).
    j is rounded with the 1.5 * 2^52 shift, whose low mantissa bits are j mod 16384.
    ``scratch`` (see :class:`Scratch`) provides the work and result arrays.
    """
    shape = np.shape(x)
    t = np.multiply(x, 1.0 / _H, out=scratch("sc_t", shape))
    big = np.add(t, _ROUND, out=scratch("sc_b", shape))
    idx = np.bitwise_and(big.view(np.int64), _NTAB - 1, out=scratch("sc_i", shape, np.int64))
    big -= _ROUND                                       # j
    t -= big
    t *= _H                                             # d
    ct = np.take(_COS_TAB, idx, out=scratch("sc_cos", shape), mode="clip")
    st = np.take(_SIN_TAB, idx, out=scratch("sc_sin", shape), mode="clip")
    d2 = np.multiply(t, t, out=big)
    cd = np.multiply(d2, -0.5, out=scratch("sc_cd", shape))
    cd += 1.0                                           # cos d
    d2 *= -1.0 / 6.0
    d2 += 1.0
    d2 *= t                                             # sin d
    c = np.multiply(ct, cd, out=scratch("sc_c", shape))
    c -= np.multiply(st, d2, out=t)
    st *= cd
    ct *= d2
    st += ct
    return c, st


_AP = DESMARAIS_A * DESMARAIS_P
_P2 = DESMARAIS_P ** 2


def point_factors(r1: np.ndarray, mach: float, wv: np.ndarray) -> dict:
    """Factors of the kernel that depend only on a sample point's y-z distance r1 to a strip.

    With b2 = 1 - M^2, k1 = (omega/V) r1, kappa = k1^2 and c_n = 1/(p_n^2 + kappa):

    ``c1`` = b2 r1^2, ``ib`` = 1/(b2 r1) (inf where r1 = 0), ``fn`` = (b2 r1)^2,
    ``am`` = M b2 r1^2, ``mp1`` = -p_1 ib, and per frequency ``w2`` = kappa a_n c_n,
    ``w1`` = k1 a_n p_n c_n (nk, 12, m) and ``c0`` = 2 (1 - kappa sum_n a_n c_n) (nk, m)
    = 2 Re I1(0).

    Parameters
    ----------
    r1 : (m,) float, >= 0
    mach : float
    wv : (nk,) float
        omega / V = k / b.
    """
    b2 = 1.0 - mach * mach
    # the frequency factors depend on r1 alone: evaluate them once per distinct value (a strip's
    # sample points at one spanwise station share it) and gather
    r1d, back = np.unique(r1, return_inverse=True)
    back = back.ravel()
    k1 = wv[:, None] * r1d[None, :]
    kappa = k1 * k1
    c = np.reciprocal(kappa[:, None, :] + _P2[None, :, None])     # (nk, 12, D)
    # (einsum rather than matmul: no BLAS threads spinning for these small products)
    c0 = 2.0 - 2.0 * kappa * np.einsum("n,knd->kd", DESMARAIS_A, c)
    with np.errstate(divide="ignore"):
        ib = 1.0 / (b2 * r1)
    w2 = (c * (DESMARAIS_A[None, :, None] * kappa[:, None, :])).take(back, axis=-1)
    w1 = (c * (_AP[None, :, None] * k1[:, None, :])).take(back, axis=-1)
    return {"r1": r1, "c1": b2 * r1 * r1, "ib": ib, "fn": (b2 * r1) ** 2,
            "am": mach * b2 * r1 * r1, "mp1": -DESMARAIS_P[0] * ib, "w2": w2, "w1": w1,
            "c0": c0.take(back, axis=-1)}


def block_geometry(x0: np.ndarray, pf: dict, mach: float, scratch=_new) -> dict:
    """Geometry-only factors of the kernel for r receivers and m points (shared by all k).

    Parameters
    ----------
    x0 : (r, m) float
        Streamwise offsets (receiver minus sending point); x0 != 0 where r1 == 0.
    pf : dict
        :func:`point_factors` of the m points (r1 shared by the r receivers of one strip).
    mach : float
        0 <= M < 1.

    Returns
    -------
    dict of (r, m) arrays
        ``x0``; ``R`` = sqrt(x0^2 + b2 r1^2); ``q1`` = 1 + x0/R = -K10 (A&R eq. 12);
        ``rmx`` = R - M x0 = b2 r1 sqrt(1 + u1^2) > 0; ``v`` = M R - x0 = b2 r1 u1 (A&R eq. 11);
        ``f`` = 1 - |u1|/sqrt(1 + u1^2) = (b2 r1)^2 / (rmx (rmx + |v|)) (cancellation-free);
        ``A`` = M r1/R / sqrt(1 + u1^2) = M b2 r1^2 / (R rmx); and ``en`` (12, r, m) =
        exp(-p_n |u1|); ``sv`` = sign(v) and ``neg`` = (v < 0). The arrays come from
        ``scratch`` (:class:`Scratch`).
    """
    sh = x0.shape
    R = np.multiply(x0, x0, out=scratch("g_R", sh))
    R += pf["c1"]
    np.sqrt(R, out=R)
    q1 = np.divide(x0, R, out=scratch("g_q1", sh))
    q1 += 1.0
    rmx = np.multiply(x0, -mach, out=scratch("g_rmx", sh))
    rmx += R
    v = np.multiply(R, mach, out=scratch("g_v", sh))
    v -= x0
    av = np.abs(v, out=scratch("g_sv", sh))
    f = np.add(av, rmx, out=scratch("g_f", sh))
    f *= rmx
    np.divide(pf["fn"], f, out=f)
    A = np.multiply(R, rmx, out=scratch("g_A", sh))
    np.divide(pf["am"], A, out=A)
    # Desmarais terms exp(-p_n |u1|) with p_{n+1} = 2 p_n: one exp, then squares (relative error
    # <= 2^11 eps). Every third square starts from max(e, 1e-37), so that three squares stay
    # above 1e-296, out of the slow subnormal range; this raises terms below 1e-74 to at most
    # 1e-74, negligible against the others (weights |a_n| k1^2 / (p_n^2 + k1^2) < 1).
    en = scratch("g_en", (12,) + sh)
    np.multiply(av, pf["mp1"], out=en[0])
    np.exp(en[0], out=en[0])
    for n in range(1, 12):
        if n % 3 == 1:
            np.maximum(en[n - 1], 1e-37, out=en[n])
            en[n] *= en[n]
        else:
            np.multiply(en[n - 1], en[n - 1], out=en[n])
    sv = np.copysign(1.0, v, out=av)                    # -sgn of the I(u) symmetry branch
    neg = np.less(v, 0.0, out=scratch("g_neg", sh, bool))
    return {"x0": x0, "R": R, "q1": q1, "rmx": rmx, "v": v, "f": f, "A": A, "en": en, "sv": sv,
            "neg": neg}


def incremental_k1(geo: dict, pf: dict, kk: int, wv: float, mach: float, cosx: np.ndarray,
                   sinx: np.ndarray, re: np.ndarray, im: np.ndarray, scratch=_new) -> None:
    """Real and imaginary parts of K1 exp(-i omega x0/V) - K10 (A&R eq. 11) for one frequency.

    With S1 = sum a_n p_n c_n e_n and S2 = sum a_n c_n e_n (c_n = 1/(p_n^2 + k1^2)),
    1 - u/sqrt(1+u^2) - i k1 I0 = f - k1^2 S2 - i k1 S1 and Re I1(0) = 1 - k1^2 S0, so that
    K1 exp(-i omega x0/V) = -[sgn (f - k1^2 S2) - A - i k1 S1] exp(-i (k1 u1 + omega x0/V))
    - 2 Re I1(0) [u1 < 0] exp(-i omega x0/V), sgn = -sign(u1) (the I(u) symmetry branch), and
    k1 u1 + omega x0/V = (omega/V) M rmx / b2.

    Parameters
    ----------
    geo : dict
        From :func:`block_geometry` (r receivers, m points).
    pf : dict
        From :func:`point_factors` of the same m points.
    kk : int
        Index of the frequency in ``pf``; ``wv`` its omega / V.
    cosx, sinx : (r, m) float
        cos and sin of omega x0 / V (the caller forms them as separable products); they are
        used as scratch space and overwritten.
    re, im : (r, m) float
        Output arrays (may be strided views).
    scratch : callable, optional
        Work-array provider (:class:`Scratch`).
    """
    sh = cosx.shape
    s2 = np.einsum("nrm,nm->rm", geo["en"], pf["w2"][kk], out=scratch("k_s2", sh))  # k1^2 S2
    s1 = np.einsum("nrm,nm->rm", geo["en"], pf["w1"][kk], out=scratch("k_s1", sh))  # k1 S1
    np.subtract(geo["f"], s2, out=s2)                                 # f - k1^2 S2
    s2 *= geo["sv"]
    s2 += geo["A"]                                                    # -alpha
    if mach > 0.0:                                                    # exp(-i (k1 u1 + w x0))
        ph = np.multiply(geo["rmx"], wv * mach / (1.0 - mach * mach), out=scratch("k_ph", sh))
        ct, st = sincos(ph, scratch)
        np.multiply(st, s1, out=re)
        np.multiply(ct, s1, out=im)
        ct *= s2
        re -= ct
        st *= s2
        im += st
    else:                                                             # M = 0: no phase
        np.negative(s2, out=re)
        im[...] = s1
    re += geo["q1"]                                                   # - K10
    # - 2 Re I1(0) exp(-i omega x0/V) where u1 < 0 (v < 0); cosx, sinx are overwritten
    g = np.multiply(geo["neg"], pf["c0"][kk], out=s1)
    cosx *= g
    sinx *= g
    re -= cosx
    im += sinx


def incremental_k2(geo: dict, pf: dict, mach: float, wv: np.ndarray) -> np.ndarray:
    """K2 exp(-i omega x0/V) - K20 (A&R eqs. 11-12) at every point (r1 > 0), complex (nk, r, m).

    ``geo`` as from :func:`block_geometry` and ``pf`` from :func:`point_factors`, restricted to
    the m points needed.
    """
    b2 = 1.0 - mach * mach
    x0, R, rmx, v, f = geo["x0"], geo["R"], geo["rmx"], geo["v"], geo["f"]
    r1 = pf["r1"]
    u = np.abs(v) * pf["ib"]
    k1 = wv[:, None] * r1[None, :]                                   # (nk, m)
    inv = 1.0 / (DESMARAIS_P[None, :, None] + 1j * k1[:, None, :])   # 1/(p_n + i k1)
    ea = geo["en"] * DESMARAIS_A[:, None, None]
    i0 = np.einsum("nrm,knm->krm", ea, inv)
    j0 = np.einsum("nrm,knm->krm", ea, inv * inv) + u * i0
    i00 = np.einsum("n,knm->km", DESMARAIS_A, inv)[:, None, :]       # I0(u = 0)
    j00 = np.einsum("n,knm->km", DESMARAIS_A, inv * inv)[:, None, :]  # J0(u = 0)
    k1 = k1[:, None, :]
    inv_s2 = (b2 * r1 / rmx) ** 2                                    # 1 / (1 + u1^2)
    phi = (2.0 + 1j * k1 * u) * f - u * inv_s2 * (b2 * r1 / rmx) - 1j * k1 * i0 + k1 * k1 * j0
    neg = v < 0.0
    two_re0 = neg * 2.0 * (2.0 - 1j * k1 * i00 + k1 * k1 * j00).real
    theta = mach * rmx / b2                                          # k1 u1 + omega x0/V
    ph = np.exp(-1j * wv[:, None, None] * theta[None])
    ex = np.exp(-1j * wv[:, None, None] * x0[None])
    a = geo["A"]
    mru = mach * v / (b2 * R)                                        # M r1 u1 / R
    extra = 1j * k1 * a * mach * r1 / R + a * (b2 * r1 * r1 / (R * R) + (2.0 + mru) * inv_s2)
    k2e = np.where(neg, -np.conj(phi), phi) * ph + two_re0 * ex + extra * ph
    k20 = 2.0 + x0 / R * (2.0 + b2 * r1 * r1 / (R * R))             # A&R eq. 12
    return k2e - k20


def span_weights(yh: np.ndarray, zh: np.ndarray, method: str):
    """Weights turning sample values of P1, P2 into the span integrals of the interpolants.

    With sigma = eta/e and the receiver at (yh, zh) = (ybar, zbar)/e in the sending frame,

        int_-e^e P1/r1^2 deta = (1/e)   sum_q W1_q P1(sigma_q)
        int_-e^e P2/r1^4 deta = (1/e^3) sum_q W2_q P2(sigma_q)

    where W_q = sum_m FIT[m, q] mu_m and mu_m = int_-1^1 sigma^m / ((sigma-yh)^2 + zh^2)^p dsigma
    (p = 1, 2), from the recurrence sigma^2 = D + 2 yh sigma - (yh^2 + zh^2), D the denominator.
    Planar pairs (|zh| <= NEAR_PLANAR) use the finite-part value mu_0 = 2/(yh^2 - 1) and W2 = 0.

    Parameters
    ----------
    yh, zh : (m,) float
    method : "quartic" or "parabolic"

    Returns
    -------
    W1, W2 : (m, Q) float, Q = 5 (quartic) or 3 (parabolic)
    """
    fit = FIT[method]
    nq = fit.shape[0]
    planar = np.abs(zh) <= NEAR_PLANAR
    z = np.where(planar, 0.0, np.abs(zh))
    rho2 = yh * yh + z * z
    zs = np.where(planar, 1.0, z)
    with np.errstate(divide="ignore", invalid="ignore"):
        # mu_0: A&R's F; non-planar arctangent form or planar finite part (RTM planar case).
        f0 = np.where(planar, 2.0 / (yh * yh - 1.0),
                      (np.arctan((1.0 - yh) / zs) + np.arctan((1.0 + yh) / zs)) / zs)
        lg = np.log(((1.0 - yh) ** 2 + z * z) / ((1.0 + yh) ** 2 + z * z))
        mu = [f0, 0.5 * lg + yh * f0]                 # (non-finite only on a side-edge line,
        for m in range(2, nq):                        # which aero.dlm reports)
            even = 2.0 / (m - 1) if (m - 2) % 2 == 0 else 0.0     # int_-1^1 sigma^(m-2)
            mu.append(even + 2.0 * yh * mu[m - 1] - rho2 * mu[m - 2])
        mu = np.stack(mu, axis=-1)
        w1 = np.einsum("mi,ij->mj", mu, fit)
    nonplanar = ~planar
    w2 = np.zeros_like(w1)
    if np.any(nonplanar):
        y, zz, r2 = yh[nonplanar], z[nonplanar], rho2[nonplanar]
        mu_np = mu[nonplanar]
        tb, ta = 1.0 - y, -1.0 - y
        db, da = tb * tb + zz * zz, ta * ta + zz * zz
        nu = [(tb / db - ta / da) / (2.0 * zz * zz) + mu_np[:, 0] / (2.0 * zz * zz),
              -0.5 / db + 0.5 / da]
        nu[1] = nu[1] + y * nu[0]
        for m in range(2, nq):
            nu.append(mu_np[:, m - 2] + 2.0 * y * nu[m - 1] - r2 * nu[m - 2])
        nu = np.stack(nu, axis=-1)
        far = r2 >= FAR2
        if np.any(far):
            den = (_GL_X[None, :] - y[far, None]) ** 2 + zz[far, None] ** 2
            g = _GL_W[None, :] / (den * den)
            nu[far] = np.einsum("mi,ij->mj", g, np.vander(_GL_X, nq, increasing=True))
        w2[nonplanar] = np.einsum("mi,ij->mj", nu, fit)
    return w1, w2
