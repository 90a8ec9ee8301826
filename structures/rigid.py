"""Rigid elements (RBE2, RBAR, RBE3) as multipoint constraints u_m = G u_n, in displacement frames.

Each element gives rows ``u_m - sum_j G_mj u_j = 0`` on g-set DOFs (grid index * 6 + component - 1,
components in the grid's CD frame). Chains (a dependent DOF of one element independent in another)
are resolved in :func:`solve_constraints` by one sparse solve, so element order does not matter.

- RBE2 / RBAR: the element moves as a rigid body q (6 basic DOFs at its first grid); with the
  independent rows S_n and dependent rows S_m of u = S q, u_m = S_m S_n^-1 u_n.
- RBE3: the reference grid follows the weighted least-squares rigid motion of the independent
  points, q = (S^T W S)^-1 S^T W u_n (Nastran QRG RBE3), with rotational weights scaled by the
  square of the mean distance of the independent grids from the reference grid.
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from structures.common.errors import InputError, card_message
from structures.frames import rigid_offset


def _components(text: str) -> list[int]:
    return sorted({int(ch) for ch in str(text) if ch in "123456"})


def _rigid_rows(grids, entries, ref_xyz, elem, filename):
    """Rows of S (u_cd = S q) for (grid, components) entries, and their g-set DOF numbers."""
    if not entries:
        return np.zeros((0, 6)), np.zeros(0, dtype=np.int64)
    gi = grids.index([gid for gid, _ in entries], card=elem.card, card_id=elem.eid,
                     filename=filename)
    comps = [_components(c) for _, c in entries]
    # u_cd = blockdiag(CD^T, CD^T) (u_ref + theta x r) per grid: (n, 6, 6)
    cd_t = np.swapaxes(grids.cd_axes[gi], -1, -2)
    offset = rigid_offset(grids.xyz[gi] - ref_xyz)
    s_full = np.concatenate([cd_t @ offset[:, :3], cd_t @ offset[:, 3:]], axis=1)
    which = np.repeat(np.arange(len(entries)), [len(c) for c in comps])
    comp = np.array([c - 1 for cs in comps for c in cs], dtype=np.int64)
    return s_full[which, comp], 6 * gi[which] + comp


def element_constraints(grids, elem, filename: str = ""):
    """Constraint rows of one rigid element.

    Returns
    -------
    dep : (nm,) int g-set DOFs made dependent.
    indep : (nn,) int g-set DOFs they depend on.
    g : (nm, nn) float coefficients, u_dep = g @ u_indep.
    """
    first = elem.independent[0][0] if elem.card != "RBE3" else elem.dependent[0][0]
    ref = grids.xyz[grids.index([first], card=elem.card, card_id=elem.eid, filename=filename)[0]]
    s_n, indep = _rigid_rows(grids, elem.independent, ref, elem, filename)
    s_m, dep = _rigid_rows(grids, elem.dependent, ref, elem, filename)
    if len(dep) == 0:
        raise InputError(card_message("the element has no dependent DOFs.", card=elem.card,
                                      card_id=elem.eid, filename=filename,
                                      fix="give the dependent components (CM / CMA, CMB / REFC)."))
    if elem.card in ("RBE2", "RBAR"):
        if len(indep) != 6 or abs(np.linalg.det(s_n)) < 1e-12 * max(1.0, np.abs(s_n).max()) ** 6:
            raise InputError(card_message(
                "the independent DOFs do not define a rigid-body motion (they must be 6 and "
                "independent).", card=elem.card, card_id=elem.eid, filename=filename,
                fix="make the independent components total 123456 (e.g. CNA=123456)."))
        return dep, indep, s_m @ np.linalg.inv(s_n)
    weights = np.repeat(np.asarray(elem.weights, float),
                        [len(_components(c)) for _, c in elem.independent])
    rot_rows = np.concatenate([[c > 3 for c in _components(comps)] for _, comps in elem.independent])
    pts = np.array([grids.xyz[grids.index([g])[0]] for g, _ in elem.independent])
    lc = np.mean(np.linalg.norm(pts - ref, axis=1))
    weights = np.where(rot_rows, weights * max(lc, 1e-30) ** 2, weights)
    normal = s_n.T @ (weights[:, None] * s_n)
    w_eig, w_vec = np.linalg.eigh(normal)
    tol = 1e-10 * w_eig.max()
    null = w_vec[:, w_eig <= tol]
    if null.size and np.abs(s_m @ null).max() > 1e-8 * max(1.0, np.abs(s_m).max()):
        raise InputError(card_message(
            "the independent grids and components do not determine the dependent components "
            "(e.g. collinear points and translations only).", card="RBE3", card_id=elem.eid,
            filename=filename, fix="add independent grids/components or reduce REFC."))
    inv = (w_vec[:, w_eig > tol] / w_eig[w_eig > tol]) @ w_vec[:, w_eig > tol].T
    return dep, indep, s_m @ inv @ s_n.T * weights[None, :]


def solve_constraints(grids, rigid, n_g: int, filename: str = ""):
    """Resolve all rigid elements into u_m = G_mo u_o.

    Parameters
    ----------
    grids : Grids
    rigid : sequence of RigidElement
    n_g : int, number of g-set DOFs.

    Returns
    -------
    m_dofs : (nm,) int sorted dependent g-set DOFs.
    g_mo : scipy.sparse csr (nm, n_g), zero on the m-set columns: u_m = g_mo @ u_g.
    """
    if not rigid:
        return np.zeros(0, dtype=np.int64), sp.csr_matrix((0, n_g))
    owner, rows, cols, vals = {}, [], [], []
    blocks = []
    for elem in rigid:
        dep, indep, g = element_constraints(grids, elem, filename)
        for d in dep:
            if d in owner:
                gid, comp = grids.ids[d // 6], d % 6 + 1
                raise InputError(card_message(
                    f"grid {gid} component {comp} is dependent in both {owner[d][0]} "
                    f"{owner[d][1]} and {elem.card} {elem.eid}.", card=elem.card,
                    card_id=elem.eid, filename=filename,
                    fix="a DOF may be dependent in one rigid element only: make it independent "
                        "in one of them."))
            owner[int(d)] = (elem.card, elem.eid)
        blocks.append((dep, indep, g))
    m_dofs = np.array(sorted(owner), dtype=np.int64)
    for dep, indep, g in blocks:
        rr, cc = np.meshgrid(np.searchsorted(m_dofs, dep), indep, indexing="ij")
        rows.append(rr.ravel())
        cols.append(cc.ravel())
        vals.append(g.ravel())
    rows, cols, vals = np.concatenate(rows), np.concatenate(cols), np.concatenate(vals)
    # the terms on m-set DOFs (chains) and on the others
    on_m = np.isin(cols, m_dofs)
    g_mm = sp.csr_matrix((vals[on_m], (rows[on_m], np.searchsorted(m_dofs, cols[on_m]))),
                         shape=(len(m_dofs), len(m_dofs)))
    g_all_o = sp.csr_matrix((vals[~on_m], (rows[~on_m], cols[~on_m])), shape=(len(m_dofs), n_g))
    g_all_o.eliminate_zeros()
    g_mm.eliminate_zeros()
    if g_mm.nnz == 0:
        return m_dofs, g_all_o
    # Chains: u_m = G_mm u_m + G_mo u_o  ->  (I - G_mm) u_m = G_mo u_o
    lhs = (sp.identity(len(m_dofs), format="csc") - g_mm.tocsc())
    try:
        lu = spla.splu(lhs)
    except RuntimeError:
        raise InputError(card_message("rigid elements form a closed loop of dependencies.",
                                      filename=filename,
                                      fix="break the loop so that no DOF depends on itself.")) from None
    dense_rhs = g_all_o.toarray() if g_all_o.shape[1] * len(m_dofs) < 5e7 else None
    if dense_rhs is not None:
        sol = sp.csr_matrix(lu.solve(dense_rhs))
    else:
        sol = sp.csr_matrix(spla.spsolve(lhs, g_all_o.tocsc()))
    sol.eliminate_zeros()
    return m_dofs, sol
