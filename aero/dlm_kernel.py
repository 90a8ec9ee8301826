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

import numpy as np

__all__ = ["DESMARAIS_A", "DESMARAIS_P", "SAMPLES", "FIT", "NEAR_PLANAR", "FAR2", "sincos",
           "kernel_geometry", "frequency_factors", "incremental_k1", "incremental_k2",
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


def sincos(x: np.ndarray):
    """cos(x) and sin(x) to ~1 ulp of |x|, about 3x faster than np.cos + np.sin here.

    x = j h + d with h = 2 pi / 16384 and |d| <= h/2: table values of cos/sin(j h) rotated by d
    through cos d = 1 - d^2/2, sin d = d - d^3/6 (truncation below 6e-17 for |d| <= 1.9e-4).
    """
    t = x * (1.0 / _H)
    j = np.rint(t)
    d = t - j
    d *= _H
    idx = j.astype(np.int64)
    idx &= _NTAB - 1
    ct, st = _COS_TAB.take(idx), _SIN_TAB.take(idx)
    d2 = d * d
    cd = 1.0 - 0.5 * d2
    d2 *= -1.0 / 6.0
    d2 += 1.0
    d2 *= d                                             # sin d
    return ct * cd - st * d2, st * cd + ct * d2


_NTAB = 16384
_H = 2.0 * np.pi / _NTAB
_COS_TAB, _SIN_TAB = np.cos(_H * np.arange(_NTAB)), np.sin(_H * np.arange(_NTAB))


def kernel_geometry(x0: np.ndarray, r1: np.ndarray, mach: float) -> dict:
    """Geometry-only factors of the kernel (shared by all reduced frequencies).

    Parameters
    ----------
    x0 : (r, m) float
        Streamwise offsets from the m sending points to r receivers.
    r1 : (m,) float
        y-z distances, shared by the r receivers (receivers of one strip); r1 >= 0 and
        x0 != 0 where r1 == 0.
    mach : float
        0 <= M < 1.

    Returns
    -------
    dict
        (r, m) arrays ``R, rmx, u, f, neg, sgn, negf, A, K10, theta``, ``en`` (12, r, m) =
        exp(-p_n |u1|), and ``x0``, ``r1``; used by :func:`incremental_k1`, :func:`incremental_k2`.
    """
    b2 = 1.0 - mach * mach
    R = np.sqrt(x0 * x0 + b2 * r1 * r1)
    rmx = R - mach * x0                                 # = beta^2 r1 sqrt(1 + u1^2) > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        u1 = (mach * R - x0) / (b2 * r1)                # A&R eq. 11 (+-inf where r1 == 0)
    u = np.abs(u1)
    with np.errstate(over="ignore", invalid="ignore"):
        s = np.sqrt(1.0 + u * u)                        # (np.hypot is ~10x slower)
        f = 1.0 / (s * (s + u))                         # 1 - u/sqrt(1+u^2), cancellation-free
    # Desmarais terms exp(-p_n u) with p_{n+1} = 2 p_n: one exp, then squares (relative error
    # <= 2^11 eps); clamping at 1e-150 keeps the squares out of the slow subnormal range, terms
    # below that are negligible against the others (|a_n| / p_n^2 < 1e4).
    en = np.empty((12,) + u.shape)
    np.exp(-DESMARAIS_P[0] * u, out=en[0])
    for n in range(1, 12):
        np.maximum(en[n - 1], 1e-150, out=en[n])
        en[n] *= en[n]
    sgn = np.copysign(1.0, -u1)                         # +1 where u1 < 0 (I(u) symmetry branch)
    negf = 0.5 * sgn + 0.5
    return {"x0": x0, "r1": r1, "R": R, "rmx": rmx, "u": u, "f": f, "neg": sgn > 0.0,
            "sgn": sgn, "negf": negf, "en": en,
            "A": mach * b2 * r1 * r1 / (R * rmx),       # M r1/R / sqrt(1+u1^2)
            "K10": -1.0 - x0 / R,                       # A&R eq. 12
            "theta": mach * rmx / b2}                   # k1 u1 + omega x0/V = (omega/V) theta


_AP = DESMARAIS_A * DESMARAIS_P
_P2 = DESMARAIS_P ** 2


def frequency_factors(r1: np.ndarray, wv: np.ndarray) -> dict:
    """Reduced-frequency factors that depend on r1 only (shared by a strip's receivers).

    With c_n = 1/(p_n^2 + k1^2), k1 = (omega/V) r1: ``k1``, ``kappa`` = k1^2 (nk, m),
    ``ac`` = a_n c_n and ``apc`` = a_n p_n c_n (nk, 12, m), ``s0`` = sum_n a_n c_n (nk, m).
    """
    k1 = wv[:, None] * r1[None, :]
    kappa = k1 * k1
    c = np.reciprocal(kappa[:, None, :] + _P2[None, :, None])
    return {"k1": k1, "kappa": kappa, "ac": c * DESMARAIS_A[None, :, None],
            "apc": c * _AP[None, :, None], "s0": np.matmul(DESMARAIS_A, c)}


def incremental_k1(geo: dict, freq: dict, wv: np.ndarray, cosx: np.ndarray, sinx: np.ndarray):
    """Real and imaginary parts of K1 exp(-i omega x0/V) - K10 at every point and frequency.

    With c_n = 1/(p_n^2 + k1^2): S0 = sum a_n c_n, S1 = sum a_n p_n e_n c_n,
    S2 = sum a_n e_n c_n, so that 1 - u/sqrt(1+u^2) - i k1 I0 = f - k1^2 S2 - i k1 S1 and
    Re I1(0) = 1 - k1^2 S0.

    Parameters
    ----------
    geo : dict
        From :func:`kernel_geometry` (r receivers, m points).
    freq : dict
        From :func:`frequency_factors` of the same m points.
    wv : (nk,) float
        omega / V = k / b for each reduced frequency.
    cosx, sinx : (nk, r, m) float
        cos and sin of omega x0 / V (computed by the caller, often as separable products).

    Returns
    -------
    (re, im) : two (nk, r, m) float arrays
    """
    s1 = np.einsum("nrm,knm->krm", geo["en"], freq["apc"])
    s2 = np.einsum("nrm,knm->krm", geo["en"], freq["ac"])
    k1, kappa = freq["k1"][:, None, :], freq["kappa"][:, None, :]
    ar = geo["f"] - kappa * s2                          # Re of [1 - u/sqrt(1+u^2) - i k1 I0]
    bi = k1 * s1                                        # minus its imaginary part
    alpha = geo["sgn"] * ar - geo["A"]
    if np.any(geo["theta"]):
        ct, st = sincos(wv[:, None, None] * geo["theta"][None])
    else:                                               # M = 0: no phase
        ct, st = np.ones_like(ar), np.zeros_like(ar)
    # 2 Re I1(0) = 2 (1 - k1^2 S0), only where u1 < 0
    two_re0 = geo["negf"] * (2.0 - 2.0 * kappa * freq["s0"][:, None, :])
    re = ct * alpha + st * bi - two_re0 * cosx - geo["K10"]
    im = ct * bi - st * alpha + two_re0 * sinx
    return re, im


def incremental_k2(geo: dict, mach: float, wv: np.ndarray, ex: np.ndarray) -> np.ndarray:
    """K2 exp(-i omega x0/V) - K20 at every point (r1 > 0) and frequency, complex (nk, r, m).

    ``geo`` as from :func:`kernel_geometry`; ``ex`` is exp(-i omega x0 / V), (nk, r, m).
    """
    b2 = 1.0 - mach * mach
    x0, r1, R, rmx, u, f = geo["x0"], geo["r1"], geo["R"], geo["rmx"], geo["u"], geo["f"]
    k1 = wv[:, None] * r1[None, :]                               # (nk, m)
    inv = 1.0 / (DESMARAIS_P[None, :, None] + 1j * k1[:, None, :])   # 1/(p_n + i k1)
    ea = geo["en"] * DESMARAIS_A[:, None, None]
    i0 = np.einsum("nrm,knm->krm", ea, inv)
    j0 = np.einsum("nrm,knm->krm", ea, inv * inv) + u * i0
    i00 = np.matmul(DESMARAIS_A, inv)[:, None, :]                # I0(u = 0)
    j00 = np.matmul(DESMARAIS_A, inv * inv)[:, None, :]          # J0(u = 0)
    k1 = k1[:, None, :]
    with np.errstate(over="ignore"):
        s3 = np.sqrt(1.0 + u * u) ** 3
    phi = (2.0 + 1j * k1 * u) * f - u / s3 - 1j * k1 * i0 + k1 * k1 * j0
    two_re0 = geo["negf"] * 2.0 * (2.0 - 1j * k1 * i00 + k1 * k1 * j00).real
    ph = np.exp(-1j * wv[:, None, None] * geo["theta"][None])   # exp(-i (k1 u1 + omega x0/V))
    a = geo["A"]
    mru = mach * (mach * R - x0) / (b2 * R)                      # M r1 u1 / R
    inv_s2 = (b2 * r1 / rmx) ** 2                                # 1 / (1 + u1^2)
    extra = 1j * k1 * a * mach * r1 / R + a * (b2 * r1 * r1 / (R * R) + (2.0 + mru) * inv_s2)
    k2e = np.where(geo["neg"], -np.conj(phi), phi) * ph + two_re0 * ex + extra * ph
    k20 = 2.0 + x0 / R * (2.0 + b2 * r1 * r1 / (R * R))         # A&R eq. 12
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
        w1 = mu @ fit
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
            nu[far] = g @ np.vander(_GL_X, nq, increasing=True)
        w2[nonplanar] = nu @ fit
    return w1, w2
