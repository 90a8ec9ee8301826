"""Doublet-lattice aerodynamic influence coefficients (normalwash factors) D_jj(M, k).

D(k) = D_steady + D_increment(k): the steady part is the horseshoe vortex lattice of
:mod:`aero.vlm`, the unsteady increment integrates the incremental kernel numerators along each
box's 1/4-chord doublet line (Albano & Rodden 1969, AIAA J. 7(2), eqs. 13-16), with the quartic
numerator approximation of Rodden, Taylor & McIntosh 1998 (J. Aircraft 35(5)) or the original
parabolic one; see :mod:`aero.dlm_kernel` for the formulas and the Desmarais approximation of the
kernel integrals.

    w_i / V = sum_j D_ij(k) dCp_j,
    D_ij = D_steady_ij + chord_j / (8 pi) int_{-e}^{e} [P1(eta)/r1^2 + P2(eta)/r1^4] d eta

(A&R eq. 16; chord_j the mean box chord, e_j the semi-width of the doublet line in the y-z plane)
with P1 = -(K1 exp(-i omega x0/V) - K10) T1 and P2 = -(K2 exp(-i omega x0/V) - K20) T2* (RTM).
The minus sign makes the kernel consistent with the horseshoe lattice: at k = 0,
-chord/(8 pi) int (K10 T1/r1^2 + K20 T2*/r1^4) d eta is exactly the horseshoe normalwash of
:mod:`aero.vlm` (checked by tests/aero/test_dlm.py::test_steady_kernel_equals_horseshoe).
Conventions: k = omega b / V with b = refc / 2 (Nastran), time dependence exp(i omega t),
w the induced velocity along the receiving box's normal, dCp = (p_lower - p_upper)/q positive
along the sending box's normal (:mod:`aero.panels`), so D's steady diagonal is negative.

Evaluation: receivers are processed by strips (same collocation y, z and normal), so that the
y-z distance r1 to every distinct sending sample point, the span weights and the frequency
factors are set up once per strip; blocks of a strip's receivers then evaluate the kernel on
(receiver, distinct point) pairs with reused per-thread work arrays, and a sparse (n, points)
matrix of span weights integrates all frequencies at once. A strip whose exact mirror image
(y -> -y, same z and box x) is also a receiving strip, with a mirror-symmetric set of sending
points (full-span models), passes its kernel values, permuted, to that strip: the pair
quantities r1 and x0 are bitwise equal there, so this changes no digit. Threads work on strips
(or mirror pairs of strips); the steady matrix is computed alongside.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from scipy.sparse import csr_matrix

from aero import dlm_kernel as dk
from aero.panels import BoxMesh, mirror_xz
from aero.vlm import check_mach, check_symxz, steady_aic
from structures.common.errors import InputError, card_message

__all__ = ["dlm_aic", "check_mesh_for_k", "METHODS"]

METHODS = ("quartic", "parabolic")
_TARGET_PAIRS = 1 << 16         # (receiver, distinct sample point) pairs per block


def _senders(mesh: BoxMesh, samples: np.ndarray, wv: np.ndarray) -> dict:
    """Sending-box frames: midpoint, semi-width e, unit y_e and normal, sweep, sample points.

    The sample points shared by neighbouring boxes (strip edges) are kept once (``upts``, with
    ``inv`` mapping box-major sample slots to them), with cos/sin(omega x_q / V) (nk, U).
    """
    d = mesh.doublet_out - mesh.doublet_in
    e = 0.5 * np.hypot(d[:, 1], d[:, 2])
    ye = np.zeros_like(d)
    ye[:, 1:] = d[:, 1:] / (2.0 * e[:, None])
    mid = 0.5 * (mesh.doublet_in + mesh.doublet_out)
    tanl = d[:, 0] / (2.0 * e)                                   # tan(sweep of the doublet line)
    eta = e[:, None, None] * samples[None, :, None]              # (n, nq, 1)
    pts = mid[:, None, :] + eta * (ye + np.outer(tanl, [1.0, 0.0, 0.0]))[:, None, :]
    upts, inv = np.unique(pts.reshape(-1, 3), axis=0, return_inverse=True)
    xq = np.ascontiguousarray(upts[:, 0])
    cq, sq = dk.sincos(wv[:, None] * xq[None, :])
    # exact mirror image y -> -y of the point set (a full-span mesh): upts[mirror[m]] is the
    # image of point m; None unless every image is bitwise one of the points
    mir = upts * np.array([1.0, -1.0, 1.0])
    order = np.lexsort((mir[:, 2], mir[:, 1], mir[:, 0]))
    mirror = None
    if np.array_equal(mir[order], upts):
        mirror = np.empty(order.size, dtype=np.intp)
        mirror[order] = np.arange(order.size)
    return {"mid": mid, "e": e, "ye": ye, "n": np.array(mesh.normal), "tanl": tanl,
            "chord": np.array(mesh.chord), "upts": upts, "inv": inv.ravel(), "xq": xq,
            "cq": cq, "sq": sq, "mirror": mirror}


def _strip_setup(yz, nrm, snd, wv, method, mach, kernel=True):
    """Everything that depends only on a receiving strip's y, z and normal (all its boxes).

    ``kernel=False`` leaves out the frequency factors of the kernel (for a strip whose kernel
    values are those of its mirror strip, permuted).
    """
    sig = dk.SAMPLES[method]
    nq = sig.size
    e = snd["e"]
    n = e.size
    dyz = yz[None, :] - snd["mid"][:, 1:]                        # (n, 2) y-z offset to midpoint
    yh = np.einsum("ni,ni->n", dyz, snd["ye"][:, 1:]) / e        # ybar / e, sending frame
    zh = np.einsum("ni,ni->n", dyz, snd["n"][:, 1:]) / e         # zbar / e
    t1 = np.einsum("ni,i->n", snd["n"], nrm)                    # T1 = n_r . n_s (A&R eq. 8)
    w1, w2 = dk.span_weights(yh, zh, method)                     # (n, nq)
    upts = snd["upts"]                                           # U distinct sample points
    r1u = np.sqrt((yz[0] - upts[:, 1]) ** 2 + (yz[1] - upts[:, 2]) ** 2)
    # P1 = -(K1 e^{-i w x0} - K10) T1 (RTM); A&R eq. 16 with the 1/e of the span weights, as a
    # sparse (n, U) map from the distinct points to the sending boxes
    om = w1 * ((-snd["chord"] / (8.0 * np.pi * e)) * t1)[:, None]
    wmap = csr_matrix((om.ravel(), snd["inv"], np.arange(0, n * nq + 1, nq)),
                      shape=(n, upts.shape[0]))
    setup = {"pf": dk.point_factors(r1u, mach, wv) if kernel else None, "wmap": wmap}
    js = np.nonzero(np.abs(zh) > dk.NEAR_PLANAR)[0]
    setup["js"] = js
    if js.size:
        es = e[js]
        dnr = np.einsum("ni,i->n", dyz[js], nrm[1:])            # d . n_r at the midpoint
        yn = np.einsum("ni,i->n", snd["ye"][js], nrm)           # y_e(sender) . n_r
        t2 = (zh[js] * es)[:, None] * (dnr[:, None] - es[:, None] * sig * yn[:, None])
        c2 = -snd["chord"][js] / (8.0 * np.pi * es ** 3)         # P2 = -(dK2) T2*, 1/e^3 weights
        setup["om2"] = w2[js] * t2 * c2[:, None]
        pts = snd["inv"][(js[:, None] * nq + np.arange(nq)).ravel()]
        setup["pts"] = pts
        setup["pf2"] = {"r1": r1u[pts], "ib": 1.0 / ((1.0 - mach * mach) * r1u[pts])}
    return setup


def _increment_rows(xr, setups, snd, mach, wv, nq, scratch):
    """Unsteady increments for receivers at x = xr of one strip (and of its mirror strip).

    ``setups`` lists (strip set-up, point permutation): the first has no permutation and its
    kernel factors are used; a second one, for the mirror-image strip (same x, y -> -y), takes
    the same kernel values at the mirrored points (``snd["mirror"]``), which is exact: r1 and
    x0, hence every kernel factor, are bitwise the same. ``scratch`` is the calling thread's
    :class:`aero.dlm_kernel.Scratch`. Returns one complex (nk, r, n) array per set-up.
    """
    xq = snd["xq"]
    nk, r, u = wv.size, xr.size, xq.size
    x0 = np.subtract(xr[:, None], xq[None, :], out=scratch("x0", (r, u)))   # x0 = x_r - x_q
    pf = setups[0][0]["pf"]
    geo = dk.block_geometry(x0, pf, mach, scratch)
    # cos/sin(omega x0/V) as separable products of receiver and sender terms
    cr, sr = dk.sincos(wv[:, None] * xr[None, :])
    cr, sr = cr[:, :, None], sr[:, :, None]
    buf = scratch("buf", (nk, 2, r, u))
    cosx, sinx, tmp = (scratch(name, (r, u)) for name in ("cosx", "sinx", "tmp"))
    for kk in range(nk):
        cq, sq = snd["cq"][kk], snd["sq"][kk]
        np.multiply(cr[kk], cq, out=cosx)
        cosx += np.multiply(sr[kk], sq, out=tmp)
        np.multiply(sr[kk], cq, out=sinx)
        sinx -= np.multiply(cr[kk], sq, out=tmp)
        dk.incremental_k1(geo, pf, kk, wv[kk], mach, cosx, sinx, buf[kk, 0], buf[kk, 1],
                          scratch)
    # span integration: sparse (n, U) weights times the points' values (one product for all k)
    cols0 = scratch("cols", (u, nk * 2 * r))
    np.copyto(cols0, buf.reshape(-1, u).T)
    outs = []
    for setup, perm in setups:
        cols = cols0 if perm is None else np.take(cols0, perm, axis=0,
                                                  out=scratch("cols_m", cols0.shape))
        wmap = setup["wmap"]
        res = (wmap @ cols).T.reshape(nk, 2, r, wmap.shape[0])
        out = res[:, 0] + 1j * res[:, 1]
        js = setup["js"]
        if js.size:
            pts = setup["pts"] if perm is None else perm[setup["pts"]]
            geo2 = {key: geo[key][:, pts] for key in ("x0", "R", "rmx", "v", "f", "A")}
            geo2["en"] = geo["en"][:, :, pts]
            dk2 = dk.incremental_k2(geo2, setup["pf2"], mach, wv).reshape(nk, r, js.size, nq)
            out[..., js] += np.einsum("krpq,pq->krp", dk2, setup["om2"])
        outs.append(out)
    return outs


def _mirror_pairs(mesh: BoxMesh, strips, senders):
    """Receiving strips grouped with their exact mirror strip (y -> -y, same z and box x).

    Returns a list of tuples of strip indices: (s,) or (s, s_mirror). Pairs only when every
    sender set is itself mirror-symmetric (``mirror`` permutation found).
    """
    if any(snd["mirror"] is None for _, snd in senders):
        return [(i,) for i in range(len(strips))]
    key = {}
    for i, idx in enumerate(strips):
        y, z = mesh.collocation[idx[0], 1:]
        key[(float(y), float(z), mesh.collocation[idx, 0].tobytes())] = i
    groups, used = [], set()
    for i, idx in enumerate(strips):
        if i in used:
            continue
        y, z = mesh.collocation[idx[0], 1:]
        j = key.get((-float(y), float(z), mesh.collocation[idx, 0].tobytes())) if y else None
        if j is None or j in used or j == i:
            groups.append((i,))
        else:
            groups.append((i, j))
            used.add(j)
        used.add(i)
    return groups


def _strips(mesh: BoxMesh):
    """Groups of receiving boxes sharing collocation y, z and normal (one strip of a panel)."""
    key = np.concatenate([mesh.collocation[:, 1:], mesh.normal[:, 1:]], axis=1)
    _, inverse = np.unique(key, axis=0, return_inverse=True)
    order = np.argsort(inverse.ravel(), kind="stable")
    bounds = np.flatnonzero(np.diff(inverse.ravel()[order])) + 1
    return np.split(order, bounds)


def dlm_aic(mesh: BoxMesh, mach: float, k, *, refc: float, method: str = "quartic",
            symxz: int = 0, chunk_size: int | None = None,
            workers: int | None = None) -> np.ndarray:
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
        Receiving boxes per block (blocks never mix strips). A block's work arrays take about
        (27 + 4 nk) * 8 bytes per (receiver, distinct sample point) pair and are reused from
        block to block (one set per thread); the default sizes blocks to ~2^16 pairs for one k
        (~2^16 * 9 / (8 + nk) pairs for nk), i.e. ~15 MB per thread with one k, ~17 MB with 8,
        whatever n. The peak is that, the (nk, n, n) complex
        result and the (n, n) steady matrix.
    workers : int, optional
        Threads over receiving strips (default: the number of CPUs); each thread holds one
        block's work arrays. With more than one thread the steady matrix is computed
        concurrently with the first strips.

    Returns
    -------
    (nk, n, n) complex
        D[k, i, j]: w_i / V per unit dCp_j; D[k] -> steady_aic(mesh, mach) as k -> 0.

    Raises
    ------
    InputError
        Mach outside [0, 1), unknown method (the message lists the valid ones), negative or
        non-finite k, refc <= 0, chunk_size < 1, or a collocation point on the side-edge line of
        a coplanar box (singular kernel; the message names both boxes).
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
    if chunk_size is not None and int(chunk_size) < 1:
        raise InputError(card_message(f"chunk_size={chunk_size} must be >= 1.",
                                      fix="give a positive number of receiving boxes."))
    rows = None if chunk_size is None else int(chunk_size)
    n, nk = mesh.n, kk.size
    nq = dk.SAMPLES[method].size
    wv = kk / (0.5 * refc)                                       # omega / V = k / b
    senders = [(1.0, _senders(mesh, dk.SAMPLES[method], wv))]
    if s:
        senders.append((-float(s), _senders(mirror_xz(mesh), dk.SAMPLES[method], wv)))
    if chunk_size is None:                       # ~_TARGET_PAIRS (receiver, point) pairs per block
        rows = max(1, (9 * _TARGET_PAIRS) // max(1, senders[0][1]["xq"].size * (8 + nk)))
    out = np.zeros((nk, n, n), dtype=complex)
    strips = _strips(mesh)
    groups = _mirror_pairs(mesh, strips, senders)
    local = threading.local()

    def run(group):
        """One receiving strip (and its mirror strip): set-up once, then blocks of `rows`."""
        if not hasattr(local, "scratch"):
            local.scratch = dk.Scratch()                         # per-thread work arrays
        idxs = [strips[i] for i in group]
        for factor, snd in senders:
            setups = []
            for g, idx in enumerate(idxs):
                yz, nrm = mesh.collocation[idx[0], 1:], mesh.normal[idx[0]]
                setups.append((_strip_setup(yz, nrm, snd, wv, method, m, kernel=g == 0),
                               None if g == 0 else snd["mirror"]))
            for i0 in range(0, idxs[0].size, rows):              # strips' rows are disjoint
                incs = _increment_rows(mesh.collocation[idxs[0][i0:i0 + rows], 0], setups, snd,
                                       m, wv, nq, local.scratch)
                for idx, inc in zip(idxs, incs):
                    sub = idx[i0:i0 + rows]
                    if factor != 1.0:
                        inc *= factor
                    if not np.isfinite(inc).all():               # singular pair: report it
                        bad.extend((int(a), int(sub[b]), int(c)) for a, b, c in
                                   np.argwhere(~np.isfinite(inc))[:1])
                    out[:, sub] += inc

    nthreads = min(len(groups), os.cpu_count() or 1) if workers is None else int(workers)
    bad = []                                                     # (k, i, j) of non-finite D
    if nthreads > 1:                                             # numpy releases the GIL
        with ThreadPoolExecutor(max_workers=nthreads) as pool:
            steady = pool.submit(steady_aic, mesh, m, symxz=s)
            list(pool.map(run, groups))
            steady = steady.result()
    else:
        for group in groups:
            run(group)
        steady = steady_aic(mesh, m, symxz=s)
    out += steady[None]
    if not np.isfinite(steady).all():
        bad.extend((0, int(i), int(j)) for i, j in np.argwhere(~np.isfinite(steady))[:1])
    if bad:
        _, i, j = min(bad)
        raise InputError(card_message(
            f"the doublet-lattice AIC is singular for receiving box {mesh.box_id[i]} and sending "
            f"box {mesh.box_id[j]} (or its XZ image): the collocation point lies on the "
            "streamwise extension of a side edge of the sending box in its plane, or on its "
            "doublet line (overlapping panels).",
            card="CAERO1", card_id=int(mesh.panel_id[j]),
            fix="align the spanwise divisions (NSPAN/LSPAN) of coplanar panels, remove overlaps, "
                "or move one panel slightly out of the other's plane."))
    return out


def check_mesh_for_k(mesh: BoxMesh, mach: float, kmax: float, refc: float) -> list[str]:
    """Box-size checks of a mesh for reduced frequencies up to ``kmax``.

    Two modelling rules for the doublet-lattice method from Rodden & Johnson, MSC.Nastran
    Aeroelastic Analysis User's Guide (1994), chapter 2 (doublet-lattice modelling guidelines):
    the streamwise box chord should satisfy dx < 0.08 V/f, i.e. at least 12.5 boxes per
    wavelength V/f = 2 pi b / k (b = refc/2), and boxes should be roughly square; the guide asks
    for aspect ratios of a few at most, and the band [0.25, 4] flagged here is our reading of it.

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
