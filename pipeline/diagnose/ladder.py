"""Reanalysis of a joint over its ladder of compliances on one Craig-Bampton basis.

A ``joint_flexibility`` candidate at compliance c (and rotation 0, the ladder's: the refit frees
the rotation) hangs the joint's grids on CBUSHes of stiffness k_ref / c
(:mod:`pipeline.diagnose.joints`). The changed model's a-set, constraint map T and mass
M do not depend on c, and its stiffness is linear in 1 / c:

    K(c) = K_0 + B / c,

B the springs at k_ref (from two assemblies, c = 1 and 2: B = 2 (K(1) - K(2)), K_0 = K(1) - B),
nonzero only on the nb DOFs of the springs' grids (the boundary b; the rest is the interior i).
A joint with one compliance c_p per CBUSH component (:func:`pipeline.diagnose.effects.directional`)
is K(c) = K_0 + sum_p B_p / c_p alike, B_p from the assembly at every c_p = 1 and one per
component with its c_p = 2 (seven in all).
K_ii, K_ib and M do not depend on c, so one Craig-Bampton basis (Craig & Bampton 1968, AIAA J.
6(7), the fixed-interface modes and the constraint modes)

    Psi = [[Phi_i, -K_ii^-1 K_ib], [0, I_bb]]         (rows i, b)

serves every rung: K_r(c) = Psi^T K_0 Psi + sum_p Psi^T B_p Psi / c_p, M_r = Psi^T M Psi, and
the modes of the rung are those of (K_r(c), M_r), of size nf + nb. The constraint modes hold the
static response of the boundary exactly, so the rigid-body motions, the rigid joint (c -> 0) and the
free hung part (c -> infinity) are in the basis; the truncation to the nf lowest fixed-interface
modes (:data:`FIXED_INTERFACE_FACTOR` x the modes asked for) is the only approximation. The
screening takes the best rung from this basis and analyses that size again exactly
(:func:`pipeline.diagnose.screen.signatures`).

Used where the exact reanalysis is a dense eigen-solution of the whole a-set
(na <= :data:`structures.modal.DENSE_LIMIT`: n^3 work and one assembly per rung, against one
factorisation and one truncated eigen-solution per joint here); larger models keep the exact
ladder.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import xarray as xr

from structures.assembly import assemble
from structures.common.errors import SolverError
from structures.massprops import mass_properties
from structures.modal import DEFAULT_SHIFT, DENSE_LIMIT, rigid_body_modes, solve_eigen
from structures.model import FEModel
from structures.sparse_factor import factorize

#: Fixed-interface modes kept, per analysis mode asked for. Measured on the X-56A-class model
#: (8 joints, compliances 1 to 1e5, both configurations, the 24 lowest elastic modes): largest
#: frequency error 3.3e-6 with 3, 2.5e-5 with 2 (chi^2 off by 0.2 of 1937);
#: tests/pipeline/diagnose/test_screen.py holds the frame's joints to 1e-5.
FIXED_INTERFACE_FACTOR = 3
#: Compliances of the two assemblies that separate K_0 and B.
_C1, _C2 = 1.0, 2.0


@dataclass(frozen=True)
class ReducedJoint:
    """A joint's changed model on its Craig-Bampton basis (module docstring).

    Attributes
    ----------
    k0, m : (nr, nr) Psi^T K_0 Psi, Psi^T M Psi.
    b : (n_parts, nr, nr) Psi^T B_p Psi, one per compliance parameter (1, or 6 for a
        directional joint).
    sensor : (n_dof, nr) basic-frame displacement of the measured DOFs per basis vector.
    rigid : list of str, the rigid-body motions of the changed model (they come first).
    props : MassProperties of the changed model (M does not depend on c).
    nmodes : int, analysis modes per rung.
    """

    k0: np.ndarray
    b: np.ndarray
    m: np.ndarray
    sensor: np.ndarray
    rigid: list
    props: object
    nmodes: int

    def properties(self, compliance: float):
        """Mass properties (the same at every compliance)."""
        return self.props

    def modes(self, compliance) -> tuple[xr.Dataset, np.ndarray]:
        """Modes of the rung at ``compliance`` (> 0; a float, or (n_parts,) one per part).

        Returns
        -------
        modes : xarray.Dataset, ``frequency(mode)`` [Hz] with the ``rigid_motion(mode)``
            coordinate ("" for elastic modes), the rigid-body modes first at 0 Hz.
        sensor_shapes : (nmodes, n_dof) mass-normalised shapes at the measured DOFs.
        """
        c = np.broadcast_to(np.asarray(compliance, float), len(self.b))
        k = self.k0 + np.tensordot(1.0 / c, self.b, axes=1)                 # K_r(c)
        lam, y = solve_eigen(sp.csc_matrix(k), sp.csc_matrix(self.m), self.nmodes,
                             shift=DEFAULT_SHIFT)
        nr = len(self.rigid)
        lam[:nr] = 0.0
        freq = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
        names = (self.rigid + [""] * len(lam))[:len(lam)]
        ds = xr.Dataset({"frequency": ("mode", freq, {"units": "Hz"})},
                        coords={"rigid_motion": ("mode", np.array(names, dtype=str))})
        return ds, (self.sensor @ y).T


def reduce_joint(model: FEModel, candidate, sensor_index, nmodes: int, *,
                 any_size: bool = False, dense_limit: int = DENSE_LIMIT) -> ReducedJoint | None:
    """The joint candidate's changed model on its Craig-Bampton basis.

    Parameters
    ----------
    model : FEModel, the configuration's current model.
    candidate : Candidate, ``joint_flexibility`` (compliance and rotation, the rotation held
        at 0; or directional, :data:`pipeline.diagnose.effects.JOINT_DIRECTIONS`).
    sensor_index : (n_dof,) measured DOFs along the modes' ``dof`` (6 per grid, basic frame).
    nmodes : int, analysis modes per rung.
    any_size : bool, reduce an a-set above ``dense_limit`` too, through sparse matrices
        (:func:`structures.sparse_factor.factorize` for K_ii, :func:`structures.modal.solve_eigen`
        for the fixed-interface modes); else None there.
    dense_limit : int, the largest a-set reduced with dense matrices.

    Returns
    -------
    ReducedJoint, or None where the basis does not apply: an a-set above ``dense_limit``
    without ``any_size``, an a-set that changes with the compliance (automatic SPCs), an
    interior that is not stiff once the boundary is clamped (a mechanism inside), or no
    fixed-interface mode to keep (``nmodes`` 0, or every DOF on the springs).
    """
    from pipeline.diagnose.apply import apply_effect
    from pipeline.diagnose.effects import JOINT_DIRECTIONS

    if candidate.parameters == JOINT_DIRECTIONS:
        base = np.full(len(JOINT_DIRECTIONS), _C1)
        raised = [np.where(np.arange(base.size) == p, _C2, _C1) for p in range(base.size)]
    else:
        base = np.r_[_C1, np.zeros(len(candidate.parameters) - 1)]       # rotation 0
        raised = [np.r_[_C2, base[1:]]]
    changed = apply_effect(model, candidate, base)
    s1 = assemble(changed, warn=False)
    dense = s1.K.shape[0] <= dense_limit
    if not dense and not any_size:
        return None

    def matrix(a):
        return a.toarray() if dense else sp.csr_matrix(a)

    k1 = matrix(s1.K)
    parts = []
    for x in raised:
        s2 = assemble(apply_effect(model, candidate, x), warn=False)
        if not np.array_equal(s1.a_dofs, s2.a_dofs):
            return None
        parts.append((k1 - matrix(s2.K)) / (1.0 / _C1 - 1.0 / _C2))       # B_p
    springs = sum(parts[1:], parts[0])                                     # B
    k0 = k1 - springs / _C1                                                # K_0
    # Off the springs' DOFs K(1) and K(2) are the same sums of the same numbers, so B is exactly
    # 0 there; on them its rows are k_ref-sized (smallest row 1.6e-3 of max|B| over the X-56A-
    # class and frame joints). The cut lies far below that and far above the round-off an entry
    # of B = 2 (K(1) - K(2)) can carry, eps max|K(1)| (6e-15 of max|B| on the X-56A-class
    # model); a round-off row taken into b would only enlarge the exact part of the basis.
    rows = abs(springs).max(axis=1)
    rows = np.asarray(rows.todense() if sp.issparse(rows) else rows).ravel()
    bound = np.flatnonzero(rows > 1e-12 * rows.max())
    inner = np.setdiff1d(np.arange(k0.shape[0]), bound)
    n_i, nb = inner.size, bound.size
    nf = min(n_i, FIXED_INTERFACE_FACTOR * nmodes)
    if nf < 1:
        return None
    m = matrix(s1.M)
    psi = np.zeros((k0.shape[0], nf + nb))
    psi[bound, nf:] = np.eye(nb)
    k_ii, k_ib, m_ii = k0[inner][:, inner], k0[inner][:, bound], m[inner][:, inner]
    if dense:
        try:
            factor = sla.cho_factor(k_ii)
        except np.linalg.LinAlgError:
            return None
        # fixed-interface modes as the largest 1 / lambda of (M_ii, K_ii): K_ii is positive
        # definite once the boundary is clamped, M_ii may be singular (massless rotations)
        _, psi[inner, :nf] = sla.eigh(m_ii, k_ii, subset_by_index=[n_i - nf, n_i - 1])
        psi[inner, nf:] = -sla.cho_solve(factor, k_ib)                    # constraint modes
    else:
        try:
            factor = factorize(k_ii, groups=s1.a_dofs[inner] // 6)
            _, psi[inner, :nf] = solve_eigen(k_ii, m_ii, nf, groups=s1.a_dofs[inner] // 6)
        except SolverError:
            return None
        psi[inner, nf:] = -factor.solve(k_ib.toarray())
    rotate = (s1.rotation @ (s1.T @ psi))                                   # (n_g, nr) basic
    _, rigid = rigid_body_modes(changed, s1)
    return ReducedJoint(k0=psi.T @ (k0 @ psi), b=np.stack([psi.T @ (b @ psi) for b in parts]),
                        m=psi.T @ (m @ psi),
                        sensor=np.asarray(rotate)[np.asarray(sensor_index)], rigid=list(rigid),
                        props=mass_properties(changed, m_basic=s1.m_basic), nmodes=nmodes)
