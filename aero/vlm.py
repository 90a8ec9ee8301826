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
"""
from __future__ import annotations

import numpy as np

from aero.panels import BoxMesh, mirror_xz
from structures.errors import InputError, card_message

__all__ = ["steady_aic"]

_FOUR_PI = 4.0 * np.pi
_TARGET_ELEMENTS = 1 << 18          # pair entries per chunk (a few MB of temporaries)


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


def _leg(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Velocity per unit circulation of a semi-infinite vortex from q along +x (Katz & Plotkin
    eq. 10.117 with one end at infinity): v = (x_hat x r)/|x_hat x r|^2 (1 + r_x/|r|) / (4 pi).

    p : (m, 1, 3) receivers; q : (1, s, 3) start points. Returns (m, s, 3).
    """
    r = p - q
    h2 = r[..., 1] ** 2 + r[..., 2] ** 2
    rn = np.sqrt(h2 + r[..., 0] ** 2)
    ok = h2 > 1e-20 * rn ** 2                                  # p on the leg's line: no velocity
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(ok, (1.0 + r[..., 0] / rn) / (_FOUR_PI * h2), 0.0)
    return np.stack([np.zeros_like(f), -r[..., 2] * f, r[..., 1] * f], axis=-1)


def _bound(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Velocity per unit circulation of the finite vortex a -> b (Katz & Plotkin eq. 10.115):
    v = (r1 x r2)/|r1 x r2|^2 * r0 . (r1/|r1| - r2/|r2|) / (4 pi)."""
    r1, r2 = p - a, p - b
    r0 = b - a
    c = np.cross(r1, r2)
    c2 = np.einsum("...i,...i->...", c, c)
    n1 = np.sqrt(np.einsum("...i,...i->...", r1, r1))
    n2 = np.sqrt(np.einsum("...i,...i->...", r2, r2))
    ok = c2 > 1e-20 * (n1 * n2) ** 2                           # p on the vortex line: none
    with np.errstate(divide="ignore", invalid="ignore"):
        proj = np.einsum("...i,...i->...", r0, r1 / n1[..., None] - r2 / n2[..., None])
        f = np.where(ok, proj / (_FOUR_PI * c2), 0.0)
    return c * f[..., None]


def horseshoe_normalwash(colloc: np.ndarray, normal: np.ndarray, a: np.ndarray, b: np.ndarray,
                         chord: np.ndarray, beta: float) -> np.ndarray:
    """w/V at receivers per unit dCp on horseshoe-vortex senders (one block, no chunking).

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
    stretch = np.array([1.0 / beta, 1.0, 1.0])
    p = (colloc * stretch)[:, None, :]
    qa, qb = (a * stretch)[None], (b * stretch)[None]
    v = _bound(p, qa, qb) + _leg(p, qb) - _leg(p, qa)          # legs: infinity -> a, b -> infinity
    return np.einsum("msi,mi->ms", v, normal) * (0.5 * chord)[None, :]


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
