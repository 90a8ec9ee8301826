"""Normal modes: K phi = lambda M phi for the lowest modes, by shift-invert Lanczos.

The shift sigma is negative (default -(2 pi 0.1 Hz)^2), so K - sigma M is positive definite even for
free-free models, whose rigid-body modes come out near 0 Hz. The factorisation is
:func:`structures.sparse_factor.factorize` (MKL PARDISO when installed, else SuperLU) and the
eigensolver ARPACK (shift-invert mode); small systems use a dense solver on the same shifted
pencil. Modes are mass-normalised (Phi^T M Phi = I) and returned as the modes Dataset
(basic-frame shapes).

Every elastic eigenpair's residual is checked (:func:`eigen_residuals`): when the shift lies so far
below the elastic eigenvalues that the factorisation loses them (rigid-body modes at 0 Hz, elastic
ones at kHz), the solve is repeated at sigma = -lambda_min / 10 (lambda_min the lowest elastic
eigenvalue found); modes that stay inaccurate are named in a warning.

Mechanisms are reported, not hidden: a direction with neither stiffness nor mass makes the shifted
matrix singular, and a zero-frequency mode that is not a rigid-body motion of the structure is a
mechanism; both raise :class:`SolverError` naming the grids that move most.
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
from structures.common.errors import SolverError, card_message
from structures.frames import rigid_offset
from structures.model import FEModel
from structures.modes import modes_dataset
from structures.sparse_factor import PIVOT_RATIO, factorize, massless_mechanism

DEFAULT_SHIFT = -(2.0 * np.pi * 0.1) ** 2
DENSE_LIMIT = 600
#: Largest backward error (:func:`eigen_residuals`) accepted for elastic modes. Measured: accurate
#: solves 1e-16..1e-12 (60,000-DOF plate ~1e-15); the free-free cylinder at the default shift
#: 1e-9..5e-8 (PARDISO) and up to 2e-3 (SuperLU, roots 1.5 % off).
RESIDUAL_TOL = 1e-10
#: Eigenvalues above this fraction of the largest one found are elastic for the residual check.
ELASTIC_RATIO = 1e-6


def solve_eigen(k: sp.spmatrix, m: sp.spmatrix, nmodes: int, *, shift: float = DEFAULT_SHIFT,
                groups: np.ndarray | None = None,
                filename: str = "") -> tuple[np.ndarray, np.ndarray]:
    """Lowest ``nmodes`` eigenpairs of (K, M).

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
    n = k.shape[0]
    nmodes = min(nmodes, n)
    shifted = (k - shift * m).tocsc()
    if n <= DENSE_LIMIT:
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
        lam = shift + 1.0 / mu
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
                "parts, near mechanisms) or ask for fewer modes."), RuntimeWarning, stacklevel=2)
    gm = np.einsum("ij,ij->j", vec, m @ vec)
    return lam, vec / np.sqrt(gm)


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
    # cheaper multi-right-hand-side solves.
    op = spla.LinearOperator((n, n), matvec=factor.solve, dtype=float)
    ncv = min(n, max(2 * nmodes + 1, nmodes + 20))
    try:
        with ThreadpoolController().select(internal_api="openblas").limit(limits=1):
            lam, vec = spla.eigsh(k, k=nmodes, M=m, sigma=shift, which="LM", OPinv=op,
                                  ncv=ncv, tol=1e-9)
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


def _check_mechanisms(model, system, lam, phi, scale):
    zero = np.abs(lam) <= 1e-12 * scale
    if not np.any(zero):
        return
    rb = rigid_body_basis(model, system)
    q, _ = np.linalg.qr(rb)
    for j in np.flatnonzero(zero):
        u = system.T @ phi[:, j]
        resid = u - q @ (q.T @ u)
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
    nmodes : int, default the deck's EIGRL/EIGR ND, else 20.
    mass : {'deck', 'consistent', 'lumped'}
    shift : float, negative spectral shift (rad/s)^2.
    system : AssembledSystem, optional, reuse an existing assembly.

    Returns
    -------
    xarray.Dataset with ``frequency(mode)`` [Hz], ``shape(mode, dof)`` (basic frame),
    ``generalized_mass(mode)`` and the dof coordinates; ``attrs['nmodes_requested']``.
    """
    if system is None:
        system = assemble(model, mass)
    n = nmodes or model.eigrl_nd or 20
    lam, phi = solve_eigen(system.K, system.M, n, shift=shift, groups=system.a_dofs // 6,
                           filename=model.filename)
    dk = system.K.diagonal()
    dm = system.M.diagonal()
    ratio = dk[dm > 0] / dm[dm > 0]
    scale = float(np.median(ratio)) if ratio.size else 1.0
    _check_mechanisms(model, system, lam, phi, scale)
    freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
    shapes = (system.rotation @ (system.T @ phi)).T
    return modes_dataset(freq, shapes, model.grids.ids, model.grids.xyz, source="our solver",
                         deck=model.filename, units=model.units,
                         extra_attrs={"mass_formulation": mass, "eigenvalue_shift": shift})
