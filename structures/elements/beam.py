"""Two-node beam and rod elements (CBAR/CBEAM, CROD): stiffness and mass in the basic frame.

Beam: Euler-Bernoulli bending with optional transverse-shear flexibility (Timoshenko factor
phi = 12 E I / (K A G L^2), Przemieniecki, *Theory of Matrix Structural Analysis*, 1968, sec. 5.6),
axial and St-Venant torsion; rigid end offsets; pin flags by static condensation; a product of
inertia I12 handled by rotating to the section's principal axes. Nastran's conventions: I1 bends in
element plane 1 (x-y, displacement v), I2 in plane 2 (x-z, displacement w), K1/K2 blank = no shear
flexibility.

Mass: lumped (Nastran's default, half of (rho A + NSM) L translational at each end) or coupled
(PARAM COUPMASS: cubic-Hermite consistent translational mass, linear axial, and for CBEAM the
torsional inertia rho (I1 + I2) L of the section, which Nastran's CBAR omits; Przemieniecki
sec. 11.3).

Element DOF order: [u1 v1 w1 tx1 ty1 tz1 u2 v2 w2 tx2 ty2 tz2].
"""
from __future__ import annotations

import numpy as np

from structures.frames import rigid_offset


def beam_axes(p_a, p_b, v):
    """Element axes and lengths.

    Parameters
    ----------
    p_a, p_b : (ne, 3) end points (after offsets), basic.
    v : (ne, 3) orientation vector, basic.

    Returns
    -------
    axes : (ne, 3, 3) rows are the element x, y, z unit vectors in basic.
    length : (ne,)
    """
    d = np.asarray(p_b, float) - np.asarray(p_a, float)
    length = np.linalg.norm(d, axis=1)
    x = d / length[:, None]
    v = np.asarray(v, float)
    y = v - np.einsum("ij,ij->i", v, x)[:, None] * x
    y /= np.linalg.norm(y, axis=1)[:, None]
    z = np.cross(x, y)
    return np.stack([x, y, z], axis=1), length


def _principal(i1, i2, i12):
    """Principal values and rotation angle alpha of the section's bending inertia."""
    alpha = 0.5 * np.arctan2(2.0 * i12, i1 - i2)
    c, s = np.cos(alpha), np.sin(alpha)
    i1p = i1 * c * c + i2 * s * s + 2.0 * i12 * s * c
    i2p = i1 * s * s + i2 * c * c - 2.0 * i12 * s * c
    return i1p, i2p, alpha


def beam_local_stiffness(length, e, g, area, i1, i2, j, k1=None, k2=None):
    """Local 12x12 stiffness of uniform beams.

    Parameters
    ----------
    length, e, g, area, i1, i2, j : (ne,) arrays.
    k1, k2 : (ne,) shear-area factors or None (no shear flexibility); NaN entries mean none.

    Returns
    -------
    (ne, 12, 12)
    """
    L = np.asarray(length, float)
    ne = len(L)
    k = np.zeros((ne, 12, 12))

    def phi(factor, inertia):
        if factor is None:
            return np.zeros(ne)
        f = np.asarray(factor, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            out = 12.0 * e * inertia / (f * area * g * L ** 2)
        return np.where(np.isfinite(out) & (f > 0), out, 0.0)

    ea = e * area / L
    gj = g * j / L
    for (a, b), val in (((0, 0), ea), ((6, 6), ea), ((0, 6), -ea), ((6, 0), -ea),
                        ((3, 3), gj), ((9, 9), gj), ((3, 9), -gj), ((9, 3), -gj)):
        k[:, a, b] = val
    for idx, inertia, factor, sign in (([1, 5, 7, 11], i1, k1, 1.0), ([2, 4, 8, 10], i2, k2, -1.0)):
        ph = phi(factor, inertia)
        c = e * inertia / ((1.0 + ph) * L ** 3)
        sL = sign * L
        blk = np.stack([
            np.stack([12 + 0 * L, 6 * sL, -12 + 0 * L, 6 * sL], -1),
            np.stack([6 * sL, (4 + ph) * L ** 2, -6 * sL, (2 - ph) * L ** 2], -1),
            np.stack([-12 + 0 * L, -6 * sL, 12 + 0 * L, -6 * sL], -1),
            np.stack([6 * sL, (2 - ph) * L ** 2, -6 * sL, (4 + ph) * L ** 2], -1)], 1)
        k[:, np.ix_(idx, idx)[0], np.ix_(idx, idx)[1]] = c[:, None, None] * blk
    return k


def beam_local_mass(length, mass_per_length, polar_inertia_per_length, lumped):
    """Local 12x12 mass: lumped translational, or coupled (consistent) with torsional inertia.

    Parameters
    ----------
    length, mass_per_length, polar_inertia_per_length : (ne,)
    lumped : bool

    Returns
    -------
    (ne, 12, 12)
    """
    L = np.asarray(length, float)
    m = mass_per_length * L
    ne = len(L)
    out = np.zeros((ne, 12, 12))
    if lumped:
        for i in (0, 1, 2, 6, 7, 8):
            out[:, i, i] = 0.5 * m
        return out
    for a, b in ((0, 6), (3, 9)):
        scale = m if a == 0 else polar_inertia_per_length * L
        out[:, a, a] = out[:, b, b] = scale / 3.0
        out[:, a, b] = out[:, b, a] = scale / 6.0
    for idx, sign in (([1, 5, 7, 11], 1.0), ([2, 4, 8, 10], -1.0)):
        sL = sign * L
        blk = np.stack([
            np.stack([156 + 0 * L, 22 * sL, 54 + 0 * L, -13 * sL], -1),
            np.stack([22 * sL, 4 * L ** 2, 13 * sL, -3 * L ** 2], -1),
            np.stack([54 + 0 * L, 13 * sL, 156 + 0 * L, -22 * sL], -1),
            np.stack([-13 * sL, -3 * L ** 2, -22 * sL, 4 * L ** 2], -1)], 1)
        out[:, np.ix_(idx, idx)[0], np.ix_(idx, idx)[1]] = (m / 420.0)[:, None, None] * blk
    return out


def condense_pins(k, m, pins):
    """Condense released end DOFs (pin flags) out of local stiffness and mass matrices.

    The released DOFs follow the kept ones statically, u_r = -K_rr^-1 K_rk u_k, so with
    T = [I; -K_rr^-1 K_rk] the element matrices become T^T K T (exact static condensation) and
    T^T M T (the mass consistent with that motion: a released translation's lumped mass moves
    to the DOFs it follows, e.g. end A's axial mass to end B's with PA = 1; released rotations
    leave lumped translational mass unchanged).

    Parameters
    ----------
    k, m : (ne, 12, 12) local stiffness and mass in element axes (not modified).
    pins : (ne,) int bit masks; bits 0-5 release end-A components 1-6, bits 6-11 end-B.

    Returns
    -------
    k_c, m_c : (ne, 12, 12) with zero rows/columns on the released DOFs.
    """
    k_out = np.array(k, copy=True)
    m_out = np.array(m, copy=True)
    for e in np.flatnonzero(pins):
        rel = [i for i in range(12) if pins[e] >> i & 1]
        keep = [i for i in range(12) if i not in rel]
        t = np.zeros((12, len(keep)))
        t[keep, np.arange(len(keep))] = 1.0
        t[rel, :] = -np.linalg.solve(k[e][np.ix_(rel, rel)], k[e][np.ix_(rel, keep)])
        k_out[e] = 0.0
        m_out[e] = 0.0
        k_out[e][np.ix_(keep, keep)] = t.T @ k[e] @ t
        m_out[e][np.ix_(keep, keep)] = t.T @ m[e] @ t
    return k_out, m_out


def to_grids(local, axes, offset_a, offset_b):
    """Transform local 12x12 matrices to basic axes at the grids (through rigid end offsets).

    Parameters
    ----------
    local : (ne, 12, 12)
    axes : (ne, 3, 3) rows = element axes in basic.
    offset_a, offset_b : (ne, 3) basic offset vectors from grid A / B to the element ends.

    Returns
    -------
    (ne, 12, 12) in basic axes at the grids.
    """
    ne = len(local)
    t = np.zeros((ne, 12, 12))
    for blk in range(4):
        t[:, 3 * blk:3 * blk + 3, 3 * blk:3 * blk + 3] = axes
    off = np.zeros((ne, 12, 12))
    off[:, :6, :6] = rigid_offset(offset_a)
    off[:, 6:, 6:] = rigid_offset(offset_b)
    tt = t @ off
    return np.swapaxes(tt, 1, 2) @ local @ tt


def beam_matrices(x_a, x_b, v, offset_a, offset_b, e, g, area, i1, i2, i12, j, nsm, rho,
                  k1=None, k2=None, pins=None, lumped=True, torsional_inertia=True):
    """Stiffness and mass of CBAR/CBEAM elements in basic axes at their grids.

    Parameters
    ----------
    x_a, x_b : (ne, 3) grid positions (basic).
    v : (ne, 3) orientation vectors (basic).
    offset_a, offset_b : (ne, 3) end offsets (basic).
    e, g, area, i1, i2, i12, j, nsm, rho : (ne,) section and material values.
    k1, k2 : (ne,) shear factors, or None for no shear flexibility.
    pins : (ne,) int bit masks (see :func:`condense_pins`), or None.
    lumped : bool, lumped (Nastran default) or coupled mass.
    torsional_inertia : bool, include rho (I1 + I2) in the coupled mass (CBEAM); Nastran's CBAR
        coupled mass omits it.

    Returns
    -------
    K, M : (ne, 12, 12)
    """
    p_a = np.asarray(x_a, float) + offset_a
    p_b = np.asarray(x_b, float) + offset_b
    axes, length = beam_axes(p_a, p_b, v)
    i12 = np.asarray(i12, float)
    i1p, i2p, alpha = _principal(np.asarray(i1, float), np.asarray(i2, float), i12)
    c, s = np.cos(alpha), np.sin(alpha)
    y, z = axes[:, 1], axes[:, 2]
    principal_axes = np.stack([axes[:, 0], c[:, None] * y + s[:, None] * z,
                               -s[:, None] * y + c[:, None] * z], axis=1)
    k_local = beam_local_stiffness(length, e, g, area, i1p, i2p, j, k1, k2)
    polar = rho * (np.asarray(i1) + np.asarray(i2)) if torsional_inertia else np.zeros(len(length))
    # The consistent mass is the same in element and principal axes (equal bending blocks).
    m_local = beam_local_mass(length, rho * area + nsm, polar, lumped)
    if pins is not None and np.any(pins):
        # Pin flags are given in the element (not principal) axes: condense there.
        rot = np.zeros((len(length), 12, 12))
        r = np.einsum("eij,ekj->eik", principal_axes, axes)
        for blk in range(4):
            rot[:, 3 * blk:3 * blk + 3, 3 * blk:3 * blk + 3] = r
        k_elem = np.swapaxes(rot, 1, 2) @ k_local @ rot
        k_local, m_local = condense_pins(k_elem, m_local, np.asarray(pins))
        principal_axes = axes
    k = to_grids(k_local, principal_axes, offset_a, offset_b)
    # Lumped mass without pin flags is m I on the translations at each end, the same in every
    # axes: rotating it would only add round-off couplings (1e-33 of the diagonal) that make M
    # look non-diagonal to the eigensolver (structures.modal's lumped path). Condensed pins can
    # move a translation's mass (condense_pins): then it is rotated like the stiffness.
    isotropic = lumped and (pins is None or not np.any(pins))
    mass_axes = np.broadcast_to(np.eye(3), principal_axes.shape) if isotropic else principal_axes
    m = to_grids(m_local, mass_axes, offset_a, offset_b)
    return k, m


def rod_matrices(x_a, x_b, e, g, area, j, nsm, rho, lumped=True):
    """Stiffness and mass of CROD elements (axial + torsion) in basic axes at their grids.

    Parameters
    ----------
    x_a, x_b : (ne, 3) grid positions; e, g, area, j, nsm, rho : (ne,).
    lumped : bool

    Returns
    -------
    K, M : (ne, 12, 12)
    """
    d = np.asarray(x_b, float) - np.asarray(x_a, float)
    length = np.linalg.norm(d, axis=1)
    x = d / length[:, None]
    ne = len(length)
    outer = np.einsum("ei,ej->eij", x, x)
    k = np.zeros((ne, 12, 12))
    ka = (e * area / length)[:, None, None] * outer
    kt = (g * j / length)[:, None, None] * outer
    for (a, b), sign in (((0, 0), 1), ((6, 6), 1), ((0, 6), -1), ((6, 0), -1)):
        k[:, a:a + 3, b:b + 3] = sign * ka
        k[:, a + 3:a + 6, b + 3:b + 6] = sign * kt
    m_tot = (rho * area + nsm) * length
    m = np.zeros((ne, 12, 12))
    eye = np.eye(3)
    if lumped:
        m[:, 0:3, 0:3] = m[:, 6:9, 6:9] = 0.5 * m_tot[:, None, None] * eye
    else:
        m[:, 0:3, 0:3] = m[:, 6:9, 6:9] = (m_tot / 3.0)[:, None, None] * eye
        m[:, 0:3, 6:9] = m[:, 6:9, 0:3] = (m_tot / 6.0)[:, None, None] * eye
    return k, m
