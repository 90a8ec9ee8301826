"""Second-order response model of a candidate that acts at second order in its parameters.

A bowed member (``member_curvature``, :mod:`pipeline.diagnose.effects`) changes its stiffness to
second order in the bow (the axial softening ~ bow^2 of :mod:`pipeline.diagnose.members`) and
its couplings to first order, so the residual r(x) of a bow x (npar,) is not linear in x. The
secant through 0 and the screening step h, s = (r(h) - r0) / h = a + c h for r = r0 + a x + c x^2,
predicts r0 + (a + c h) x: too large a change below h and too small above it, so that the bounded
linear fit runs to the bound. Measured on the frame's tail member (PID 51, blind-study seed 8,
chi^2 794 at no bow, step 0.05): the linear model's chi^2 keeps falling to the bound 0.15
(563 there) where the exact chi^2 is 1600-2400, and the refit started there ended at 1140; the
exact chi^2 has its valley, 380-410, at bows 0.10-0.125.

A member's taper (``member_taper``: section size s = (1 + scale)(1 + taper (xi - 1/2)), I ~ s^4)
acts far from linearly too, in both signs of each parameter: on the frame's wing-root member
(blind-study taper seed 6, chi^2 2125 without it) the exact chi^2 at the truth's (scale, taper)
= (-0.19, -0.57) is 315 where the secant through the screening step (0.1, 0.3) predicts 2165;
the linear screening ranked it 9th of 38 tapers and left it out of the refit.

**Model**: the second-order Taylor expansion r(x) = r0 + sum_k a_k x_k + sum_{k <= l} c_kl x_k x_l
from samples of one of two :data:`SCHEMES` (:func:`sample_points`), each spanning 2 h_k:

- ``one_sided`` (a bow, whose quadrant fixes the signs), npar (npar + 3) / 2 samples: x = h_k e_k
  and 2 h_k e_k give a_k and c_kk (the parabola through the samples at 0, h, 2h: the one-sided
  three-point differences r'(0) = (4 r(h) - r(2h) - 3 r(0)) / 2h and
  r''(0) / 2 = (r(2h) - 2 r(h) + r(0)) / 2h^2), h_k e_k + h_l e_l gives c_kl;
- ``centred`` (a taper, either sign), 2 npar + npar (npar - 1) / 2 samples: x = +-2 h_k e_k
  give a_k = (r(2h) - r(-2h)) / 4h and c_kk = (r(2h) + r(-2h) - 2 r(0)) / 8h^2 (central
  differences), 2 h_k e_k + 2 h_l e_l gives c_kl (on the taper above the model
  predicts 676 at the truth, 416 at (-0.2, 0) where the exact chi^2 is 416).

It is exact for a quadratic response.

**Fit** (:func:`quadratic_fit`): min |r(x)|^2 within the candidate's bounds and within the
sampled span (:func:`trust_box`: x_k between 0 and 2 h_k, or between -2 h_k and 2 h_k; the model
interpolates there; beyond it extrapolates, and on the frame's tail member the exact chi^2 at
3 h is 1600-3000 where the one-sided model gives 700-1200: a local mode of the bowed member
enters the measured band). Dense grid of :data:`GRID` points per
parameter, then bounded Gauss-Newton from the best point (``scipy.optimize.least_squares``).

**Line search** (:func:`line_search`): the exact chi^2 on the ray from 0 through the fit to the
candidate's bounds, at :data:`RAY` fractions of it and at the fit, then half a step either side
of the best: the size beyond the sampled span that the model cannot see.
"""
from __future__ import annotations

import itertools

import numpy as np
from scipy.optimize import least_squares

from structures.common.errors import InputError, SolverError

#: Grid points per parameter of the quadratic fit's first pass.
GRID = 25
#: Fractions of the ray from 0 to the candidate's bounds sampled by the exact line search.
RAY = tuple(np.arange(1, 7) / 6.0)
#: Candidates of each kind (best model fits first) given the exact line search
#: (:func:`line_searches`), by the kind's sampling scheme: the four best tapers ("centred"), or
#: a bow's four quadrant candidates for the two best members or pairs ("one_sided").
LINE_SEARCH_TOP = {"centred": 4, "one_sided": 8}
#: Sampling schemes of :func:`sample_points` (module docstring).
SCHEMES = ("one_sided", "centred")


def _pairs(npar: int) -> list:
    return list(itertools.combinations(range(npar), 2))


def n_columns(npar: int) -> int:
    """Columns of the model: npar linear, npar squares, npar (npar - 1) / 2 cross terms."""
    return 2 * npar + len(_pairs(npar))


def monomials(x) -> np.ndarray:
    """(..., n_columns) the model's regressors [x_k, x_k^2, x_k x_l (k < l)] of x (..., npar)."""
    x = np.asarray(x, float)
    cross = [x[..., k] * x[..., l] for k, l in _pairs(x.shape[-1])]
    return np.concatenate([x, x ** 2] + ([np.stack(cross, axis=-1)] if cross else []), axis=-1)


def _check_scheme(scheme: str) -> None:
    if scheme not in SCHEMES:
        raise InputError(f"quadratic model: scheme {scheme!r} is not one of {list(SCHEMES)}.")


def sample_points(reference, scheme: str = "one_sided") -> np.ndarray:
    """Sizes at which the response is sampled (module docstring).

    ``one_sided``: (npar (npar + 3) / 2, npar), h_k e_k and 2 h_k e_k for every k (in that
    order), then h_k e_k + h_l e_l for k < l. ``centred``: (2 npar + npar (npar - 1) / 2, npar),
    2 h_k e_k and -2 h_k e_k for every k, then 2 h_k e_k + 2 h_l e_l for k < l.
    """
    _check_scheme(scheme)
    h = np.asarray(reference, float)
    npar = h.size
    eye = np.diag(h) * (2.0 if scheme == "centred" else 1.0)
    first, second = (1.0, -1.0) if scheme == "centred" else (1.0, 2.0)
    cross = [eye[k] + eye[l] for k, l in _pairs(npar)]
    return np.array([row for k in range(npar) for row in (first * eye[k], second * eye[k])]
                    + cross)


def coefficients(r0, sampled, reference, scheme: str = "one_sided") -> np.ndarray:
    """The model's matrix S (n_data, n_columns), r(x) = r0 + S monomials(x).

    Parameters
    ----------
    r0 : (n_data,) response at x = 0.
    sampled : (n_samples, n_data) response at :func:`sample_points` (``reference``,
        ``scheme``).
    reference : (npar,) nonzero sampling steps h.
    scheme : one of :data:`SCHEMES`.

    Returns
    -------
    S : (n_data, n_columns) columns a_k, then c_kk, then c_kl (k < l).
    """
    _check_scheme(scheme)
    h = np.asarray(reference, float)
    npar = h.size
    d = np.asarray(sampled, float) - np.asarray(r0, float)[None, :]
    d1, d2 = d[0:2 * npar:2], d[1:2 * npar:2]
    if scheme == "centred":                                # r(2h) - r0, r(-2h) - r0
        step = 2.0 * h
        a = (d1 - d2) / (2.0 * step[:, None])                             # r'(0), central
        c = (d1 + d2) / (2.0 * step[:, None] ** 2)                        # r''(0) / 2
    else:                                                  # r(h) - r0, r(2h) - r0
        step = h
        a = (4.0 * d1 - d2) / (2.0 * h[:, None])                          # r'(0), one-sided
        c = (d2 - 2.0 * d1) / (2.0 * h[:, None] ** 2)                     # r''(0) / 2
    cols = [a, c]
    if npar > 1:
        cross = np.array([d[2 * npar + i] - a[k] * step[k] - a[l] * step[l]
                          - c[k] * step[k] ** 2 - c[l] * step[l] ** 2
                          for i, (k, l) in enumerate(_pairs(npar))])
        cols.append(cross / np.array([step[k] * step[l] for k, l in _pairs(npar)])[:, None])
    return np.concatenate(cols, axis=0).T


def trust_box(reference, lower, upper, scheme: str = "one_sided") -> tuple[np.ndarray, np.ndarray]:
    """The bounds intersected with the sampled span: x_k between 0 and 2 h_k (``one_sided``) or
    between -2 h_k and 2 h_k (``centred``)."""
    _check_scheme(scheme)
    h2 = 2.0 * np.asarray(reference, float)
    if scheme == "centred":
        return (np.maximum(np.asarray(lower, float), -np.abs(h2)),
                np.minimum(np.asarray(upper, float), np.abs(h2)))
    lo = np.maximum(np.asarray(lower, float), np.minimum(0.0, h2))
    hi = np.minimum(np.asarray(upper, float), np.maximum(0.0, h2))
    return lo, hi


def quadratic_fit(r0, signature, reference, lower, upper,
                  scheme: str = "one_sided") -> tuple[np.ndarray, float]:
    """min |r0 + S monomials(x)|^2 within the bounds and the sampled span (:func:`trust_box`).

    Parameters
    ----------
    r0 : (n_data,)
    signature : (n_data, n_columns), :func:`coefficients`.
    reference, lower, upper : (npar,)
    scheme : one of :data:`SCHEMES`, the samples' (the trust box).

    Returns
    -------
    x : (npar,)
    chi2 : float, the model's |r(x)|^2 (|r0|^2 with x = 0 when the model has no lower point).
    """
    r0, s = np.asarray(r0, float), np.asarray(signature, float)
    lo, hi = trust_box(reference, lower, upper, scheme)
    axes = [np.linspace(a, b, GRID) for a, b in zip(lo, hi)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, lo.size)
    chi2 = np.sum((r0[None, :] + monomials(grid) @ s.T) ** 2, axis=1)
    x0 = grid[int(np.argmin(chi2))]
    npar = lo.size
    pairs = _pairs(npar)

    def fun(x):
        return r0 + s @ monomials(x)

    def jac(x):
        d = np.zeros((n_columns(npar), npar))                              # d monomials / dx
        d[np.arange(npar), np.arange(npar)] = 1.0
        d[npar + np.arange(npar), np.arange(npar)] = 2.0 * x
        for i, (k, l) in enumerate(pairs):
            d[2 * npar + i, k], d[2 * npar + i, l] = x[l], x[k]
        return s @ d

    free = hi > lo
    x = x0
    if np.all(free):
        x = least_squares(fun, x0, jac=jac, bounds=(lo, hi), method="trf").x
    best = float(np.sum(fun(x) ** 2))
    none = float(r0 @ r0)
    if best >= none:
        return np.clip(np.zeros(npar), lo, hi), none
    return x, best


def line_search(residual_at, x, lower, upper) -> tuple | None:
    """The exact chi^2's best point on the ray from 0 through ``x`` to the bounds.

    Parameters
    ----------
    residual_at : callable (npar,) -> (n_data,) residual, or None (the size cannot be analysed).
    x : (npar,) a point of the ray (the quadratic fit), not 0.
    lower, upper : (npar,) bounds (x inside).

    Returns
    -------
    (x* (npar,), r* (n_data,), chi2* float) or None when no point of the ray could be analysed.
    """
    x = np.asarray(x, float)
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    with np.errstate(divide="ignore", invalid="ignore"):
        reach = np.where(x > 0, upper / x, np.where(x < 0, lower / x, np.inf))
    t_max = float(np.min(reach))                                           # >= 1: x is inside
    tried = {}

    def at(t):
        key = round(t, 12)
        if key not in tried:
            r = residual_at(np.clip(t * x, lower, upper))
            tried[key] = None if r is None else (r, float(np.sum(np.square(r))))
        return tried[key]

    def best():
        good = {t: v for t, v in tried.items() if v is not None}
        return min(good, key=lambda t: good[t][1]) if good else None

    for t in [f * t_max for f in RAY] + [1.0]:
        at(t)
    t_best = best()
    if t_best is None:
        return None
    step = t_max / (2.0 * len(RAY))
    for t in (t_best - step, t_best + step):
        if 0.0 < t <= t_max:
            at(t)
    t_best = best()
    r, chi2 = tried[t_best]
    return np.clip(t_best * x, lower, upper), r, chi2


def line_searches(out, r0, residual, kinds) -> None:
    """The exact line search (:func:`line_search`) of the :data:`LINE_SEARCH_TOP` entries of
    each kind of ``kinds`` (mapping kind -> scheme of :data:`SCHEMES`) in ``out`` (the
    screening's (Candidate, S, exact) list, :func:`pipeline.diagnose.screen.signatures`) whose
    model fits best; each is replaced in place by (Candidate, S, (x*, chi2*)). A ray along
    which the exact chi^2 is nowhere below the current model's (the quadratic model was wrong at
    every sampled size) gives the size 0, the current chi^2 and a zero signature: a candidate's
    screening result is never worse than leaving it out (the example aircraft's main-gear taper
    pair in its first round: best ray point 119 above the current chi^2, so listed below
    "nothing missing"). ``residual(cand, x)`` is the exact training residual (InputError or
    SolverError where the model cannot be analysed)."""
    fits = {kind: [] for kind in kinds}
    for i, (cand, s, exact) in enumerate(out):
        if cand.kind in kinds and exact is None:
            x, chi2 = quadratic_fit(r0, s, cand.reference, cand.lower, cand.upper,
                                    kinds[cand.kind])
            if np.any(x):
                fits[cand.kind].append((chi2, i, x))
    chosen = [f for kind in kinds
              for f in sorted(fits[kind], key=lambda f: f[0])[:LINE_SEARCH_TOP[kinds[kind]]]]
    current = float(np.sum(np.square(r0)))
    for _, i, x in chosen:
        cand = out[i][0]

        def residual_at(size, cand=cand):
            try:
                return residual(cand, size)
            except (InputError, SolverError):
                return None
        found = line_search(residual_at, x, cand.lower, cand.upper)
        if found is None:
            continue
        size, r, chi2 = found
        if chi2 >= current:
            size, r, chi2 = np.zeros_like(size), r0, current
        out[i] = (cand, secant(r0, r, size), (size, chi2))


def secant(r0, r, x) -> np.ndarray:
    """(n_data, npar) S with S x = r - r0 and S y = 0 for y orthogonal to x (0 when x = 0)."""
    x = np.asarray(x, float)
    if not np.any(x):
        return np.zeros((np.size(r0), x.size))
    return np.outer(np.asarray(r) - np.asarray(r0), x) / (x @ x)
