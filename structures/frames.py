"""Coordinate frames: displacement axes of rectangular, cylindrical and spherical systems.

A frame's axes are returned as a (3, 3) matrix whose columns are the unit vectors in basic, so that
``u_basic = axes @ u_local``. For cylindrical (r, theta, z) and spherical (r, theta, phi) systems
the axes depend on the point, as in Nastran.
"""
from __future__ import annotations

import numpy as np


def displacement_axes(kind: str, origin, beta, points) -> np.ndarray:
    """Local displacement axes at ``points`` for a coordinate system.

    Parameters
    ----------
    kind : {'R', 'C', 'S'}
        Rectangular, cylindrical or spherical.
    origin : (3,) basic position of the system's origin.
    beta : (3, 3) rows are the system's i, j, k unit vectors in basic (pyNastran's ``beta()``).
    points : (n, 3) basic positions.

    Returns
    -------
    (n, 3, 3) axes, columns in basic.
    """
    beta = np.asarray(beta, float)
    pts = np.atleast_2d(np.asarray(points, float))
    n = len(pts)
    if kind == "R":
        return np.broadcast_to(beta.T, (n, 3, 3)).copy()
    local = (pts - np.asarray(origin, float)) @ beta.T
    i, j, k = beta
    if kind == "C":
        th = np.arctan2(local[:, 1], local[:, 0])
        c, s = np.cos(th)[:, None], np.sin(th)[:, None]
        e_r = c * i + s * j
        e_t = -s * i + c * j
        e_z = np.broadcast_to(k, (n, 3))
        return np.stack([e_r, e_t, e_z], axis=-1)
    if kind == "S":
        r_xy = np.hypot(local[:, 0], local[:, 1])
        th = np.arctan2(r_xy, local[:, 2])
        ph = np.arctan2(local[:, 1], local[:, 0])
        st, ct = np.sin(th)[:, None], np.cos(th)[:, None]
        sp, cp = np.sin(ph)[:, None], np.cos(ph)[:, None]
        e_r = st * cp * i + st * sp * j + ct * k
        e_t = ct * cp * i + ct * sp * j - st * k
        e_p = -sp * i + cp * j
        return np.stack([e_r, e_t, e_p], axis=-1)
    raise ValueError(f"unknown coordinate system type {kind!r}; valid: 'R', 'C', 'S'")


def skew(v) -> np.ndarray:
    """Cross-product matrices: ``skew(a) @ b == np.cross(a, b)``; v (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v, float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def rigid_offset(r) -> np.ndarray:
    """6x6 transformations from a grid's motion to the motion of a point offset by ``r``.

    ``u_point = u_grid + theta x r``: r (..., 3) -> (..., 6, 6), basic axes.
    """
    r = np.asarray(r, float)
    out = np.zeros(r.shape[:-1] + (6, 6))
    eye = np.eye(3)
    out[..., :3, :3] = eye
    out[..., 3:, 3:] = eye
    out[..., :3, 3:] = -skew(r)
    return out
