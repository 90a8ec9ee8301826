"""Normal modes: K phi = lambda M phi for the lowest modes, by shift-invert Lanczos.

The shift sigma is negative (default -(2 pi 0.1 Hz)^2), so K - sigma M is positive definite even for
free-free models, whose rigid-body modes come out near 0 Hz. The factorisation is
:func:`structures.sparse_factor.factorize` (MKL PARDISO when installed, else SuperLU) and the
eigensolver ARPACK (shift-invert mode); small systems use a dense solver on the same shifted
pencil. Modes are mass-normalised (Phi^T M Phi = I) and returned as the modes Dataset
(basic-frame shapes).

Every elastic eigenpair of the sparse solve is checked (:func:`eigen_residuals`): when the shift
lies so far below the elastic eigenvalues that the factorisation loses them (rigid-body modes at
0 Hz, elastic ones at kHz), the solve is repeated at sigma = -lambda_min / 10 (lambda_min the
lowest elastic eigenvalue found); modes that stay inaccurate are named in a warning. The dense
solve (up to ``DENSE_LIMIT`` DOFs) is not: it resolves mu = 1 / (lambda - sigma) to about
eps / |sigma|, a relative error of about eps lambda / |sigma| in lambda (by that estimate 2e-13
for a 3 Hz mode at the default shift; measured 3e-6 on the stiff 40-mass chain of
tests/structures/test_modal_solve.py at 100 x the default shift). The same check on the dense
solves warned on the Craig-Bampton bases of the diagnose joint ladders
(:mod:`pipeline.diagnose.ladder`), whose accuracy is measured against exact reanalysis there.

Rigid-body modes are exact (:func:`rigid_body_modes`): the geometric rigid-body motions the
constraints (or the SUPORT r-set) leave free and that carry no strain energy, M-orthonormal, at
frequency 0.0, with the elastic modes M-orthogonalised against them (:func:`exact_rigid_modes`).

Mechanisms are reported, not hidden: a direction with neither stiffness nor mass makes the shifted
matrix singular, and a zero-frequency mode that is not a rigid-body motion of the structure is a
mechanism; both raise :class:`SolverError` naming the grids that move most. The singularity test
(a pivot below ``PIVOT_RATIO`` of its diagonal entry, :mod:`structures.sparse_factor`) can also
fail a free-free model that is only stiff: a rigid-body direction's pivot is about -sigma m, m
its mass, against diagonal entries of the stiffest elements. So a failed test is repeated once at
``SHIFT_RETRY`` sigma: a rigid-body direction's pivot grows with -sigma, a massless mechanism's
stays round-off. Measured on the X-56A-class empty-fuel model with the section of its engine deck
(CBAR 5001, spine to pylon root, the spine's PBAR) x 1.52 (a taper the diagnose screening samples):
pivot ratio 5.1e-12 at the default shift, 5.1e-10 at 100 x; the 24 elastic frequencies of the
retry agree with a solve at 10^4 x to 2e-8.
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
import xarray as xr
from threadpoolctl import ThreadpoolController

from structures.assembly import AssembledSystem, assemble
from structures.common.errors import InputError, SolverError, card_message
from structures.frames import rigid_offset
from structures.model import FEModel
from structures.modes import modes_dataset
from structures.sparse_factor import (PIVOT_RATIO, MasslessMechanism, factorize,
                                      massless_mechanism)

DEFAULT_SHIFT = -(2.0 * np.pi * 0.1) ** 2
#: Factor on the shift for the one repeated solve after a failed singularity test (module
#: docstring).
SHIFT_RETRY = 100.0
DENSE_LIMIT = 600
#: Largest backward error (:func:`eigen_residuals`) accepted for elastic modes. Measured: accurate
#: solves 1e-16..1e-12 (60,000-DOF plate ~1e-15); the free-free cylinder at the default shift
#: 1e-9..5e-8 (PARDISO) and up to 2e-3 (SuperLU, roots 1.5 % off).
RESIDUAL_TOL = 1e-10
#: ARPACK's convergence tolerance on the Ritz values, a decade below RESIDUAL_TOL. Measured on a
#: 900-DOF pencil with massless DOFs, 40 solves each from ARPACK's own random starts: tol = 1e-9
#: gave backward errors up to 1.07e-10 (over RESIDUAL_TOL: a spurious warning), 1e-10 up to
#: 1.1e-11, 1e-11 up to 2.7e-13.
LANCZOS_TOL = 1e-11
#: Modes computed when neither the caller nor the deck (EIGRL/EIGR ND) says how many.
DEFAULT_NMODES = 20
#: Eigenvalues above this fraction of the largest one found are elastic for the residual check.
ELASTIC_RATIO = 1e-6
#: Largest backward error ||K phi|| / || |K| |phi| || of a rigid-body mode. Measured: 7e-17 (the
#: free-free beam, the cylinder, the X-56A-class aircraft) to 3e-15 (bah_plane); a motion held by
#: springs shows their force relative to the structure's (1.0 for the two-mode plate on springs,
#: k_spring / k_structure in general): the X-56A-class aircraft on its bungees (0.5-1.7 Hz
#: suspension modes) 2.5e-8 to 4.5e-7, and with a one-element engine-pylon member split in four
#: and bowed (stiffer pieces) down to 9.3e-11, which the former limit 1e-10 took for a rigid
#: motion. 1e-13 keeps 30 x round-off's largest; a spring below it would hold its motion at
#: ~3e-7 of the structure's frequencies.
RIGID_TOL = 1e-13
#: Rigid-body motions by basic axis (translations 1-3, rotations 4-6; Nastran aircraft axes:
#: x along the fuselage, y spanwise, z up).
RIGID_MOTIONS = ("surge", "sway", "plunge", "roll", "pitch", "yaw")


def solve_eigen(k: sp.spmatrix, m: sp.spmatrix, nmodes: int, *, shift: float = DEFAULT_SHIFT,
                groups: np.ndarray | None = None,
                filename: str = "") -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``nmodes`` eigenpairs of (K, M).

    When K - sigma M fails the singularity test, the solve is repeated once at
    ``SHIFT_RETRY`` sigma (module docstring): a massless mechanism fails again and raises.

    Parameters
    ----------
    k, m : sparse (n, n) symmetric; M positive semi-definite.
    nmodes : int
    shift : float, negative shift sigma (rad/s)^2.
    groups : (n,) int, optional, the grid of each DOF (orders the factorisation by grids).

    Returns
    -------
    lam : (nmodes,) eigenvalues (rad/s)^2, ascending.
    phi : (n, nmodes) mass-normalised eigenvectors.
    """
    try:
        return _solve_at(k, m, nmodes, shift, groups, filename)
    except MasslessMechanism:
        return _solve_at(k, m, nmodes, SHIFT_RETRY * shift, groups, filename)


def _solve_at(k, m, nmodes: int, shift: float, groups, filename: str) -> tuple:
    """:func:`solve_eigen` at one shift (the sparse solve's residual check may move it once)."""
    nmodes = min(nmodes, k.shape[0])
    shifted = (k - shift * m).tocsc()
    if k.shape[0] <= DENSE_LIMIT:
        lam, vec = _dense(m, nmodes, shifted, shift, filename)
    else:
        lam, vec = _shift_invert(k, m, nmodes, shifted, shift, groups, filename)
        inaccurate = _inaccurate(k, m, lam, vec)
        if inaccurate.any() and -0.1 * lam[lam > ELASTIC_RATIO * lam.max()].min() < shift:
            # The shift is far below the elastic eigenvalues (e.g. rigid-body modes at 0 and
            # elastic modes at kHz): K - sigma M is then nearly singular along the rigid-body
            # motions and the solves lose the elastic components. Solve again at
            # sigma = -lambda_min / 10, lambda_min the lowest elastic eigenvalue found.
            shift = -0.1 * float(lam[lam > ELASTIC_RATIO * lam.max()].min())
            lam, vec = _shift_invert(k, m, nmodes, (k - shift * m).tocsc(), shift, groups,
                                     filename)
            inaccurate = _inaccurate(k, m, lam, vec)
        if inaccurate.any():
            warnings.warn(card_message(
                f"modes {(np.flatnonzero(inaccurate) + 1).tolist()} have eigenpair residuals above "
                f"{RESIDUAL_TOL:.0e} (relative; shift sigma = {shift:.4g}): they are inaccurate.",
                filename=filename, fix="check the model's conditioning (very stiff or very light "
                "parts, near mechanisms) or ask for fewer modes."), RuntimeWarning, stacklevel=3)
    gm = np.einsum("ij,ij->j", vec, m @ vec)
    return lam, vec / np.sqrt(gm)


def _dense(m, nmodes: int, shifted: sp.csc_matrix, shift: float,
           filename: str) -> tuple[np.ndarray, np.ndarray]:
    """Dense generalised eigen-solution of (M, K - sigma M); eigenpairs ascending."""
    dense = shifted.toarray()
    try:
        chol = sla.cholesky(dense, lower=True)
    except np.linalg.LinAlgError:
        raise massless_mechanism(filename) from None
    if np.any(np.diag(chol) ** 2 <= PIVOT_RATIO * np.diag(dense)):
        raise massless_mechanism(filename)
    mu, vec = sla.eigh(m.toarray(), dense)
    order = np.argsort(-mu)[:nmodes]
    mu, vec = mu[order], vec[:, order]
    if np.any(mu <= 0):
        raise SolverError(card_message(
            f"only {int(np.sum(mu > 0))} degrees of freedom carry mass; {nmodes} modes were "
            "asked for.", filename=filename, fix="ask for fewer modes or add mass."))
    return shift + 1.0 / mu, vec


def _shift_invert(k, m, nmodes: int, shifted: sp.csc_matrix, shift: float, groups,
                  filename: str) -> tuple[np.ndarray, np.ndarray]:
    """ARPACK shift-invert on the factorised ``shifted`` = K - sigma M; eigenpairs ascending."""
    n = k.shape[0]
    factor = factorize(shifted, groups=groups, filename=filename)
    # ARPACK's small dense steps gain nothing from BLAS threads and lose a lot when the cores
    # are shared: run OpenBLAS on one thread (MKL PARDISO's solves keep their threads; a
    # threadpool_limits(user_api="blas") would limit MKL too). A block Lanczos with 12-vector
    # PARDISO solves was no faster (2.5-2.9 s against 2.3-2.5 s at 60,744 DOF, 11.1-11.9 s
    # against 11.5-12.3 s at 241,500, 40 modes): more vectors (~180 against ~103) offset the
    # cheaper multi-right-hand-side solves. A Lanczos basis of nmodes + 20..30 vectors takes the
    # fewest solves (60,744-DOF plate: 86 solves for 40 modes against 103 with 2 nmodes + 1; 51
    # for 20 modes, 156 for 80 against 162; 31 for 10), eigenvalues unchanged to 3e-14.
    mass = m.diagonal()
    carried = np.flatnonzero(mass > 0)
    lumped = m.count_nonzero() == carried.size and nmodes < carried.size
    size = carried.size if lumped else n
    ncv = min(size, nmodes + int(np.clip(nmodes, 20, 30)))
    if lumped:
        # Diagonal (lumped) M = diag(D, 0): the standard symmetric problem C y = mu y on the
        # DOFs with mass alone, C = D^1/2 [(K - sigma M)^-1]_mm D^1/2, mu = 1 / (lambda - sigma)
        # (Ericsson & Ruhe 1980, Math. Comp. 35, eq. 2.3, with the massless DOFs condensed):
        # Lanczos vectors half as long at 60,744 DOF (30,372 with mass), 0.2 s less ARPACK work
        # for 40 modes; phi = (K - sigma M)^-1 M phi / mu from one block solve, residuals ~1e-15.
        root = np.sqrt(mass[carried])

        def reduced(y: np.ndarray) -> np.ndarray:
            b = np.zeros(n)
            b[carried] = root * y
            return root * factor.solve(b)[carried]

        op = spla.LinearOperator((size, size), matvec=reduced, dtype=float)
    else:
        op = spla.LinearOperator((n, n), matvec=factor.solve, dtype=float)
    # A fixed start vector (from a local generator: the global numpy state is untouched) makes
    # the solve repeatable; ARPACK's own random start advances from call to call in a process.
    v0 = np.random.default_rng(0).standard_normal(size)
    try:
        with ThreadpoolController().select(internal_api="openblas").limit(limits=1):
            if lumped:
                mu, y = spla.eigsh(op, k=nmodes, which="LA", ncv=ncv, tol=LANCZOS_TOL, v0=v0)
                b = np.zeros((n, nmodes))
                b[carried] = root[:, None] * y
                lam, vec = shift + 1.0 / mu, factor.solve(b) / mu
            else:
                lam, vec = spla.eigsh(k, k=nmodes, M=m, sigma=shift, which="LM", OPinv=op,
                                      ncv=ncv, tol=LANCZOS_TOL, v0=v0)
    except spla.ArpackNoConvergence as exc:
        raise SolverError(card_message(f"the eigensolver did not converge ({exc}).",
                                       filename=filename,
                                       fix="ask for fewer modes or check the model.")) from None
    order = np.argsort(lam)
    lam, vec = lam[order], vec[:, order]
    return lam, vec


def _inaccurate(k, m, lam: np.ndarray, phi: np.ndarray) -> np.ndarray:
    """(nmodes,) bool: elastic modes whose :func:`eigen_residuals` exceed RESIDUAL_TOL."""
    return (lam > ELASTIC_RATIO * lam.max()) & (eigen_residuals(k, m, lam, phi) > RESIDUAL_TOL)


def eigen_residuals(k: sp.spmatrix, m: sp.spmatrix, lam: np.ndarray,
                    phi: np.ndarray) -> np.ndarray:
    """Componentwise backward error of each eigenpair,
    ||K phi - lam M phi|| / (|| |K| |phi| || + |lam| || |M| |phi| ||).

    Normalised by the absolute-value products, the measure is round-off (~1e-16) for an accurate
    pair whatever its frequency; ``||K phi||`` would be tiny for the low modes of a stiff model and
    make accurate pairs look inaccurate.

    Parameters
    ----------
    k, m : sparse (n, n)
    lam : (nmodes,) eigenvalues
    phi : (n, nmodes) eigenvectors

    Returns
    -------
    (nmodes,) backward errors
    """
    kp, mp = k @ phi, m @ phi
    scale = (np.linalg.norm(abs(k) @ np.abs(phi), axis=0)
             + np.abs(lam) * np.linalg.norm(abs(m) @ np.abs(phi), axis=0))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.linalg.norm(kp - mp * lam, axis=0) / scale


def rigid_body_basis(model: FEModel, system: AssembledSystem) -> np.ndarray:
    """Rigid-body motions (about the basic origin) of all g-set DOFs in CD frames: (ng, 6)."""
    grids = model.grids
    d_basic = rigid_offset(grids.xyz).reshape(-1, 6)
    return system.rotation.T @ d_basic


def _null_rows(a: np.ndarray, tol: float) -> np.ndarray:
    """(6, nf) orthonormal basis of the null space of ``a`` (., 6): singular values <= ``tol``."""
    if a.shape[0] == 0:
        return np.eye(6)
    # R of a = QR has a's singular values and right singular vectors; the SVD of the tall ``a``
    # itself would build its (n, n) left factor (28 GB at 61,206 DOF).
    _, sv, vt = np.linalg.svd(np.linalg.qr(a, mode="r"))
    return vt[np.sum(sv > tol):].T


def _echelon_names(q: np.ndarray) -> tuple[np.ndarray, list[int]]:
    """Reduced row echelon form of the motions ``q`` (6, nr) with the rotations as leading
    columns: each column then starts with its own motion (a rotation, about a point the
    constraints fix, or a pure translation). Returns (6, nr) columns and their motion index."""
    order = [3, 4, 5, 0, 1, 2]
    b = q.T[:, order].copy()
    pivots, row = [], 0
    for col in range(6):
        if row == b.shape[0]:
            break
        r = row + int(np.argmax(np.abs(b[row:, col])))
        if abs(b[r, col]) <= 1e-8 * np.abs(b).max():
            continue
        b[[row, r]] = b[[r, row]]
        b[row] /= b[row, col]
        others = np.arange(b.shape[0]) != row
        b[others] -= np.outer(b[others, col], b[row])
        pivots.append(order[col])
        row += 1
    out = np.empty_like(b)
    out[:, order] = b
    return out[:row].T, pivots


def _m_orthonormal(m, v: np.ndarray, against: np.ndarray | None = None) -> np.ndarray:
    """Gram-Schmidt of the columns of ``v`` in the M inner product (twice, for round-off), after
    removing their M-projection on the M-orthonormal columns ``against``."""
    v = np.array(v, dtype=float)
    for _ in range(2):
        if against is not None and against.shape[1]:
            v -= against @ (against.T @ (m @ v))
        for j in range(v.shape[1]):
            w = v[:, j]
            if j:
                w = w - v[:, :j] @ (v[:, :j].T @ (m @ w))
            v[:, j] = w / np.sqrt(w @ (m @ w))
    return v


def _not_autospc(system: AssembledSystem) -> np.ndarray:
    """(ng,) bool: the g-set DOFs AUTOSPC does not hold (a rigid motion need not vanish there)."""
    keep = np.ones(system.T.shape[0], dtype=bool)
    keep[system.autospc] = False
    return keep


def rigid_body_modes(model: FEModel, system: AssembledSystem) -> tuple[np.ndarray, list[str]]:
    """Exact rigid-body modes of a free or partly free model, from the geometry.

    The candidates are the six rigid-body motions the constraints allow: those that the reduction
    to the a-set keeps, u_g = T u_a on every g-set DOF but the automatic SPCs (SPC, GRID PS and
    rigid elements restrict them; a free-free model keeps all six). Of these, the rigid-body modes
    are the motions with no strain energy: the eigenvectors of the candidates' (K_r, M_r) whose
    backward error ||K phi|| / || |K| |phi| || is at most :data:`RIGID_TOL` (round-off for a
    rigid motion; a spring to ground leaves k_spring / k_structure). A mechanism is not a
    rigid-body motion and is not among them (:func:`compute_modes` reports it as before).

    With SUPORT / SUPORT1 (the r-set), the modes are the rigid motions of unit displacement of
    each r-set DOF, as Nastran's rigid-body modes (MSC Dynamic Analysis Guide, "Rigid-body
    modes": D_rigid from the geometry); the r-set must be statically determinate: as many DOFs as
    rigid-body modes, and determining them. Their names are the r-set components' (a SUPORT
    component 5 is "pitch"; components are in the grid's displacement frame).

    Each mode is named by its motion in the basic axes (:data:`RIGID_MOTIONS`; x along the
    fuselage, y spanwise, z up): the translations first, then the rotations, Gram-Schmidt in the
    M inner product in that order, so the rotations turn about the centre of gravity in the free
    directions, and Phi_r^T M Phi_r = I.

    Parameters
    ----------
    model : FEModel
    system : AssembledSystem

    Returns
    -------
    phi : (na, nr) a-set rigid-body modes, M-orthonormal.
    names : list of str, (nr,) motion of each mode.
    """
    rb = np.asarray(rigid_body_basis(model, system))
    span = np.ptp(model.grids.xyz, axis=0).max() or 1.0
    rb = rb * np.r_[np.ones(3), np.full(3, 1.0 / span)]   # rotations scaled to the model's size
    ra = rb[system.a_dofs]
    keep = _not_autospc(system)
    free = _null_rows((rb - system.T @ ra)[keep], 1e-9)   # rb's entries are O(1)
    v = ra @ free
    if v.shape[1] == 0:
        return np.zeros((ra.shape[0], 0)), []
    b = v
    v = _m_orthonormal(system.M, b)
    _, z = np.linalg.eigh(v.T @ (system.K @ v))
    # v = b G (Gram-Schmidt): the strain-free combinations v z go back to the motions through
    # b^+, not as free @ z (which holds only when all of them are strain-free)
    q = free @ np.linalg.lstsq(b, v @ z[:, _backward_error(system.K, v @ z) <= RIGID_TOL],
                               rcond=None)[0]
    if model.suport:
        return _suport_modes(model, system, rb, q)
    q, motion = _echelon_names(q)
    order = np.argsort(motion, kind="stable")
    phi = _m_orthonormal(system.M, ra @ q[:, order])
    return phi, [RIGID_MOTIONS[motion[i]] for i in order]


def _suport_modes(model, system, rb, q):
    """Rigid-body modes of unit r-set displacements (SUPORT / SUPORT1), see rigid_body_modes."""
    index = model.grids.index([g for g, _ in model.suport], card="SUPORT",
                              filename=model.filename)
    r_dofs = np.array([6 * g + c for g, (_, mask) in zip(index, model.suport) for c in range(6)
                       if mask >> c & 1])
    r_dofs = r_dofs[np.argsort(r_dofs % 6, kind="stable")]   # translations first
    ids = model.grids.ids[r_dofs // 6]
    on_a = np.isin(r_dofs, system.a_dofs)
    if not on_a.all():
        bad = int(np.flatnonzero(~on_a)[0])
        raise InputError(card_message(
            f"grid {ids[bad]} component {r_dofs[bad] % 6 + 1} is a SUPORT DOF but is constrained "
            "(SPC, GRID PS, rigid element dependent or no stiffness).", card="SUPORT",
            card_id=int(ids[bad]), filename=model.filename,
            fix="support only DOFs that are free; remove it from SUPORT or from the SPC set."))
    d_r = rb[r_dofs] @ q
    if d_r.shape[0] != q.shape[1] or np.linalg.matrix_rank(d_r, tol=1e-8 * max(
            np.abs(d_r).max(initial=0.0), 1e-300)) < q.shape[1]:
        raise InputError(card_message(
            f"the SUPORT DOFs {[(int(g), int(c) + 1) for g, c in zip(ids, r_dofs % 6)]} do not "
            f"determine the model's {q.shape[1]} rigid-body motions (they must be as many, and "
            "statically determinate).", card="SUPORT", card_id=int(ids[0]),
            filename=model.filename,
            fix=f"give {q.shape[1]} SUPORT components that fix every rigid-body motion, e.g. "
                "a grid near the CG with the free components."))
    phi = _m_orthonormal(system.M, rb[system.a_dofs] @ (q @ np.linalg.inv(d_r)))
    return phi, [RIGID_MOTIONS[c] for c in r_dofs % 6]


def _backward_error(k, v: np.ndarray) -> np.ndarray:
    """(nv,) ||K v|| / || |K| |v| || of the columns of ``v`` (eigen_residuals at lambda = 0)."""
    return eigen_residuals(k, k, np.zeros(v.shape[1]), v)


def exact_rigid_modes(m, lam: np.ndarray, phi: np.ndarray,
                      phi_r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Replace the lowest eigenpairs by the exact rigid-body modes.

    Parameters
    ----------
    m : sparse (na, na) mass.
    lam : (n,) eigenvalues, ascending; the lowest nr (by min-max, <= the largest Rayleigh quotient
        of the rigid motions, zero) are the rigid-body ones.
    phi : (na, n) mass-normalised eigenvectors.
    phi_r : (na, nr) M-orthonormal rigid-body modes (:func:`rigid_body_modes`).

    Returns
    -------
    lam : (n,) with lam[:nr] = 0 exactly, the elastic eigenvalues unchanged.
    phi : (na, n) rigid modes first, then the elastic ones M-orthogonalised against them and each
        other (Gram-Schmidt in the M inner product) and re-normalised: Phi^T M Phi = I.
    """
    nr = min(phi_r.shape[1], len(lam))
    if nr == 0:
        return lam, phi
    elastic = _m_orthonormal(m, phi[:, nr:], against=phi_r[:, :nr])
    return (np.concatenate([np.zeros(nr), lam[nr:]]),
            np.concatenate([phi_r[:, :nr], elastic], axis=1))


#: Largest |eigenvalue| of a rigid-body mode, as a fraction of the first elastic eigenvalue
#: (:func:`_check_rigid_count`). Measured round-off: 1e-11 on the X-56A-class model, 1.2e-6 to
#: 1.6e-6 on it with a main-gear leg's or engine deck's section scaled 1.3-1.5 (the diagnose
#: screening's taper samples: stiff elements, K's round-off eps max|K|), 2e-6 with a joint at
#: compliance 1e-6. A rigid mode the solve missed puts the first elastic eigenvalue among them,
#: a ratio of lambda_1 / lambda_2 of the elastic modes: 1e-4 would be a first elastic mode 100 x
#: below the second in frequency.
RIGID_ZERO = 1e-4


#: Modes asked for, as a multiple of those wanted (plus the rigid-body ones), when a solve
#: missed a rigid-body mode (:func:`compute_modes`). Measured: the Dakota cylinder
#: (tests/data/dakota_cylinder, 2028 DOFs) with a mirror pair of masses with rotary inertia on
#: its shell, as the diagnose screening writes it, had five of its six zeros at 8 and 9 modes,
#: all six at 10 and more.
RIGID_RETRY = 2


def _rigid_ratio(lam: np.ndarray, nr: int) -> float:
    """Largest |eigenvalue| of the nr lowest, as a fraction of the next (0 when there is no
    next one or no rigid-body motion)."""
    if nr == 0 or nr >= lam.size:
        return 0.0
    first = max(abs(float(lam[nr])), np.finfo(float).tiny)
    return float(np.abs(lam[:nr]).max()) / first


def _check_rigid_count(model, lam: np.ndarray, nr: int) -> None:
    """The nr lowest eigenvalues that :func:`exact_rigid_modes` replaces must be rigid-body ones:
    zero next to the first elastic eigenvalue (below ``RIGID_ZERO`` of it); an eigen-solution
    that missed a rigid mode would otherwise lose its first elastic mode."""
    ratio = _rigid_ratio(lam, nr)
    if ratio > RIGID_ZERO:
        first = max(abs(float(lam[nr])), np.finfo(float).tiny)
        zero = int(np.sum(np.abs(lam[:nr]) <= RIGID_ZERO * first))
        raise SolverError(card_message(
            f"the model has {nr} rigid-body motions, but only {zero} of the lowest eigenvalues "
            f"are zero (largest of them {ratio:.3g} x the first elastic one).",
            filename=model.filename,
            fix="check the constraints and SUPORT: a rigid motion the model should not have (a "
                "solve with twice the modes found no more zeros)."))


def _check_mechanisms(model, system, lam, phi, scale):
    """A zero-frequency mode that is no rigid-body motion raises. The comparison leaves out the
    DOFs AUTOSPC holds (as :func:`rigid_body_modes` does): a rigid rotation turns the rotations of
    a grid that only rods or solids reach, which stay zero in every mode (the BAH wing with a
    grid on three rods was a 'mechanism' until then)."""
    zero = np.abs(lam) <= 1e-12 * scale
    if not np.any(zero):
        return
    keep = _not_autospc(system)
    q, _ = np.linalg.qr(rigid_body_basis(model, system)[keep])
    for j in np.flatnonzero(zero):
        u = system.T @ phi[:, j]
        resid = np.zeros_like(u)
        resid[keep] = u[keep] - q @ (q.T @ u[keep])
        if np.linalg.norm(resid) > 1e-4 * np.linalg.norm(u):
            # A constrained model has no rigid-body motion to remove: the mode itself shows where
            # the mechanism is (the residual would spread it over the clamped grids).
            shown = u if (model.spc or np.any(model.grids.ps)) else resid
            moving = np.argsort(-np.abs(shown).reshape(-1, 6).max(axis=1))[:5]
            raise SolverError(card_message(
                f"mode {j + 1} has zero frequency but is not a rigid-body motion: the model has a "
                f"mechanism (grids moving most: {model.grids.ids[moving].tolist()}).",
                filename=model.filename,
                fix="add the missing stiffness or constraints at those grids (SPC, elements)."))


def compute_modes(model: FEModel, nmodes: int | None = None, *, mass: str = "deck",
                  shift: float = DEFAULT_SHIFT,
                  system: AssembledSystem | None = None) -> xr.Dataset:
    """Lowest normal modes of a model as the modes Dataset.

    Parameters
    ----------
    model : FEModel
    nmodes : int, default the deck's EIGRL/EIGR ND, else ``DEFAULT_NMODES``; at most as many as
        degrees of freedom carry mass (a model has no more modes).
    mass : {'deck', 'consistent', 'lumped'}
    shift : float, negative spectral shift (rad/s)^2.
    system : AssembledSystem, optional, reuse an existing assembly.

    Returns
    -------
    xarray.Dataset with ``frequency(mode)`` [Hz], ``shape(mode, dof)`` (basic frame),
    ``generalized_mass(mode)`` and the dof coordinates; the exact rigid-body modes
    (:func:`rigid_body_modes`, frequency 0.0) first, named by coordinate ``rigid_motion(mode)``
    ("plunge", "pitch", ...; "" for elastic modes), with attrs ``rigid_modes`` (their number),
    ``rigid_residual`` (their largest ||K phi|| / || |K| |phi| ||, <= RIGID_TOL) and
    ``modes_requested`` (the number asked for, more than the modes when fewer DOFs carry mass).
    """
    if system is None:
        system = assemble(model, mass)
    dm = system.M.diagonal()
    # A model has as many modes as degrees of freedom carrying mass (the rest condense out)
    carried = int(np.count_nonzero(dm > 0))
    if carried == 0:
        raise SolverError(card_message("no degree of freedom carries mass: the model has no "
                                       "modes.", filename=model.filename,
                                       fix="add mass (CONM2, material density, NSM)."))
    requested = nmodes or model.eigrl_nd or DEFAULT_NMODES
    n = min(requested, carried)
    lam, phi = solve_eigen(system.K, system.M, n, shift=shift, groups=system.a_dofs // 6,
                           filename=model.filename)
    dk = system.K.diagonal()
    ratio = dk[dm > 0] / dm[dm > 0]
    scale = float(np.median(ratio)) if ratio.size else 1.0
    _check_mechanisms(model, system, lam, phi, scale)
    phi_r, motions = rigid_body_modes(model, system)
    if _rigid_ratio(lam, phi_r.shape[1]) > RIGID_ZERO and n < carried:
        # A Lanczos solve can miss one member of a multiple eigenvalue, the rigid-body zeros:
        # solved again with a larger Krylov space (RIGID_RETRY), the lowest n kept
        more = min(carried, RIGID_RETRY * n + phi_r.shape[1])
        lam, phi = solve_eigen(system.K, system.M, more, shift=shift, groups=system.a_dofs // 6,
                               filename=model.filename)
        lam, phi = lam[:n], phi[:, :n]
        _check_mechanisms(model, system, lam, phi, scale)
    _check_rigid_count(model, lam, phi_r.shape[1])
    lam, phi = exact_rigid_modes(system.M, lam, phi, phi_r)
    freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
    shapes = (system.rotation @ (system.T @ phi)).T
    residual = float(_backward_error(system.K, phi_r).max(initial=0.0))
    ds = modes_dataset(freq, shapes, model.grids.ids, model.grids.xyz, source="our solver",
                       deck=model.filename, units=model.units,
                       extra_attrs={"mass_formulation": mass, "eigenvalue_shift": shift,
                                    "modes_requested": requested,
                                    "rigid_modes": len(motions[:len(lam)]),
                                    "rigid_residual": residual})
    names = (motions + [""] * len(lam))[:len(lam)]
    return ds.assign_coords(rigid_motion=("mode", np.array(names, dtype=str), {
        "long_name": "rigid-body motion of the mode (basic axes), '' for elastic modes"}))
