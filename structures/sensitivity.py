"""Sensitivities for model tuning: eigenvalue and mode-shape derivatives.

**Matrices and their derivatives** K(x), M(x), dK/dx_i, dM/dx_i come from
:class:`structures.subassembly.SubAssembly` (sub-assembly of the elements the variables change;
exact polynomial derivatives where the fields enter polynomially).

**Eigenvalue derivatives** (Fox & Kapoor 1968, mass-normalised phi_j):
d lambda_j = phi_j^T (dK - lambda_j dM) phi_j.

**Mode-shape derivatives.**

- ``"nelson"`` (Nelson 1976): exact for distinct eigenvalues however close (the test uses modes 1 %
  apart). With F = -(dK - lambda_j dM - d lambda_j M) phi_j, solve (K - lambda_j M) v = F with the
  DOF of largest |phi_j| held at zero, then dphi_j = v + c phi_j, c = -phi_j^T M v - phi_j^T dM phi_j / 2.
  One sparse factorisation per mode, all variables as right-hand sides.
- ``"modal"`` (modal method with static residual correction, Wang 1991): the coupling with the m
  computed modes is exact, dphi_j = sum_{k != j} phi_k phi_k^T F0_j / (lambda_k - lambda_j)
  + c_jj phi_j (c_jj = -phi_j^T dM phi_j / 2) plus the truncated modes through the residual
  flexibility of the shifted matrix, +[(K - sigma M)^-1 - sum_k phi_k phi_k^T / (lambda_k - sigma)] F0_j,
  F0_j = -(dK - lambda_j dM) phi_j, and its second term (lambda_j - sigma) [(K - sigma M)^-1 M
  (K - sigma M)^-1 - sum_k phi_k phi_k^T / (lambda_k - sigma)^2] F0_j: the expansion
  1/(lambda_k - lambda_j) = 1/(lambda_k - sigma) + (lambda_j - sigma)/(lambda_k - sigma)^2 + ...
  truncated after two terms for the modes k not computed, so the relative error is of order
  ((lambda_j - sigma) / (lambda_{m+1} - sigma))^2. One factorisation shared by every mode and
  variable (two solves per right-hand side): the fast choice for large models.

**Rigid-body modes** (a zero eigenvalue repeated up to six times) have no unique derivative; they are
replaced by the canonical mass-normalised basis Phi_r = R (R^T M R)^(-1/2) of the design-independent
rigid-body motions R, whose derivative is R d[(R^T M R)^(-1/2)] (Daleckii-Krein divided differences).
"""
from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse.linalg as spla

from structures.common.errors import InputError, SolverError, card_message
from structures.modal import DEFAULT_SHIFT
from structures.subassembly import SubAssembly

SHAPE_METHODS = ("nelson", "modal")


# ---------------------------------------------------------------------------------- rigid modes
def _inv_sqrt_and_derivative(a, da):
    """S = A^(-1/2) for SPD A (r, r) and dS for da (nvar, r, r) by Daleckii-Krein."""
    w, u = np.linalg.eigh(a)
    s = (u / np.sqrt(w)) @ u.T
    f = w ** -0.5
    diff = w[:, None] - w[None, :]
    same = np.abs(diff) <= 1e-12 * np.abs(w).max()
    with np.errstate(divide="ignore", invalid="ignore"):
        dd = np.where(same, -0.5 * w[:, None] ** -1.5, (f[:, None] - f[None, :]) / diff)
    ds = np.einsum("ik,vkl,jl->vij", u, np.einsum("ki,vkl,lj->vij", u, da, u) * dd, u)
    return s, ds


def rigid_modes(rigid, m, dm=None, rows=None):
    """Canonical mass-normalised rigid-body modes Phi_r = R (R^T M R)^(-1/2) and derivatives.

    Parameters
    ----------
    rigid : (na, r) rigid-body motions R of the a-set
    m : sparse (na, na)
    dm : list of sparse (na, na), optional
    rows : sparse (nr, na), optional: the derivatives at these rows only, (rows R) dS

    Returns
    -------
    phi_r : (na, r)
    dphi_r : (nvar, na or nr, r) or None
    """
    mr = m @ rigid
    a = rigid.T @ mr
    if dm is None:
        s, _ = _inv_sqrt_and_derivative(a, np.zeros((0,) + a.shape))
        return rigid @ s, None
    da = np.stack([rigid.T @ (d @ rigid) for d in dm]) if dm else np.zeros((0,) + a.shape)
    s, ds = _inv_sqrt_and_derivative(a, da)
    return rigid @ s, np.einsum("nr,vrs->vns", rigid if rows is None else rows @ rigid, ds)


def split_rigid(lam, rigid, *, tol: float = 1e-6, filename: str = ""):
    """Number of leading rigid-body modes among ``lam`` (ascending): lam < tol * max|lam|.

    Raises SolverError when the count does not match the rank of the rigid-body basis (a partially
    supported model whose rigid modes the canonical basis cannot represent).
    """
    scale = np.max(np.abs(lam))
    n_zero = int(np.sum(lam < tol * scale))
    if n_zero == 0:
        return 0
    if n_zero != rigid.shape[1] or np.linalg.matrix_rank(rigid) != n_zero:
        raise SolverError(card_message(
            f"{n_zero} zero-frequency modes but a rigid-body basis of rank "
            f"{np.linalg.matrix_rank(rigid)}: partially supported models are not supported by tuning.",
            filename=filename, fix="support the model fully (free-free or with suspension springs)."))
    return n_zero


# ----------------------------------------------------------------------------- eigen derivatives
def eigenvalue_derivatives(lam, phi, dk, dm) -> np.ndarray:
    """Fox-Kapoor d lambda_j / dx_i = phi_j^T (dK_i - lambda_j dM_i) phi_j.

    Parameters
    ----------
    lam : (m,), phi : (na, m) mass-normalised, dk, dm : lists (nvar) of sparse (na, na)

    Returns
    -------
    (nvar, m)
    """
    out = np.zeros((len(dk), lam.size))
    for i, (a, b) in enumerate(zip(dk, dm)):
        out[i] = np.einsum("nj,nj->j", phi, a @ phi) - lam * np.einsum("nj,nj->j", phi, b @ phi)
    return out


def _nelson(k, m, lam_j, phi_j, dk, dm, dlam_j, filename):
    """Nelson's method for one simple eigenpair; returns (nvar, na)."""
    n = phi_j.size
    r = int(np.argmax(np.abs(phi_j)))
    keep = np.r_[0:r, r + 1:n]
    mphi = m @ phi_j
    rhs = np.stack([-(a @ phi_j - lam_j * (b @ phi_j)) + dl * mphi
                    for a, b, dl in zip(dk, dm, dlam_j)], axis=1)
    a_mat = (k - lam_j * m).tocsc()[keep][:, keep].tocsc()
    try:
        # indefinite but symmetric: symmetric ordering on the diagonal (no pivoting keeps the fill
        # of the positive-definite shifted matrix; threshold pivoting multiplied it by 20 on the
        # 20,000-DOF benchmark), then one step of iterative refinement below
        lu = spla.splu(a_mat, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                       options={"SymmetricMode": True})
    except RuntimeError:
        raise SolverError(card_message(
            f"Nelson's method: K - lambda M is singular beyond one DOF at lambda = {lam_j:.6g} "
            "(a repeated eigenvalue).", filename=filename,
            fix="use shape_method='modal' or break the symmetry that repeats the eigenvalue.")) from None
    v = np.zeros((n, len(dk)))
    sol = lu.solve(rhs[keep])
    v[keep] = sol + lu.solve(rhs[keep] - a_mat @ sol)                     # iterative refinement
    c = -(mphi @ v) - 0.5 * np.array([phi_j @ (b @ phi_j) for b in dm])
    return (v + phi_j[:, None] * c[None, :]).T


def mode_shape_derivatives(k, m, lam, phi, dk, dm, dlam, *, n_rigid: int = 0, rigid=None,
                           method: str = "nelson", rows=None, shift: float = DEFAULT_SHIFT,
                           lu=None, filename: str = "") -> np.ndarray:
    """d phi / dx for every mode (rigid modes from the canonical basis).

    Parameters
    ----------
    k, m : sparse (na, na)
    lam : (m,) ascending; phi : (na, m) mass-normalised, the first ``n_rigid`` columns being the
        canonical rigid modes of :func:`rigid_modes`
    dk, dm : lists (nvar) of sparse (na, na)
    dlam : (nvar, m) from :func:`eigenvalue_derivatives`
    n_rigid : int
    rigid : (na, r) rigid-body motions (needed when n_rigid > 0)
    method : {'nelson', 'modal'}
    rows : sparse (nr, na), optional: return rows @ dphi only (e.g. the measured DOFs)
    shift : float, sigma of the modal method's residual flexibility (K - sigma M)^-1
    lu : SuperLU of K - sigma M, optional (from :func:`eigenpairs`; factored here if absent)

    Returns
    -------
    (nvar, na or nr, m)
    """
    if method not in SHAPE_METHODS:
        raise InputError(f"unknown mode-shape derivative method {method!r}; valid: "
                         f"{', '.join(SHAPE_METHODS)}.")
    nvar, nmode = len(dk), lam.size
    project = (lambda a: a) if rows is None else (lambda a: rows @ a)
    nrow = phi.shape[0] if rows is None else rows.shape[0]
    out = np.zeros((nvar, nrow, nmode))
    if n_rigid:
        out[:, :, :n_rigid] = rigid_modes(rigid, m, dm, rows)[1]
    elastic = range(n_rigid, nmode)
    if method == "nelson":
        for j in elastic:
            d = _nelson(k, m, lam[j], phi[:, j], dk, dm, dlam[:, j], filename)
            out[:, :, j] = np.stack([project(d[i]) for i in range(nvar)])
        return out
    lu = lu if lu is not None else _shifted_factor(k, m, shift, filename)
    if rows is not None:
        # adjoint form: rows S F = Z1^T F and rows S M S F = Z2^T F with S = (K - sigma M)^-1
        # symmetric, Z1 = S rows^T, Z2 = S M Z1: two solves with n_rows right-hand sides in all
        z1 = lu.solve(np.asarray(rows.T.todense()))
        z2 = lu.solve(m @ z1)
        phi_rows = rows @ phi
    phi_el, lam_el = phi[:, n_rigid:], lam[n_rigid:]
    inv = 1.0 / (lam - shift)[:, None]
    for i in range(nvar):
        # F0 is non-zero only at the DOFs of the elements variable i touches: work on those rows
        dk_i, dm_i = dk[i].tocsr(), dm[i].tocsr()
        touched = np.unique(np.r_[dk[i].tocsc().indices, dm[i].tocsc().indices])
        dm_phi = dm_i[touched] @ phi_el
        f0 = -(dk_i[touched] @ phi_el - dm_phi * lam_el[None, :])         # rows ``touched``
        coupling = phi[touched].T @ f0                                     # (m, m_el) phi_k^T F0_j
        with np.errstate(divide="ignore"):
            gap = lam[:, None] - lam_el[None, :]                           # lambda_k - lambda_j
            coef = np.where(np.abs(gap) > 0, coupling / np.where(gap == 0, 1.0, gap), 0.0)
        coef[np.arange(n_rigid, nmode), np.arange(nmode - n_rigid)] = \
            -0.5 * np.einsum("nj,nj->j", phi_el[touched], dm_phi)          # c_jj
        # 1/(lambda_k - lambda_j) = 1/(lambda_k - s) + (lambda_j - s)/(lambda_k - s)^2 + ... (two terms)
        if rows is None:
            full = np.zeros((phi.shape[0], nmode - n_rigid))
            full[touched] = f0
            s_f = lu.solve(full)
            s2_f = lu.solve(m @ s_f)
            basis = phi
        else:
            s_f, s2_f, basis = z1[touched].T @ f0, z2[touched].T @ f0, phi_rows
        residual = (s_f - basis @ (coupling * inv)
                    + (s2_f - basis @ (coupling * inv ** 2)) * (lam_el - shift)[None, :])
        out[i, :, n_rigid:] = basis @ coef + residual
    return out


def orient(phi, reference=None) -> np.ndarray:
    """Sign-fixed copy of the columns of ``phi``: positive dot product with ``reference``'s
    columns, or largest-magnitude entry positive when no reference is given."""
    phi = np.array(phi, float)
    if reference is None:
        idx = np.argmax(np.abs(phi), axis=0)
        sign = np.sign(phi[idx, np.arange(phi.shape[1])])
    else:
        sign = np.sign(np.einsum("ij,ij->j", phi, reference))
    sign[sign == 0] = 1.0
    return phi * sign


def _shifted_factor(k, m, shift, filename):
    try:
        # positive definite: no pivoting, symmetric ordering (as structures.modal)
        return spla.splu((k - shift * m).tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                         options={"SymmetricMode": True})
    except RuntimeError:
        raise SolverError(card_message("K - sigma M is singular (a massless mechanism).",
                                       filename=filename, fix="see structures.modal: constrain or "
                                                              "give mass to the free motion.")) from None


class _DenseShifted:
    """Cholesky of a small dense K - sigma M with the SuperLU-like ``solve`` the callers use."""

    def __init__(self, a, filename):
        try:
            self.factor = sla.cho_factor(a, lower=True)
        except np.linalg.LinAlgError:
            raise SolverError(card_message("K - sigma M is not positive definite (a massless "
                                           "mechanism).", filename=filename,
                                           fix="constrain or give mass to the free motion.")) from None

    def solve(self, b):
        return sla.cho_solve(self.factor, b)


DENSE_LIMIT = 1200


def eigenpairs(k, m, nmodes: int, *, shift: float = DEFAULT_SHIFT, filename: str = "", v0=None):
    """Lowest eigenpairs of (K, M) on the shifted pencil, with the factorisation kept for reuse.

    Small systems (n <= 1200): Cholesky L L^T = K - sigma M and the largest eigenvalues mu of
    L^-1 M L^-T (lambda = sigma + 1/mu), a subset solve. Larger ones: shift-invert Lanczos on a
    sparse LU of K - sigma M (tol 1e-13).

    v0 : (na,), optional Lanczos start vector (e.g. the sum of the previous design's modes)

    Returns
    -------
    lam : (nmodes,); phi : (na, nmodes) mass-normalised; lu : object with ``solve(b)`` for
    (K - sigma M)^-1 b
    """
    n = k.shape[0]
    if n <= DENSE_LIMIT:
        md = m.toarray()
        lu = _DenseShifted((k - shift * m).toarray(), filename)
        low = lu.factor[0]
        half = sla.solve_triangular(low, md, lower=True)
        c = sla.solve_triangular(low, half.T, lower=True)
        mu, y = sla.eigh(0.5 * (c + c.T), subset_by_index=[n - nmodes, n - 1])
        mu, y = mu[::-1], y[:, ::-1]
        phi = sla.solve_triangular(low, y, lower=True, trans="T")
        lam = shift + 1.0 / mu
    else:
        lu = _shifted_factor(k, m, shift, filename)
        op = spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)
        ncv = min(n, max(2 * nmodes + 1, nmodes + 20))
        try:
            lam, phi = spla.eigsh(k, k=nmodes, M=m, sigma=shift, which="LM", OPinv=op, ncv=ncv,
                                  tol=1e-13, v0=np.ones(n) if v0 is None else v0)
        except spla.ArpackNoConvergence as exc:
            raise SolverError(card_message(f"the eigensolver did not converge ({exc}).",
                                           filename=filename, fix="ask for fewer modes.")) from None
    order = np.argsort(lam)
    lam, phi = lam[order], phi[:, order]
    phi = phi / np.sqrt(np.einsum("ij,ij->j", phi, m @ phi))
    return lam, phi, lu


def model_modes(sub: SubAssembly, x, nmodes: int, *, shift: float = DEFAULT_SHIFT):
    """Eigenpairs at design x with rigid modes replaced by the canonical basis.

    Returns
    -------
    k, m : sparse (na, na); m0 : (6, 6); lam : (nmodes,); phi : (na, nmodes); n_rigid : int;
    lu : SuperLU of K - sigma M (reused by the modal method)
    """
    k, m, m0 = sub.matrices(x)
    start = sub.last_phi
    v0 = start.sum(axis=1) if start is not None and start.shape[1] == nmodes else None
    lam, phi, lu = eigenpairs(k, m, nmodes, shift=shift, filename=sub.model.filename, v0=v0)
    sub.last_phi = phi
    n_rigid = split_rigid(lam, sub.rigid, filename=sub.model.filename)
    phi = orient(phi)
    if n_rigid:
        phi[:, :n_rigid], _ = rigid_modes(sub.rigid, m)
        lam = np.array(lam)
        lam[:n_rigid] = 0.0
    return k, m, m0, lam, phi, n_rigid, lu


__all__ = ["SubAssembly", "eigenvalue_derivatives", "mode_shape_derivatives", "rigid_modes",
           "split_rigid", "model_modes", "eigenpairs", "orient"]
