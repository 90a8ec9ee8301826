"""Steady vortex-lattice normalwash matrix (the steady part of the doublet-lattice AIC).

Each box carries a horseshoe vortex: a bound vortex on its 1/4-chord doublet line (from the p1
side to the p4 side) and two trailing legs running to x = +infinity, as in the vortex-lattice
part of the doublet-lattice method (Albano & Rodden 1969, AIAA J. 7(2), eq. 7 and sec. III;
Katz & Plotkin, *Low-Speed Aerodynamics*, 2nd ed., eqs. 10.115-10.117 for the Biot-Savart law of a
finite and a semi-infinite straight vortex). Compressibility by the Prandtl-Glauert
transformation: x is stretched to x / beta, beta = sqrt(1 - M^2) (Katz & Plotkin sec. 13.8), which
reproduces the compressible steady kernel 1 + x0 / sqrt(x0^2 + beta^2 r^2) of Landahl.

Sign convention (Albano & Rodden, Nastran's D_jj): ``w/V = D @ dCp`` where w is the induced
velocity along each box normal (see :mod:`aero.panels` for the normal rule) and dCp =
(p_lower - p_upper)/q is positive along the sending box's normal; a lifting box induces a
downwash on itself, so the diagonal of D is negative. The kinematic boundary condition for a
surface z(x, t) is w = dz/dt + V dz/dx (Nastran's D1/D2 matrices).

Symmetry ``symxz`` (Nastran AERO/AEROS SYMXZ): +1 symmetric, -1 antisymmetric about y = 0, 0 none.
The image of every box is added with the factor ``-symxz`` in its natural orientation
(:func:`aero.panels.mirror_xz`), because its natural normal is minus the mirrored normal.
A vertical surface lying in the plane y = 0 is its own image: it carries no load in symmetric
motion (its columns of D vanish for symxz = +1, leave it out of symmetric models) and twice its
own influence in antisymmetric motion.
"""
from __future__ import annotations

import numpy as np

from aero.panels import BoxMesh, mirror_xz
from structures.common.errors import InputError, card_message

__all__ = ["steady_aic"]

_FOUR_PI = 4.0 * np.pi
_TARGET_ELEMENTS = 1 << 16          # pair entries per chunk (fastest on a 2 MB L2 cache)


def check_mach(mach: float) -> float:
    """Validate a subsonic Mach number for the VLM/DLM and return it as float."""
    m = float(mach)
    if not np.isfinite(m) or m < 0.0 or m >= 1.0:
        raise InputError(card_message(
            f"Mach number {mach!r} is outside [0, 1): the subsonic vortex-lattice and "
            "doublet-lattice methods do not apply at M >= 1 (supersonic flow needs a "
            "supersonic method such as ZONA51 / Mach box).", card="MKAERO1/AERO",
            fix="give Mach numbers 0 <= M < 1 (for M > ~0.9 expect transonic errors)."))
    return m


def check_symxz(symxz: int) -> int:
    """Validate the XZ-symmetry flag (+1, -1 or 0)."""
    if symxz not in (-1, 0, 1):
        raise InputError(card_message(f"symxz={symxz!r} is not one of +1, -1, 0.",
                                      card="AERO/AEROS",
                                      fix="use +1 (symmetric), -1 (antisymmetric) or 0 (none)."))
    return int(symxz)


def horseshoe_normalwash(colloc: np.ndarray, normal: np.ndarray, a: np.ndarray, b: np.ndarray,
                         chord: np.ndarray, beta: float) -> np.ndarray:
    """w/V at receivers per unit dCp on horseshoe-vortex senders (one block, no chunking).

    Bound vortex a -> b (Katz & Plotkin eq. 10.115):
    v = (r1 x r2)/|r1 x r2|^2 * r0 . (r1/|r1| - r2/|r2|) / (4 pi), r1 = p - a, r2 = p - b,
    r0 = b - a;
    semi-infinite legs along +x from a point q (eq. 10.115 with one end at infinity):
    v = (x_hat x r)/|x_hat x r|^2 (1 + r_x/|r|) / (4 pi), r = p - q, for b -> infinity and
    minus that for a -> infinity. A receiver on a vortex line gets no velocity from it.

    Parameters
    ----------
    colloc, normal : (m, 3) float
        Receiving points and their unit normals (physical coordinates).
    a, b : (s, 3) float
        Bound-vortex end points (p1 side, p4 side) of the senders (physical coordinates).
    chord : (s,) float
        Sender box chords; circulation per unit dCp is Gamma / V = chord / 2 (Kutta-Joukowski:
        rho V Gamma = dCp q chord per unit span).
    beta : float
        sqrt(1 - M^2); x is divided by beta (Prandtl-Glauert).

    Returns
    -------
    (m, s) float
    """
    px, py, pz = (colloc[:, i, None] for i in range(3))
    nx, ny, nz = (normal[:, i, None] for i in range(3))
    px = px / beta
    ax, ay, az = a[None, :, 0] / beta, a[None, :, 1], a[None, :, 2]
    bx, by, bz = b[None, :, 0] / beta, b[None, :, 1], b[None, :, 2]
    r1x, r1y, r1z = px - ax, py - ay, pz - az
    r2x, r2y, r2z = px - bx, py - by, pz - bz
    h1 = r1y * r1y + r1z * r1z
    h2 = r2y * r2y + r2z * r2z
    n1 = np.sqrt(h1 + r1x * r1x)
    n2 = np.sqrt(h2 + r2x * r2x)
    cx = r1y * r2z - r1z * r2y
    cy = r1z * r2x - r1x * r2z
    cz = r1x * r2y - r1y * r2x
    c2 = cx * cx + cy * cy + cz * cz
    r0x, r0y, r0z = bx - ax, by - ay, bz - az
    with np.errstate(divide="ignore", invalid="ignore"):
        proj = (r0x * r1x + r0y * r1y + r0z * r1z) / n1 - (r0x * r2x + r0y * r2y + r0z * r2z) / n2
        w = np.where(c2 > 1e-20 * (n1 * n2) ** 2, proj / c2, 0.0) * (nx * cx + ny * cy + nz * cz)
        w += np.where(h2 > 1e-20 * n2 * n2, (1.0 + r2x / n2) / h2, 0.0) * (nz * r2y - ny * r2z)
        w -= np.where(h1 > 1e-20 * n1 * n1, (1.0 + r1x / n1) / h1, 0.0) * (nz * r1y - ny * r1z)
    return w * (0.5 / _FOUR_PI * chord)[None, :]


def steady_aic(mesh: BoxMesh, mach: float, *, symxz: int = 0) -> np.ndarray:
    """Steady vortex-lattice normalwash matrix D with w/V = D @ dCp at the collocation points.

    Parameters
    ----------
    mesh : BoxMesh
        n boxes.
    mach : float
        Free-stream Mach number, 0 <= M < 1 (Prandtl-Glauert).
    symxz : {0, +1, -1}, keyword-only
        Symmetry about y = 0: none, symmetric, antisymmetric (only the modelled half is in mesh).

    Returns
    -------
    (n, n) float
        D[i, j]: normalwash at box i per unit dCp on box j (negative diagonal).
    """
    m = check_mach(mach)
    s = check_symxz(symxz)
    beta = np.sqrt(1.0 - m * m)
    n = mesh.n
    out = np.empty((n, n))
    image = mirror_xz(mesh) if s else None
    rows = max(1, _TARGET_ELEMENTS // max(n, 1))
    for i0 in range(0, n, rows):
        sl = slice(i0, min(n, i0 + rows))
        block = horseshoe_normalwash(mesh.collocation[sl], mesh.normal[sl], mesh.doublet_in,
                                     mesh.doublet_out, mesh.chord, beta)
        if s:
            block -= s * horseshoe_normalwash(mesh.collocation[sl], mesh.normal[sl],
                                              image.doublet_in, image.doublet_out, image.chord,
                                              beta)
        out[sl] = block
    return out
