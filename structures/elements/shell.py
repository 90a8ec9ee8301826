"""CQUAD4 / CTRIA3 flat shell elements: stiffness and mass, vectorised over elements.

Formulation (DOFs per grid [T1, T2, T3, R1, R2, R3], BASIC frame on output):

* CQUAD4 membrane: bilinear isoparametric with the two incompatible (bubble) modes per direction of
  Wilson et al. (1973) in Taylor's form (Taylor, Beresford & Wilson 1976, Int. J. Numer. Meth. Eng.
  10, 1211): their derivatives use the centre Jacobian J0 scaled by det J0 / det J, which makes the
  element pass the constant-strain patch test on distorted meshes; condensed statically.
* CQUAD4 bending: MITC4 Reissner-Mindlin plate (Bathe & Dvorkin 1985, Int. J. Numer. Meth. Eng. 21,
  367): bilinear w and rotations, transverse shear strains tied at the edge midpoints, so no shear
  locking; 2x2 Gauss.
* CTRIA3: constant-strain membrane + DKT bending (Batoz, Bathe & Ho 1980, Int. J. Numer. Meth. Eng.
  15, 1771), built from its definition: quadratic rotations whose corner values are the slopes and
  whose mid-side tangential values follow a cubic w along the edge. DKT is a Kirchhoff element: the
  transverse shear flexibility of MID3 is neglected in CTRIA3 (relative error ~ (t/wavelength)^2).
* Blank MID3 ("no transverse shear flexibility", QRG PSHELL) in CQUAD4 is imposed with a shear
  stiffness ``KIRCHHOFF_PENALTY`` times the bending stiffness / element area; MITC4 does not lock, so
  this reproduces the Kirchhoff limit to ~1/KIRCHHOFF_PENALTY.
* Drilling: rotation about the element normal is tied to the membrane's rotation at the element centre,
  w_z = (dv/dx - du/dy)/2, by a penalty ``1e-6 * K6ROT * (mean diag(A) * area + mean diag(D))``:
  rigid-body modes stay exact and flat meshes are not singular. K6ROT is Nastran's PARAM K6ROT (MSC
  QRG: stiffness added to the normal rotation of CQUAD4/CTRIA3, default 100. since MSC Nastran 2004;
  Nastran's penalty is ~1e-6 * K6ROT * G * t * area). With mean diag(A) ~ 2.2 G t (nu = 0.3) our
  penalty is about 2.2 times Nastran's at the same K6ROT; K6ROT = 0 leaves the drilling rotation
  without stiffness, to be removed by AUTOSPC (structures.singularity) as in MSC Nastran V2001.
  As in Nastran ("K6ROT is forced to 0 when only membrane elements exist"), membrane-only sections
  (PSHELL MID2 blank: no bending) get no drilling penalty.
* Warped CQUAD4: the element is built on its mean plane (normal = d13 x d24, the QRG element z axis)
  and joined to the grids by rigid offsets h_i along the normal, so rigid-body motion stays exact.
* Mass: consistent (bilinear / linear shape functions) or lumped (area/4, area/3) translational mass
  of (rho*T + NSM) per area; no rotary inertia (as Nastran's default shell mass and thin-plate theory).

Element axes follow the QRG: CQUAD4 z = d13 x d24, x = bisector of d13 and -d24 (the angle-bisector
convention; x is along G1G2 for a rectangle); CTRIA3 x = G1 -> G2. ``theta`` is the material angle
from the element x axis, about z, in radians.
"""
from __future__ import annotations

import numpy as np

from structures.elements.shell_materials import ShellSection
from structures.common.errors import InputError

KIRCHHOFF_PENALTY = 1.0e4
#: Nastran PARAM K6ROT default (MSC Nastran 2004 and later, linear solutions included).
K6ROT_DEFAULT = 100.0
CHUNK = 2048            # elements per vectorised block: bounds the temporaries (~100 MB)

_G = 1.0 / np.sqrt(3.0)
_GAUSS_2X2 = np.array([[-_G, -_G], [_G, -_G], [_G, _G], [-_G, _G]])   # weights 1
_QUAD_NODES = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _check_xyz(xyz: np.ndarray, section: ShellSection, theta: np.ndarray, nn: int, name: str):
    xyz = np.asarray(xyz, dtype=float)
    theta = np.asarray(theta, dtype=float)
    ne = xyz.shape[0] if xyz.ndim == 3 else -1
    if xyz.shape != (ne, nn, 3) or theta.shape != (ne,) or section.ne != ne:
        raise InputError(f"{name}: xyz {xyz.shape}, theta {theta.shape} and section ({section.ne} "
                         f"elements) disagree; expected ({ne}, {nn}, 3), ({ne},), {ne}. Fix: pass one "
                         "row per element.")
    return xyz, theta


def _material_to_element(section: ShellSection, theta: np.ndarray):
    """A, B, D (ne,3,3) and S (ne,2,2) rotated from material to element axes.

    eps_mat = T eps_el with T the engineering-strain rotation (Jones, eq. 2.79 with Reuter's matrix),
    so C_el = T^T C_mat T; gamma_mat = R gamma_el for the transverse shears.
    """
    c, s = np.cos(theta), np.sin(theta)
    T = np.empty((theta.size, 3, 3))
    T[:, 0] = np.stack([c * c, s * s, c * s], -1)
    T[:, 1] = np.stack([s * s, c * c, -c * s], -1)
    T[:, 2] = np.stack([-2 * c * s, 2 * c * s, c * c - s * s], -1)
    R = np.stack([np.stack([c, s], -1), np.stack([-s, c], -1)], 1)
    Tt, Rt = np.swapaxes(T, 1, 2), np.swapaxes(R, 1, 2)
    rot = lambda C: Tt @ C @ T  # noqa: E731
    S = Rt @ section.S @ R
    return rot(section.A), rot(section.B), rot(section.D), S


def _btcb(Bl: np.ndarray, C: np.ndarray, Br: np.ndarray) -> np.ndarray:
    """Batched Bl^T C Br, (ne, i, j)."""
    return np.swapaxes(Bl, 1, 2) @ (C @ Br)


def _warp_offsets(K: np.ndarray, h: np.ndarray) -> np.ndarray:
    """K of element nodes offset by -h along the local z axis from their grids, (ne, 6nn, 6nn).

    Rigid link (local axes): u_node = u - h*ry, v_node = v + h*rx, i.e. q_node = W q_grid with W
    the identity plus these two terms; returns W^T K W.
    """
    Kw = K.copy()
    nn = h.shape[1]
    for j in range(nn):                         # columns: K W
        Kw[:, :, 6 * j + 4] -= h[:, j, None] * Kw[:, :, 6 * j]
        Kw[:, :, 6 * j + 3] += h[:, j, None] * Kw[:, :, 6 * j + 1]
    for j in range(nn):                         # rows: W^T (K W)
        Kw[:, 6 * j + 4, :] -= h[:, j, None] * Kw[:, 6 * j, :]
        Kw[:, 6 * j + 3, :] += h[:, j, None] * Kw[:, 6 * j + 1, :]
    return Kw


def _to_basic(K_local: np.ndarray, R: np.ndarray) -> np.ndarray:
    """K_basic = T^T K_local T with T = blockdiag(R, R, ...) (3x3 blocks, rows of R = local axes)."""
    ne, n = K_local.shape[:2]
    nb = n // 3
    KT = (K_local.reshape(ne, n, nb, 3) @ R[:, None]).reshape(ne, nb, 3, n)   # K T, block by block
    return (np.swapaxes(R, 1, 2)[:, None] @ KT).reshape(ne, n, n)           # T^T (K T)


def _jacobian(dN: np.ndarray, xy: np.ndarray):
    """J (ne,2,2) = dN (2,nn) @ xy (ne,nn,2), its determinant and inverse (explicit 2x2)."""
    J = np.einsum("ai,eik->eak", dN, xy)
    det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
    inv = np.empty_like(J)
    with np.errstate(divide="ignore", invalid="ignore"):
        inv[:, 0, 0], inv[:, 1, 1] = J[:, 1, 1] / det, J[:, 0, 0] / det
        inv[:, 0, 1], inv[:, 1, 0] = -J[:, 0, 1] / det, -J[:, 1, 0] / det
    return J, det, inv


def _condense(K: np.ndarray, n_keep: int) -> np.ndarray:
    """Static condensation of the trailing internal DOFs: K_cc - K_ci K_ii^-1 K_ic.

    K_ii is symmetric positive definite (or exactly zero for a membrane-free section, then the
    coupling K_ci is zero too and nothing is condensed); batched Gauss elimination without pivoting.
    """
    Kc = K.copy()
    for i in range(n_keep, K.shape[1]):
        pivot = Kc[:, i, i]
        safe = np.where(pivot > 0, pivot, 1.0)
        factor = np.where(pivot > 0, 1.0, 0.0)[:, None] * Kc[:, :, i] / safe[:, None]
        Kc -= factor[:, :, None] * Kc[:, i, None, :]
    return Kc[:, :n_keep, :n_keep]


def _translational_mass(Mt: np.ndarray) -> np.ndarray:
    """Expand a scalar nodal mass matrix (ne, nn, nn) to (ne, 6nn, 6nn) on T1..T3."""
    ne, nn = Mt.shape[:2]
    M = np.zeros((ne, nn, 6, nn, 6))
    for k in range(3):
        M[:, :, k, :, k] = Mt
    return M.reshape(ne, 6 * nn, 6 * nn)


def _drill_stiffness(b_omega: np.ndarray, k: np.ndarray, nn: int) -> np.ndarray:
    """sum_i k (rz_i - omega)^2 with omega = b_omega @ q; b_omega (ne, 6nn)."""
    ne = b_omega.shape[0]
    E = np.zeros((ne, nn, 6 * nn))
    E[:, np.arange(nn), 6 * np.arange(nn) + 5] = 1.0
    V = E - b_omega[:, None, :]
    return k[:, None, None] * (np.swapaxes(V, 1, 2) @ V)


def _drill_k(A: np.ndarray, D: np.ndarray, area: np.ndarray, k6rot: float) -> np.ndarray:
    """Drilling penalty per element; zero for membrane-only sections (K6ROT forced to 0)."""
    dA = np.trace(A, axis1=1, axis2=2) / 3.0
    dD = np.trace(D, axis1=1, axis2=2) / 3.0
    return np.where(np.any(D != 0.0, axis=(1, 2)), 1.0e-6 * k6rot * (dA * area + dD), 0.0)


def _chunked(block, xyz, section, theta, lumped, k6rot, ndof):
    """Run ``block`` over chunks of CHUNK elements into preallocated K, M (bounded temporaries)."""
    ne = xyz.shape[0]
    K = np.empty((ne, ndof, ndof))
    M = np.empty((ne, ndof, ndof))
    for start in range(0, ne, CHUNK):
        part = slice(start, min(start + CHUNK, ne))
        K[part], M[part] = block(xyz[part], section.take(part), theta[part], lumped, k6rot)
    return K, M


def _quad_frame(xyz: np.ndarray):
    """Element axes R (ne,3,3) (rows x, y, z), local 2-D corners (ne,4,2), offsets h (ne,4)."""
    d13 = xyz[:, 2] - xyz[:, 0]
    d24 = xyz[:, 3] - xyz[:, 1]
    ez = np.cross(d13, d24)
    if np.any(np.linalg.norm(ez, axis=1) <= 1e-12 * np.linalg.norm(d13, axis=1) ** 2):
        raise InputError("CQUAD4 with parallel diagonals (degenerate quad). Fix: check the grid "
                         "order G1..G4 of the element (they must go round the perimeter).")
    ez = _unit(ez)
    ex = _unit(_unit(d13) - _unit(d24))                    # QRG: bisector of d13 and -d24
    ey = np.cross(ez, ex)
    R = np.stack([ex, ey, ez], axis=1)
    rel = xyz - xyz.mean(axis=1, keepdims=True)
    loc = rel @ np.swapaxes(R, 1, 2)
    return R, loc[:, :, :2], loc[:, :, 2]


def _quad_shape(xi: float, eta: float):
    """Bilinear N (4,) and dN/d(xi, eta) (2, 4)."""
    N = 0.25 * (1 + _QUAD_NODES[:, 0] * xi) * (1 + _QUAD_NODES[:, 1] * eta)
    dN = 0.25 * np.array([_QUAD_NODES[:, 0] * (1 + _QUAD_NODES[:, 1] * eta),
                          _QUAD_NODES[:, 1] * (1 + _QUAD_NODES[:, 0] * xi)])
    return N, dN


def _covariant_shear_row(xy: np.ndarray, xi: float, eta: float, direction: int) -> np.ndarray:
    """Row (ne, 28) of the covariant shear e_r = w,r + beta . x,r at (xi, eta), r = xi or eta.

    beta = (ry, -rx) are the slopes of the normal (u = z*beta_x, v = z*beta_y).
    """
    N, dN = _quad_shape(xi, eta)
    J = np.einsum("ai,eik->eak", dN, xy)
    xr, yr = J[:, direction, 0], J[:, direction, 1]
    row = np.zeros((xy.shape[0], 28))
    row[:, 2:24:6] = dN[direction]
    row[:, 4:24:6] = N[None, :] * xr[:, None]
    row[:, 3:24:6] = -N[None, :] * yr[:, None]
    return row


def quad4_matrices(xyz: np.ndarray, section: ShellSection, theta: np.ndarray,
                   lumped: bool = False,
                   k6rot: float = K6ROT_DEFAULT) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass of CQUAD4 elements in the basic frame.

    Parameters
    ----------
    xyz : ndarray (ne, 4, 3)
        Basic coordinates of G1..G4 in CQUAD4 connectivity order.
    section : ShellSection
        ``ne`` sections in material axes.
    theta : ndarray (ne,)
        Material angle [rad] from the CQUAD4 element x axis (QRG bisector convention).
    lumped : bool
        Lumped translational mass (area/4 per grid) instead of consistent.
    k6rot : float
        Nastran PARAM K6ROT, scale of the drilling penalty (>= 0).

    Returns
    -------
    K, M : ndarray (ne, 24, 24)
        DOFs node-major [T1, T2, T3, R1, R2, R3] per grid, basic frame.
    """
    xyz, theta = _check_xyz(xyz, section, theta, 4, "quad4_matrices")
    return _chunked(_quad4_block, xyz, section, theta, lumped, k6rot, 24)


def _quad4_block(xyz: np.ndarray, section: ShellSection, theta: np.ndarray, lumped: bool,
                 k6rot: float):
    """CQUAD4 K, M of one chunk of elements (see :func:`quad4_matrices`)."""
    ne = xyz.shape[0]
    R, xy, h = _quad_frame(xyz)
    A, B, D, S = _material_to_element(section, theta)
    _, det0, inv0 = _jacobian(_quad_shape(0.0, 0.0)[1], xy)
    tying = {0: [(0.0, -1.0), (0.0, 1.0)], 1: [(-1.0, 0.0), (1.0, 0.0)]}   # MITC4 points B, D / A, C
    rows = {d: [_covariant_shear_row(xy, *p, d) for p in pts] for d, pts in tying.items()}
    gauss = []
    for xi, eta in _GAUSS_2X2:
        N, dN = _quad_shape(xi, eta)
        _, det, inv = _jacobian(dN, xy)
        if np.any(det <= 0):
            bad = int(np.flatnonzero(det <= 0)[0])
            raise InputError(f"CQUAD4 number {bad} (0-based in this batch) has a non-positive Jacobian "
                             "(concave or badly distorted quad). Fix: reorder G1..G4 or remesh.")
        dNx = inv @ dN                                                    # (ne, 2, 4)
        dP = np.array([[-2 * xi, 0.0], [0.0, -2 * eta]])                  # bubbles 1-xi^2, 1-eta^2
        dPx = (inv0 @ dP) * (det0 / det)[:, None, None]                   # Taylor's correction
        Bm = np.zeros((ne, 3, 28))
        Bm[:, 0, 0:24:6] = dNx[:, 0]
        Bm[:, 1, 1:24:6] = dNx[:, 1]
        Bm[:, 2, 0:24:6] = dNx[:, 1]
        Bm[:, 2, 1:24:6] = dNx[:, 0]
        Bm[:, 0, 24:26] = dPx[:, 0]
        Bm[:, 1, 26:28] = dPx[:, 1]
        Bm[:, 2, 24:26] = dPx[:, 1]
        Bm[:, 2, 26:28] = dPx[:, 0]
        Bb = np.zeros((ne, 3, 28))                                        # kappa of beta = (ry, -rx)
        Bb[:, 0, 4:24:6] = dNx[:, 0]
        Bb[:, 1, 3:24:6] = -dNx[:, 1]
        Bb[:, 2, 4:24:6] = dNx[:, 1]
        Bb[:, 2, 3:24:6] = -dNx[:, 0]
        cov = np.stack([0.5 * (1 - eta) * rows[0][0] + 0.5 * (1 + eta) * rows[0][1],
                        0.5 * (1 - xi) * rows[1][0] + 0.5 * (1 + xi) * rows[1][1]], axis=1)
        Bs = inv @ cov                                                    # gamma = J^-1 e_cov
        gauss.append((N, det, Bm, Bb, Bs))
    area = sum(g[1] for g in gauss)
    S = S.copy()
    rigid = section.shear_rigid
    if np.any(rigid):
        dmean = 0.5 * (D[rigid, 0, 0] + D[rigid, 1, 1])
        S[rigid] = (KIRCHHOFF_PENALTY * dmean / area[rigid])[:, None, None] * np.eye(2)
    C = np.zeros((ne, 8, 8))                     # generalized [N; M; Q] = C [eps; kappa; gamma]
    C[:, :3, :3], C[:, :3, 3:6], C[:, 3:6, :3], C[:, 3:6, 3:6], C[:, 6:, 6:] = A, B, B, D, S
    Bg = np.concatenate([np.concatenate([Bm, Bb, Bs], axis=1) for _, _, Bm, Bb, Bs in gauss], axis=1)
    CBg = np.concatenate([det[:, None, None] * (C @ np.concatenate([Bm, Bb, Bs], axis=1))
                          for _, det, Bm, Bb, Bs in gauss], axis=1)
    K = np.swapaxes(Bg, 1, 2) @ CBg              # sum over Gauss points of B^T C B det J
    Kc = _condense(K, 24)
    b_omega = np.zeros((ne, 24))
    dNc = inv0 @ _quad_shape(0.0, 0.0)[1]
    b_omega[:, 1:24:6] = 0.5 * dNc[:, 0]
    b_omega[:, 0:24:6] = -0.5 * dNc[:, 1]
    Kc += _drill_stiffness(b_omega, _drill_k(A, D, area, k6rot), 4)
    Kb = _to_basic(_warp_offsets(Kc, h) if np.any(h) else Kc, R)
    m = section.mass_per_area
    if lumped:
        Mt = (m * area / 4.0)[:, None, None] * np.eye(4)
    else:
        Mt = sum(det[:, None, None] * np.outer(N, N) for N, det, *_ in gauss) * m[:, None, None]
    return 0.5 * (Kb + Kb.transpose(0, 2, 1)), _translational_mass(Mt)


def _tria_frame(xyz: np.ndarray):
    """Element axes R (ne,3,3) (x = G1->G2) and local 2-D corners (ne,3,2)."""
    ex = xyz[:, 1] - xyz[:, 0]
    ez = np.cross(ex, xyz[:, 2] - xyz[:, 0])
    if np.any(np.linalg.norm(ez, axis=1) <= 1e-12 * np.einsum("ek,ek->e", ex, ex)):
        raise InputError("CTRIA3 with collinear grids (zero area). Fix: check G1, G2, G3.")
    ex, ez = _unit(ex), _unit(ez)
    R = np.stack([ex, np.cross(ez, ex), ez], axis=1)
    loc = (xyz - xyz.mean(axis=1, keepdims=True)) @ np.swapaxes(R, 1, 2)
    return R, loc[:, :, :2]


_TRI_POINTS = np.array([[2 / 3, 1 / 6, 1 / 6], [1 / 6, 2 / 3, 1 / 6], [1 / 6, 1 / 6, 2 / 3]])  # w = 1/3
_EDGES = ((0, 1), (1, 2), (2, 0))          # mid-side nodes 3, 4, 5 of the quadratic rotation field


def _dkt_nodal_rotations(xy: np.ndarray) -> np.ndarray:
    """T (ne, 12, 9): corner bending DOFs [w, rx, ry]*3 -> slopes beta at 6 nodes (x, y each).

    Corners: beta = (ry, -rx) = -grad w (Kirchhoff). Mid-side of edge i-j (tangent t, normal n):
    beta.t = -dw/ds of the Hermite cubic w on the edge = -1.5 (w_j - w_i)/l - (beta_i + beta_j).t / 4,
    beta.n = (beta_i + beta_j).n / 2 (Batoz, Bathe & Ho 1980, the DKT hypotheses).
    """
    ne = xy.shape[0]
    P = np.array([[0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
    T = np.zeros((ne, 6, 2, 3, 3))
    for i in range(3):
        T[:, i, :, i, :] = P
    for k, (i, j) in enumerate(_EDGES):
        d = xy[:, j] - xy[:, i]
        ell = np.linalg.norm(d, axis=1)
        t = d / ell[:, None]
        n = np.stack([-t[:, 1], t[:, 0]], axis=1)
        C = 0.5 * np.einsum("ea,eb->eab", n, n) - 0.25 * np.einsum("ea,eb->eab", t, t)
        T[:, 3 + k, :, i, :] += C @ P
        T[:, 3 + k, :, j, :] += C @ P
        T[:, 3 + k, :, i, 0] += 1.5 * t / ell[:, None]
        T[:, 3 + k, :, j, 0] -= 1.5 * t / ell[:, None]
    return T.reshape(ne, 12, 9)


def tria3_matrices(xyz: np.ndarray, section: ShellSection, theta: np.ndarray,
                   lumped: bool = False,
                   k6rot: float = K6ROT_DEFAULT) -> tuple[np.ndarray, np.ndarray]:
    """Stiffness and mass of CTRIA3 elements (CST membrane + DKT bending) in the basic frame.

    Parameters
    ----------
    xyz : ndarray (ne, 3, 3)
        Basic coordinates of G1..G3.
    section : ShellSection
        ``ne`` sections in material axes (S is not used: DKT is a Kirchhoff element).
    theta : ndarray (ne,)
        Material angle [rad] from the element x axis G1 -> G2.
    lumped : bool
        Lumped translational mass (area/3 per grid) instead of consistent.
    k6rot : float
        Nastran PARAM K6ROT, scale of the drilling penalty (>= 0).

    Returns
    -------
    K, M : ndarray (ne, 18, 18)
        DOFs node-major [T1, T2, T3, R1, R2, R3] per grid, basic frame.
    """
    xyz, theta = _check_xyz(xyz, section, theta, 3, "tria3_matrices")
    return _chunked(_tria3_block, xyz, section, theta, lumped, k6rot, 18)


def _tria3_block(xyz: np.ndarray, section: ShellSection, theta: np.ndarray, lumped: bool,
                 k6rot: float):
    """CTRIA3 K, M of one chunk of elements (see :func:`tria3_matrices`)."""
    ne = xyz.shape[0]
    R, xy = _tria_frame(xyz)
    A, B, D, _ = _material_to_element(section, theta)
    x, y = xy[:, :, 0], xy[:, :, 1]
    b = np.stack([y[:, 1] - y[:, 2], y[:, 2] - y[:, 0], y[:, 0] - y[:, 1]], axis=1)
    c = np.stack([x[:, 2] - x[:, 1], x[:, 0] - x[:, 2], x[:, 1] - x[:, 0]], axis=1)
    area = 0.5 * (b[:, 0] * c[:, 1] - b[:, 1] * c[:, 0])
    dL = np.stack([b, c], axis=1) / (2 * area)[:, None, None]              # dL_i/d(x, y), (ne,2,3)
    Bm = np.zeros((ne, 3, 18))
    Bm[:, 0, 0::6] = dL[:, 0]
    Bm[:, 1, 1::6] = dL[:, 1]
    Bm[:, 2, 0::6] = dL[:, 1]
    Bm[:, 2, 1::6] = dL[:, 0]
    T = _dkt_nodal_rotations(xy)
    bend = np.array([2, 3, 4, 8, 9, 10, 14, 15, 16])                     # w, rx, ry of each grid
    K = _btcb(Bm, A, Bm) * area[:, None, None]   # CST (constant strain)
    for L in _TRI_POINTS:
        # derivatives of the quadratic shape functions: corners L(2L-1), mid-sides 4 L_i L_j
        dN6 = np.zeros((ne, 2, 6))
        for i in range(3):
            dN6[:, :, i] = (4 * L[i] - 1) * dL[:, :, i]
        for k, (i, j) in enumerate(_EDGES):
            dN6[:, :, 3 + k] = 4 * (L[j] * dL[:, :, i] + L[i] * dL[:, :, j])
        Bq = np.zeros((ne, 3, 6, 2))
        Bq[:, 0, :, 0] = dN6[:, 0]
        Bq[:, 1, :, 1] = dN6[:, 1]
        Bq[:, 2, :, 0] = dN6[:, 1]
        Bq[:, 2, :, 1] = dN6[:, 0]
        Bb = np.zeros((ne, 3, 18))
        Bb[:, :, bend] = Bq.reshape(ne, 3, 12) @ T
        cpl = _btcb(Bm, B, Bb)
        K += (area / 3.0)[:, None, None] * (_btcb(Bb, D, Bb) + cpl
                                            + cpl.transpose(0, 2, 1))
    b_omega = np.zeros((ne, 18))
    b_omega[:, 1::6] = 0.5 * dL[:, 0]
    b_omega[:, 0::6] = -0.5 * dL[:, 1]
    K += _drill_stiffness(b_omega, _drill_k(A, D, area, k6rot), 3)
    Kb = _to_basic(K, R)
    m = section.mass_per_area * area
    if lumped:
        Mt = (m / 3.0)[:, None, None] * np.eye(3)
    else:
        Mt = (m / 12.0)[:, None, None] * (np.ones((3, 3)) + np.eye(3))      # (A/12)[[2,1,1],...]
    return 0.5 * (Kb + Kb.transpose(0, 2, 1)), _translational_mass(Mt)


def element_axes(xyz: np.ndarray) -> np.ndarray:
    """Element coordinate axes of CQUAD4 (``xyz`` (ne, 4, 3)) or CTRIA3 (``xyz`` (ne, 3, 3)).

    Returns
    -------
    (ne, 3, 3) rows are the element x, y, z axes in basic (QRG conventions: CQUAD4 x bisects the
    diagonals, CTRIA3 x runs from G1 to G2; z is the normal).
    """
    xyz = np.asarray(xyz, float)
    return _quad_frame(xyz)[0] if xyz.shape[1] == 4 else _tria_frame(xyz)[0]


def material_angle(axes: np.ndarray, material_x: np.ndarray) -> np.ndarray:
    """Angle [rad] from the element x axis to the projection of ``material_x`` on the element plane.

    Parameters
    ----------
    axes : (ne, 3, 3) element axes (rows), from :func:`element_axes`.
    material_x : (ne, 3) the MCID system's x axis in basic (QRG CQUAD4 MCID: projected on the
        element surface).

    Returns
    -------
    (ne,) angles.
    """
    local = np.einsum("eij,ej->ei", axes, np.asarray(material_x, float))
    return np.arctan2(local[:, 1], local[:, 0])
