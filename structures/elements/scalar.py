"""Springs and lumped masses: CELAS1/2, CMASS2, CBUSH and CONM2 in basic axes at their grids.

Scalar elements act on a component of a grid's displacement frame; they are returned here as
12x12 matrices on the two grids' basic-frame DOFs (using the frame's direction vector), so that
assembly treats every element alike.
"""
from __future__ import annotations

import numpy as np

from structures.frames import rigid_offset


def scalar_pair_matrices(value, dir_1, dir_2):
    """12x12 matrices of scalar springs/masses between two grid components.

    Parameters
    ----------
    value : (ne,) spring stiffness or mass.
    dir_1, dir_2 : (ne, 6) selection vectors of the components on grids 1 and 2 in basic DOFs
        (a unit direction in the translational or rotational half; zeros for a grounded end).

    Returns
    -------
    (ne, 12, 12): value * b b^T with b = [dir_1, -dir_2].
    """
    b = np.concatenate([np.asarray(dir_1, float), -np.asarray(dir_2, float)], axis=1)
    return np.asarray(value, float)[:, None, None] * np.einsum("ei,ej->eij", b, b)


def component_direction(cd_axes, component):
    """Basic-frame selection 6-vectors for components 1..6 of displacement frames.

    Parameters
    ----------
    cd_axes : (ne, 3, 3) displacement axes (columns in basic).
    component : (ne,) int 1..6, or 0 for none (zero vector).

    Returns
    -------
    (ne, 6)
    """
    comp = np.asarray(component, int)
    out = np.zeros((len(comp), 6))
    for e, c in enumerate(comp):
        if c == 0:
            continue
        half = 0 if c <= 3 else 3
        out[e, half:half + 3] = cd_axes[e][:, (c - 1) % 3]
    return out


def bush_matrices(x_a, x_b, axes, k_diag, s):
    """CBUSH stiffness between grids A and B (or to ground when ``x_b`` rows are NaN).

    Parameters
    ----------
    x_a, x_b : (ne, 3) grid positions, basic; NaN rows in ``x_b`` mean grounded.
    axes : (ne, 3, 3) rows = element axes in basic.
    k_diag : (ne, 6) K1..K6 in the element axes.
    s : (ne,) location of the spring between A (0) and B (1).

    Returns
    -------
    (ne, 12, 12) in basic axes at the grids (zero rows/columns for B when grounded).
    """
    x_a = np.asarray(x_a, float)
    x_b = np.asarray(x_b, float)
    grounded = np.isnan(x_b).any(axis=1)
    x_b_eff = np.where(grounded[:, None], x_a, x_b)
    point = x_a + np.asarray(s, float)[:, None] * (x_b_eff - x_a)
    ne = len(x_a)
    q = np.zeros((ne, 6, 6))
    q[:, :3, :3] = axes
    q[:, 3:, 3:] = axes
    b = np.zeros((ne, 6, 12))
    b[:, :, :6] = -q @ rigid_offset(point - x_a)
    b[:, :, 6:] = np.where(grounded[:, None, None], 0.0, q @ rigid_offset(point - x_b_eff))
    kd = np.zeros((ne, 6, 6))
    kd[:, range(6), range(6)] = k_diag
    return np.einsum("eji,ejk,ekl->eil", b, kd, b)


def conm2_matrices(mass, offset, inertia):
    """6x6 mass matrices of CONM2s about their grids, basic axes.

    Parameters
    ----------
    mass : (nm,)
    offset : (nm, 3) vector from grid to centre of mass, basic.
    inertia : (nm, 3, 3) inertia tensor about the centre of mass, basic.

    Returns
    -------
    (nm, 6, 6)
    """
    nm = len(mass)
    local = np.zeros((nm, 6, 6))
    local[:, :3, :3] = np.asarray(mass, float)[:, None, None] * np.eye(3)
    local[:, 3:, 3:] = inertia
    t = rigid_offset(offset)
    return np.einsum("eji,ejk,ekl->eil", t, local, t)
