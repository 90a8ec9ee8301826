"""Reanalysis of a grounded spring over its ladder of sizes on one Ritz basis.

A ``boundary_stiffness`` candidate of size k adds a grounded CELAS2 of stiffness s = k k_ref at
one g-set DOF d (:mod:`pipeline.diagnose.effects`). On the a-set (u_g = T u_a) that is a rank-one
change of the stiffness alone,

    K(k) = K + s e e^T,   e = T^T 1_d  (na,),   M unchanged,

so one basis serves every candidate size. Craig-Bampton with the spring's DOFs as the boundary
does not apply to a free-free model (the interior keeps its rigid-body motions, K_ii is
singular); the basis here is that of the load-dependent Ritz / residual-flexibility methods
(Weissenburger 1968, "Effect of local modifications on the vibration characteristics of linear
systems", J. Appl. Mech. 35(2); the residual-flexibility attachment modes of Craig & Kurdila
2006, Fundamentals of Structural Dynamics, 2nd ed.): the current model's m lowest modes Phi
(rigid-body modes included, mass-normalised, K Phi = M Phi Lambda) and the residual attachment
vector of the spring's load,

    r = (K - sigma M)^-1 e - Phi (Lambda - sigma)^-1 Phi^T e,

the static response to a unit load at d minus the part the kept modes carry (the exact spectral
expansion of (K - sigma M)^-1), M-orthogonalised against Phi and M-normalised. With
Psi = [Phi, r], Psi^T M Psi = I and Psi^T K Psi = diag(Lambda, r^T K r) (r is M- and so
K-orthogonal to the eigenvectors Phi), the modes of size k are those of

    K_r(k) = diag(Lambda, r^T K r) + s w w^T,   w = Psi^T e   ((m + 1), (m + 1), M_r = I).

The exact mode of the changed model is x ~ (K - lambda M)^-1 e (from (K - lambda M) x =
-s e (e^T x)), whose truncated part sum_{j > m} phi_j phi_j^T e / (lambda_j - lambda) is the
residual r up to terms of relative size (lambda - sigma) / lambda_{m+1}: the basis holds the
spring's local flexibility, the elastic mode the spring makes out of a rigid-body motion
(frequency ~ sqrt(s) w_r) and its coupling with the kept modes. Measured against exact
reanalysis (:func:`structures.modal.compute_modes`) on the frame over sizes 1e-3 .. 1: see
:data:`MODE_FACTOR`.

A mirror pair (:mod:`pipeline.diagnose.mirror`) has a spring at each of its two sites, both of
size k: K(k) = K + s E E^T with E = [e_1, e_2], and the basis carries both residual attachment
vectors, M-orthonormalised (R = [r_1, r_2]; K_r(k) = diag(Lambda, R^T K R) + s W W^T, W = Psi^T E).

One factorisation of K - sigma M and one eigen-solution per configuration are shared by every
candidate; a candidate costs one solve, and a rung one dense eigen-solution of size m + q (q = 1,
or 2 for a pair).

A ``lumped_mass`` candidate of size x adds a point mass mu = x m_ref (m_ref the model's total mass,
times PARAM WTMASS) at one grid (three translations, basic axes): M(x) = M + mu E E^T with E the
a-set columns of the grid's basic translations, K unchanged (a spread mass's n grids each take
mu / n: E's columns are each grid's translations times sqrt(1 / n)). The exact mode solves
(K - lambda M) x = lambda mu E (E^T x), x ~ (K - lambda M)^-1 E: the same form as the spring's,
so the same basis serves (:func:`reduce_mass`: Psi = [Phi, R], R the residual attachment vectors
of the three unit loads), with K_r = diag(Lambda, R^T K R) fixed and
M_r(x) = I + mu W W^T, W = Psi^T E; each size is one dense eigen-solution of the standard form
M_r^-1/2 K_r M_r^-1/2 z = lambda z, y = M_r^-1/2 z, with M_r^-1/2 = I + U ((1 + mu s^2)^-1/2 - 1)
U^T from the thin SVD W = U diag(s) V^T (exact: M_r = I + U diag(mu s^2) U^T). A linear screening
of a mass misses the sizes a real one has: on the frame (blind-study mass seed 9, 3.9 % of the mass
on the tail, chi^2 44615 without it) the secant through 2 % ranked the right grid below a mass
elsewhere and a joint; the modes move through each other as the mass grows. The rigid-body motions
are the current model's (a point mass restrains none); the mass properties follow from the
rigid-body mass matrix, M0(x) = M0 + mu D_g^T D_g (D_g the grid's rigid-body translations).

The changed model's rigid-body motions are those of the current model that do not move d
(:func:`structures.modal.rigid_body_modes` on the current assembly with the spring added: the
same motions, names and tolerance as the exact reanalysis); they are the first modes at 0 Hz.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp
import xarray as xr

from pipeline.diagnose.effects import DIRECTIONS
from pipeline.diagnose.mirror import sites
from structures.assembly import AssembledSystem, assemble
from structures.frames import rigid_offset
from structures.massprops import (MassProperties, mass_properties,
                                  properties_from_rigid_body_mass)
from structures.modal import (DEFAULT_SHIFT, exact_rigid_modes, rigid_body_modes, solve_eigen)
from structures.model import FEModel
from structures.sparse_factor import factorize

#: Residual attachment vectors whose M-Gram eigenvalue is below this share of the largest are
#: dependent on the others (a mirror pair's two springs acting on one a-set DOF) and left out.
INDEPENDENT = 1e-12
#: Modes kept in the Ritz basis, per analysis mode asked for (the residual attachment vector
#: comes on top). Measured on the frame (46 analysis modes, 12 springs, sizes 1e-3 .. 1, the 26
#: lowest modes against exact reanalysis): largest frequency error 1.9e-6 and 1 - MAC 1.5e-6 at
#: the sensors with 1 (one rung 0.23 ms), 7e-10 and 2.6e-12 with 2 (0.8 ms); the residual's
#: frequency scale is ~1e-2, so 1 suffices (tests/pipeline/diagnose/test_grounded.py: 1e-5).
MODE_FACTOR = 1
#: Sizes first sampled, as fractions of the upper bound: quarter decades over the top three
#: decades (below 1e-3 of the bound the spring's mode lies far below the first elastic one and
#: the modes change by first-order amounts).
SPRING_LADDER = tuple(10.0 ** (-np.arange(13)[::-1] / 4.0))
#: An interval of the ladder is halved while some elastic mode at its upper end keeps less than
#: this squared projection on the mode of the same order at its lower end (on its eigenvalue
#: cluster when degenerate; at a veering two modes exchange their shapes): between
#: two sizes the modes then turn by less than ~18 degrees (cos^2 = 0.9), so a valley of chi^2
#: where a pair of modes veers and mixes (a narrow one, a few percent of the size wide) is not
#: stepped over.
ROTATION_LIMIT = 0.9
#: Narrowest interval (factor between sizes): 1/128 decade.
FINEST_STEP = 10.0 ** (1.0 / 128.0)
#: Relative eigenvalue difference within which modes form one cluster (a degenerate pair's basis
#: is arbitrary: its turning is not a change of the modes).
CLUSTER = 1e-8


@dataclass(frozen=True)
class SpringBasis:
    """One configuration's current model, shared by every grounded-spring candidate.

    Attributes
    ----------
    model : FEModel, the current model.
    system : AssembledSystem of ``model``.
    lam : (m,) eigenvalues [(rad/s)^2], the rigid-body ones exactly 0.
    phi : (na, m) M-orthonormal modes (rigid-body modes first).
    factor : factorisation of K - sigma M (``solve``).
    shift : float, sigma [(rad/s)^2].
    sensor : (n_dof, na) sparse, basic-frame displacement of the measured DOFs per a-set DOF.
    props : MassProperties (a spring changes no mass).
    nmodes : int, analysis modes per rung.
    rigid : list of str, the current model's rigid-body motions
        (:func:`structures.modal.rigid_body_modes`).
    """

    model: FEModel
    system: AssembledSystem
    lam: np.ndarray
    phi: np.ndarray
    factor: object
    shift: float
    sensor: sp.csr_matrix
    props: MassProperties
    nmodes: int
    rigid: list = field(default_factory=list)


@dataclass(frozen=True)
class ReducedSpring:
    """A grounded-spring candidate on its Ritz basis (module docstring).

    Attributes
    ----------
    k0 : (m + q, m + q) Psi^T K Psi = diag(Lambda, R^T K R) (q = 1, or 2 for a mirror pair).
    w : (m + q, q) Psi^T E, E the springs' DOF columns.
    k_ref : float, spring stiffness per unit size.
    sensor : (n_dof, m + q) sensor displacements of the basis vectors.
    rigid : list of str, rigid-body motions of the changed model (size > 0).
    props : MassProperties
    nmodes : int
    template : xarray.Dataset, the modes Dataset :meth:`modes` fills in.
    solved : dict, size -> :meth:`solve` (the ladder asks for a size twice: to place the
        rungs and to evaluate them).
    """

    k0: np.ndarray
    w: np.ndarray
    k_ref: float
    sensor: np.ndarray
    rigid: list
    props: MassProperties
    nmodes: int
    template: xr.Dataset
    solved: dict = field(default_factory=dict, repr=False, compare=False)

    def solve(self, size: float) -> tuple[np.ndarray, np.ndarray]:
        """(lam (n,), y (m + q, n)): the ``nmodes`` lowest eigenpairs of (K_r(size), I), the
        rigid-body eigenvalues set to 0 (n = min(nmodes, m + q))."""
        if size not in self.solved:
            k_r = self.k0 + (size * self.k_ref) * (self.w @ self.w.T)
            lam, y = np.linalg.eigh(k_r)                                   # M_r = I
            n = min(self.nmodes, lam.size)
            lam, y = lam[:n], y[:, :n]
            lam[:min(len(self.rigid), n)] = 0.0
            self.solved[size] = (lam, y)
        return self.solved[size]

    def modes(self, size: float) -> tuple[xr.Dataset, np.ndarray]:
        """Modes at candidate size ``size`` (> 0).

        Returns
        -------
        modes : xarray.Dataset, ``frequency(mode)`` [Hz] with the ``rigid_motion(mode)``
            coordinate ("" for elastic modes), the rigid-body modes first at 0 Hz; ``nmodes``
            modes (at most m + q).
        sensor_shapes : (nmodes, n_dof) mass-normalised shapes at the measured DOFs.
        """
        lam, y = self.solve(size)
        freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
        return self.template.copy(data={"frequency": freq}), (self.sensor @ y).T

    def properties(self, size: float) -> MassProperties:
        """Mass properties at ``size`` (a spring changes none)."""
        return self.props


@dataclass(frozen=True)
class ReducedMass:
    """A ``lumped_mass`` candidate on the Ritz basis of a :class:`SpringBasis` (module
    docstring).

    Attributes
    ----------
    k0 : (m + q, m + q) Psi^T K Psi = diag(Lambda, R^T K R) (q = 3, or 6 for a mirror pair).
    u : (m + q, q) left singular vectors of W = Psi^T E, E the a-set columns of the grids'
        basic translations.
    s2 : (q,) the squared singular values of W.
    m_ref : float, mass per unit size (consistent units).
    sensor : (n_dof, m + q) sensor displacements of the basis vectors.
    n_rigid : int, rigid-body modes (the current model's).
    m0 : (6, 6) rigid-body mass matrix of the current model about ``props.reference_point``.
    unit : (6, 6) rigid-body mass matrix of the added point masses per unit mu.
    props : MassProperties of the current model.
    nmodes : int
    template : xarray.Dataset, the modes Dataset :meth:`modes` fills in.
    solved : dict, size -> (lam, z, M_r^-1/2).
    """

    k0: np.ndarray
    u: np.ndarray
    s2: np.ndarray
    m_ref: float
    sensor: np.ndarray
    n_rigid: int
    m0: np.ndarray
    unit: np.ndarray
    props: MassProperties
    nmodes: int
    template: xr.Dataset
    solved: dict = field(default_factory=dict, repr=False, compare=False)

    def _solve(self, size: float):
        if size not in self.solved:
            d = (1.0 + (size * self.m_ref) * self.s2) ** -0.5 - 1.0
            half = np.eye(self.k0.shape[0]) + (self.u * d) @ self.u.T       # M_r^-1/2
            a = half @ self.k0 @ half
            lam, z = np.linalg.eigh(0.5 * (a + a.T))
            n = min(self.nmodes, lam.size)
            lam, z = lam[:n], z[:, :n]
            lam[:min(self.n_rigid, n)] = 0.0
            self.solved[size] = (lam, z, half)
        return self.solved[size]

    def solve(self, size: float) -> tuple[np.ndarray, np.ndarray]:
        """(lam (n,), z (m + q, n)): the ``nmodes`` lowest eigenpairs of the standard form
        M_r^-1/2 K_r M_r^-1/2 z = lam z (z orthonormal, as :meth:`ReducedSpring.solve`'s y, for
        :func:`ladder_sizes`), the rigid-body eigenvalues set to 0."""
        lam, z, _ = self._solve(size)
        return lam, z

    def modes(self, size: float) -> tuple[xr.Dataset, np.ndarray]:
        """Modes at candidate size ``size``, as :meth:`ReducedSpring.modes` (mass-normalised in
        M(size): y = M_r^-1/2 z)."""
        lam, z, half = self._solve(size)
        y = half @ z
        freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
        return self.template.copy(data={"frequency": freq}), (self.sensor @ y).T

    def properties(self, size: float) -> MassProperties:
        """Mass properties with the added mass (module docstring)."""
        return properties_from_rigid_body_mass(
            self.m0 + (size * self.m_ref) * self.unit, self.props.reference_point,
            self.props.wtmass)


def spring_basis(model: FEModel, sensor_index, nmodes: int, *,
                 shift: float = DEFAULT_SHIFT) -> SpringBasis:
    """The current model's modes and factorisation shared by its grounded-spring candidates.

    Parameters
    ----------
    model : FEModel, the configuration's current model.
    sensor_index : (n_dof,) measured DOFs along the modes' ``dof`` (6 per grid, basic frame).
    nmodes : int, analysis modes per rung; the basis keeps :data:`MODE_FACTOR` x as many.
    shift : float, sigma [(rad/s)^2], negative (K - sigma M positive definite, free-free too).

    Returns
    -------
    SpringBasis

    Raises
    ------
    SolverError
        The model cannot be analysed (a mechanism), as :func:`structures.modal.compute_modes`.
    """
    system = assemble(model, warn=False)
    lam, phi = solve_eigen(system.K, system.M, MODE_FACTOR * nmodes, shift=shift,
                           groups=system.a_dofs // 6, filename=model.filename)
    phi_r, rigid = rigid_body_modes(model, system)
    lam, phi = exact_rigid_modes(system.M, lam, phi, phi_r)
    factor = factorize(system.K - shift * system.M, groups=system.a_dofs // 6,
                       filename=model.filename)
    sensor = (system.rotation @ system.T).tocsr()[np.asarray(sensor_index, int)]
    return SpringBasis(model=model, system=system, lam=lam, phi=phi, factor=factor, shift=shift,
                       sensor=sensor, props=mass_properties(model, m_basic=system.m_basic),
                       nmodes=nmodes, rigid=list(rigid))


def reduce_spring(basis: SpringBasis, candidate, smallest: float) -> ReducedSpring:
    """The ``boundary_stiffness`` candidate on the basis's Ritz basis.

    Parameters
    ----------
    basis : SpringBasis of the model the candidate is applied to.
    candidate : Candidate, ``boundary_stiffness``.
    smallest : float, the smallest size the ladder will ask for: the rigid-body motions are
        named with the spring at that size (a motion the spring holds with a force below
        :data:`structures.modal.RIGID_TOL` of the structure's stays rigid, as in the exact
        reanalysis).

    Returns
    -------
    ReducedSpring
    """
    model, system = basis.model, basis.system
    dofs = [6 * int(model.grids.index([site.location.grids[0]])[0])
            + DIRECTIONS.index(site.get("direction")) for site in sites(candidate)]
    e = np.asarray(system.T[dofs].toarray()).T                             # T^T 1_d, (na, q)
    return reduce_load(basis, e, float(candidate.get("k_ref")), smallest)


def _ritz(basis: SpringBasis, e) -> tuple[np.ndarray, np.ndarray]:
    """(Psi (na, m + q), K_r (m + q, m + q)): the basis's modes and the M-orthonormal residual
    attachment vectors of the loads ``e`` (na, q') (Weissenburger 1968: the static response
    minus the kept modes'; dependent ones left out, :data:`INDEPENDENT`), and
    Psi^T K Psi = diag(Lambda, R^T K R)."""
    system, phi, lam = basis.system, basis.phi, basis.lam
    r = np.asarray(basis.factor.solve(e)).reshape(e.shape) \
        - phi @ ((phi.T @ e) / (lam - basis.shift)[:, None])
    for _ in range(2):                                                     # round-off
        r = r - phi @ (phi.T @ (system.M @ r))
    gram = r.T @ (system.M @ r)                                            # (q, q)
    g_val, g_vec = np.linalg.eigh(gram)
    keep = g_val > INDEPENDENT * max(float(g_val.max(initial=0.0)), 0.0)
    q = r @ (g_vec[:, keep] / np.sqrt(g_val[keep]))                        # M-orthonormal
    psi = np.column_stack([phi, q])
    k0 = np.zeros((psi.shape[1], psi.shape[1]))
    k0[np.diag_indices(lam.size)] = lam
    k0[lam.size:, lam.size:] = q.T @ (system.K @ q)
    return psi, k0


def _template(nmodes: int, rigid) -> xr.Dataset:
    names = (list(rigid) + [""] * nmodes)[:nmodes]
    return xr.Dataset({"frequency": ("mode", np.zeros(nmodes), {"units": "Hz"})},
                      coords={"rigid_motion": ("mode", np.array(names, dtype=str))})


def reduce_mass(basis: SpringBasis, candidate) -> ReducedMass:
    """The ``lumped_mass`` candidate (one grid, or a mirror pair's two; a spread mass's grids
    with their equal shares) on the basis's Ritz basis.

    Parameters
    ----------
    basis : SpringBasis of the model the candidate is applied to.
    candidate : Candidate, ``lumped_mass``.

    Returns
    -------
    ReducedMass
    """
    model, system = basis.model, basis.system
    basic = (system.rotation @ system.T).tocsr()                           # (n_g, na)
    rows = model.grids.index([g for site in sites(candidate) for g in site.location.grids])
    share = np.array([1.0 / len(site.location.grids) for site in sites(candidate)
                      for _ in site.location.grids])                      # a spread's shares
    e = np.column_stack([np.sqrt(w) * np.asarray(basic[6 * int(g) + c].toarray()).ravel()
                         for g, w in zip(rows, share) for c in range(3)])  # (na, 3 q)
    psi, k0 = _ritz(basis, e)
    props = basis.props
    d = rigid_offset(model.grids.xyz[rows] - props.reference_point)[:, :3, :]   # (q, 3, 6)
    unit = np.einsum("g,gai,gaj->ij", share, d, d)
    rigid = basis.rigid
    n = min(basis.nmodes, psi.shape[1])
    u, s, _ = np.linalg.svd(psi.T @ e, full_matrices=False)
    return ReducedMass(k0=k0, u=u, s2=s ** 2, m_ref=float(candidate.get("total_mass"))
                       * model.wtmass, sensor=np.asarray(basis.sensor @ psi),
                       n_rigid=len(rigid), m0=props.rigid_body_mass, unit=unit, props=props,
                       nmodes=basis.nmodes, template=_template(n, rigid))


def reduce_load(basis: SpringBasis, e, k_ref: float, smallest: float, *,
                rigid: list | None = None) -> ReducedSpring:
    """Springs K(k) = K + k k_ref E E^T of load vectors ``e`` on the basis's Ritz basis.

    Parameters
    ----------
    basis : SpringBasis
    e : (na, q) a-set load vectors (a grounded spring's T^T 1_d; a spring between two grids,
        :mod:`pipeline.diagnose.loadpath`, the difference of their displacements along it).
    k_ref : float, stiffness per unit size.
    smallest : float, as :func:`reduce_spring`.
    rigid : list of str, optional, the rigid-body motions of the changed model when they are
        known (a spring between two grids along the line joining them holds none: the current
        model's); else named as :func:`reduce_spring` says.

    Returns
    -------
    ReducedSpring
    """
    model, system = basis.model, basis.system
    psi, k0 = _ritz(basis, e)
    if rigid is None:
        load = sp.csc_matrix(e)
        held = (system.K + (smallest * k_ref) * (load @ load.T)).tocsc()
        _, rigid = rigid_body_modes(model, replace(system, K=held))
    n = min(basis.nmodes, psi.shape[1])
    return ReducedSpring(k0=k0, w=psi.T @ e, k_ref=float(k_ref),
                         sensor=np.asarray(basis.sensor @ psi), rigid=list(rigid),
                         props=basis.props, nmodes=basis.nmodes, template=_template(n, rigid))


def _turned(a, b) -> bool:
    """True when some elastic mode j of solution ``b`` keeps less than :data:`ROTATION_LIMIT`
    of its norm on mode j of solution ``a`` (on its eigenvalue cluster when degenerate); each
    solution is (lam (n,), y (m + q, n)), lam ascending. At a veering the modes exchange their
    shapes (the order of the eigenvalues stays): mode j then turns towards mode j +- 1."""
    (lam_a, y_a), (lam_b, y_b) = a, b
    overlap = (y_a.T @ y_b) ** 2                                           # (n, n)
    gap = np.diff(lam_a) > CLUSTER * np.maximum(np.abs(lam_a[1:]), np.finfo(float).tiny)
    label = np.concatenate([[0], np.cumsum(gap)])
    kept = (overlap * (label[:, None] == label[None, :])).sum(axis=0)
    return bool(np.any(kept[lam_b > 0] < ROTATION_LIMIT))


def ladder_sizes(reduced, upper: float, ladder=SPRING_LADDER) -> np.ndarray:
    """Sizes at which a grounded-spring candidate is analysed.

    ``ladder`` (:data:`SPRING_LADDER`) times ``upper``, every interval halved (geometric mean) while the
    modes of some configuration turn across it (:data:`ROTATION_LIMIT`), down to
    :data:`FINEST_STEP`. Costs eigen-solutions of size m + q only.

    Parameters
    ----------
    reduced : sequence of ReducedSpring, one per configuration.
    upper : float, the parameter's upper bound.
    ladder : ascending fractions of ``upper``.

    Returns
    -------
    (n_sizes,) ascending sizes.
    """
    def solved(size):
        return [r.solve(size) for r in reduced]

    sizes = list(upper * np.asarray(ladder))
    out = [sizes[0]]
    previous = solved(sizes[0])
    for size in sizes[1:]:
        stack = [(size, solved(size))]
        while stack:
            b, at_b = stack[-1]
            a = out[-1]
            if b / a > FINEST_STEP and any(_turned(p, q) for p, q in zip(previous, at_b)):
                mid = float(np.sqrt(a * b))
                stack.append((mid, solved(mid)))
                continue
            out.append(b)
            previous = at_b
            stack.pop()
    return np.array(out)
