"""Doublet-lattice aerodynamic influence coefficients (normalwash factors) D_jj(M, k).

D(k) = D_steady + D_increment(k): the steady part is the horseshoe vortex lattice of
:mod:`aero.vlm`, the unsteady increment integrates the incremental kernel numerators along each
box's 1/4-chord doublet line (Albano & Rodden 1969, AIAA J. 7(2), eqs. 13-16), with the quartic
numerator approximation of Rodden, Taylor & McIntosh 1998 (J. Aircraft 35(5)) or the original
parabolic one; see :mod:`aero.dlm_kernel` for the formulas and the Desmarais approximation of the
kernel integrals.

    w_i / V = sum_j D_ij(k) dCp_j,
    D_ij = D_steady_ij + chord_j / (8 pi) int_{-e}^{e} [P1(eta)/r1^2 + P2(eta)/r1^4] d eta

(A&R eq. 16; chord_j the mean box chord, e_j the semi-width of the doublet line in the y-z plane).
Conventions: k = omega b / V with b = refc / 2 (Nastran), time dependence exp(i omega t),
w the induced velocity along the receiving box's normal, dCp = (p_lower - p_upper)/q positive
along the sending box's normal (:mod:`aero.panels`), so D's steady diagonal is negative.
"""
from __future__ import annotations

import numpy as np

from aero import dlm_kernel as dk
from aero.panels import BoxMesh, mirror_xz
from aero.vlm import check_mach, check_symxz, steady_aic
from structures.errors import InputError, card_message

__all__ = ["dlm_aic", "check_mesh_for_k", "METHODS"]

METHODS = ("quartic", "parabolic")
_TARGET_POINTS = 1 << 16        # kernel points x frequencies per chunk (~100 MB of temporaries)


def _senders(mesh: BoxMesh, samples: np.ndarray) -> dict:
    """Sending-box frames: midpoint, semi-width e, unit y_e and normal, sweep, sample x."""
    d = mesh.doublet_out - mesh.doublet_in
    e = 0.5 * np.hypot(d[:, 1], d[:, 2])
    ye = np.zeros_like(d)
    ye[:, 1:] = d[:, 1:] / (2.0 * e[:, None])
    mid = 0.5 * (mesh.doublet_in + mesh.doublet_out)
    tanl = d[:, 0] / (2.0 * e)                                   # tan(sweep of the doublet line)
    return {"mid": mid, "e": e, "ye": ye, "n": np.array(mesh.normal), "tanl": tanl,
            "chord": np.array(mesh.chord),
            "xq": mid[:, 0, None] + e[:, None] * samples[None, :] * tanl[:, None]}


def _increment_block(colloc, nrm, snd, mach, wv, method):
    """Unsteady increment for receivers (r, 3) against all senders: complex (nk, r, n)."""
    sig = dk.SAMPLES[method]
    nq = sig.size
    e = snd["e"]
    d = colloc[:, None, :] - snd["mid"][None]                    # (r, n, 3) receiver - midpoint
    x0 = d[..., 0]
    yh = np.einsum("rni,ni->rn", d, snd["ye"]) / e               # ybar / e in the sending frame
    zh = np.einsum("rni,ni->rn", d, snd["n"]) / e                # zbar / e
    t1 = nrm @ snd["n"].T                                        # T1 = n_r . n_s (A&R eq. 8)
    r, n = x0.shape
    w1, w2 = dk.span_weights(yh.ravel(), zh.ravel(), method)
    w1 = w1.reshape(r, n, nq)
    x0q = x0[..., None] - (e * snd["tanl"])[None, :, None] * sig
    r1q = e[None, :, None] * np.sqrt((yh[..., None] - sig) ** 2 + zh[..., None] ** 2)
    geo = dk.kernel_geometry(x0q.ravel(), r1q.ravel(), mach)
    # cos/sin(omega x0/V) as separable products of receiver and sender terms (x0 = x_r - x_q)
    ar, aq = wv[:, None] * colloc[None, :, 0], wv[:, None, None] * snd["xq"][None]
    cr, sr = np.cos(ar)[:, :, None, None], np.sin(ar)[:, :, None, None]
    cq, sq = np.cos(aq)[:, None], np.sin(aq)[:, None]
    nk = wv.size
    cosx = (cr * cq + sr * sq).reshape(nk, -1)
    sinx = (sr * cq - cr * sq).reshape(nk, -1)
    re, im = dk.incremental_k1(geo, wv, cosx, sinx)
    c1 = (snd["chord"] / (8.0 * np.pi * e))[None, :] * t1        # A&R eq. 16 with 1/e of weights
    om = w1 * c1[..., None]
    out = (np.einsum("krnq,rnq->krn", re.reshape(nk, r, n, nq), om)
           + 1j * np.einsum("krnq,rnq->krn", im.reshape(nk, r, n, nq), om))
    nonplanar = np.abs(zh) > dk.NEAR_PLANAR
    if np.any(nonplanar):
        ir, js = np.nonzero(nonplanar)
        pts = (np.ravel_multi_index((ir, js), (r, n)) * nq)[:, None] + np.arange(nq)
        pts = pts.ravel()
        geo2 = {key: (val[:, pts] if key in ("ea", "eap") else val[pts])
                for key, val in geo.items()}
        ex = cosx[:, pts] - 1j * sinx[:, pts]
        dk2 = dk.incremental_k2(geo2, mach, wv, ex).reshape(nk, ir.size, nq)
        es = e[js]
        dnr = np.einsum("pi,pi->p", d[ir, js], nrm[ir])              # d . n_r at the midpoint
        yn = np.einsum("pi,pi->p", snd["ye"][js], nrm[ir])           # y_e(sender) . n_r
        t2 = (zh[ir, js] * es)[:, None] * (dnr[:, None] - es[:, None] * sig * yn[:, None])
        c2 = snd["chord"][js] / (8.0 * np.pi * es ** 3)              # A&R eq. 16, 1/e^3 weights
        w2p = w2.reshape(r, n, nq)[ir, js] * (t2 * c2[:, None])
        out[:, ir, js] += np.einsum("kpq,pq->kp", dk2, w2p)
    return out


def dlm_aic(mesh: BoxMesh, mach: float, k, *, refc: float, method: str = "quartic",
            symxz: int = 0, chunk_size: int | None = None) -> np.ndarray:
    """Doublet-lattice normalwash matrices D(M, k) for several reduced frequencies at once.

    Parameters
    ----------
    mesh : BoxMesh
        n boxes (only the modelled half when ``symxz != 0``).
    mach : float
        0 <= M < 1; M >= 1 is outside the subsonic method's range and raises InputError.
    k : float or (nk,) array_like
        Reduced frequencies k = omega b / V with b = refc / 2 (Nastran's convention), k >= 0.
    refc : float, keyword-only
        Reference chord (AERO/AEROS REFC), > 0.
    method : {"quartic", "parabolic"}
        Span-wise approximation of the incremental kernel numerator (RTM 1998 / A&R 1969).
    symxz : {0, +1, -1}
        No symmetry, symmetric or antisymmetric about y = 0.
    chunk_size : int, optional
        Receiving boxes per block. Peak temporaries scale as chunk_size * n * 5 * nk * ~200 B;
        the default keeps them near 100 MB whatever n and nk.

    Returns
    -------
    (nk, n, n) complex
        D[k, i, j]: w_i / V per unit dCp_j; D[k] -> steady_aic(mesh, mach) as k -> 0.
    """
    m = check_mach(mach)
    s = check_symxz(symxz)
    if method not in METHODS:
        raise InputError(card_message(f"unknown doublet-lattice method {method!r}.",
                                      fix=f"use one of {list(METHODS)}."))
    kk = np.atleast_1d(np.asarray(k, dtype=float))
    if kk.ndim != 1 or kk.size == 0 or not np.all(np.isfinite(kk)) or np.any(kk < 0.0):
        raise InputError(card_message(
            f"reduced frequencies {np.asarray(k).tolist()} must be a non-empty list of finite "
            "values k >= 0 (k = omega b / V, b = REFC/2).", card="MKAERO1",
            fix="list non-negative reduced frequencies."))
    refc = float(refc)
    if not np.isfinite(refc) or refc <= 0.0:
        raise InputError(card_message(f"reference chord REFC={refc} must be > 0.",
                                      card="AERO/AEROS", fix="give the reference chord."))
    n, nk = mesh.n, kk.size
    nq = dk.SAMPLES[method].size
    if chunk_size is None:
        rows = max(1, _TARGET_POINTS // max(1, n * nq * nk))
    else:
        rows = int(chunk_size)
        if rows < 1:
            raise InputError(card_message(f"chunk_size={chunk_size} must be >= 1.",
                                          fix="give a positive number of receiving boxes."))
    wv = kk / (0.5 * refc)                                       # omega / V = k / b
    senders = [(1.0, _senders(mesh, dk.SAMPLES[method]))]
    if s:
        senders.append((-float(s), _senders(mirror_xz(mesh), dk.SAMPLES[method])))
    out = np.empty((nk, n, n), dtype=complex)
    out[:] = steady_aic(mesh, m, symxz=s)[None]
    for i0 in range(0, n, rows):
        sl = slice(i0, min(n, i0 + rows))
        for factor, snd in senders:
            out[:, sl] += factor * _increment_block(mesh.collocation[sl], mesh.normal[sl], snd,
                                                    m, wv, method)
    return out


def check_mesh_for_k(mesh: BoxMesh, mach: float, kmax: float, refc: float) -> list[str]:
    """Box-size checks of a mesh for reduced frequencies up to ``kmax``.

    Two rules of the MSC.Nastran Aeroelastic Analysis User's Guide (Rodden & Johnson 1994,
    sec. 2.3 "Doublet-lattice" modelling guidelines): the streamwise box chord should satisfy
    dx < 0.08 V/f, i.e. at least 12.5 boxes per wavelength V/f = 2 pi b / k (b = refc/2), and
    boxes should be roughly square; we flag span/chord outside [0.25, 4].

    Parameters
    ----------
    mesh : BoxMesh
    mach : float
        Checked for range only (the rule is stated in the free-stream wavelength).
    kmax : float
        Largest reduced frequency k = omega b / V to be used.
    refc : float
        Reference chord, b = refc / 2.

    Returns
    -------
    list of str
        One message per offending CAERO1 panel (empty when the mesh is fine).
    """
    check_mach(mach)
    if not (np.isfinite(kmax) and kmax >= 0.0 and np.isfinite(refc) and refc > 0.0):
        raise InputError(card_message(f"kmax={kmax} and refc={refc} must be >= 0 and > 0.",
                                      fix="give the largest reduced frequency and REFC."))
    messages = []
    limit = np.inf if kmax == 0.0 else 0.08 * 2.0 * np.pi * (0.5 * refc) / kmax
    ar = mesh.span / mesh.chord
    for pid in np.unique(mesh.panel_id):
        sel = mesh.panel_id == pid
        worst = float(mesh.chord[sel].max())
        if worst > limit:
            messages.append(card_message(
                f"box chord {worst:.4g} exceeds 0.08 V/f = {limit:.4g} at k = {kmax:g} "
                f"(fewer than 12.5 boxes per wavelength; doublet-lattice accuracy degrades).",
                card="CAERO1", card_id=int(pid),
                fix=f"use at least {int(np.ceil(worst / limit))} times as "
                    "many chordwise boxes (NCHORD/LCHORD) or lower kmax."))
        lo, hi = float(ar[sel].min()), float(ar[sel].max())
        if lo < 0.25 or hi > 4.0:
            messages.append(card_message(
                f"box aspect ratio (span/chord) ranges {lo:.3g}..{hi:.3g}, outside [0.25, 4].",
                card="CAERO1", card_id=int(pid),
                fix="choose NSPAN/NCHORD (or AEFACT lists) giving nearly square boxes."))
    return messages
