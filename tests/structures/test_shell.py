"""Element-level tests of the CQUAD4 / CTRIA3 shell kernels and the PSHELL section.

Analytic references: rigid-body modes, the MacNeal-Harder distorted patch (MacNeal & Harder 1985,
Finite Elements in Analysis and Design 1, 3-20: rectangle 0.24 x 0.12 with four interior grids) for
constant membrane strain and constant curvature, total mass, frame invariance and material
equivalences (MAT8/MAT2 reducing to MAT1).
"""
from __future__ import annotations

import numpy as np
import pytest

from structures.elements.shell import quad4_matrices, tria3_matrices
from structures.elements.shell_materials import (Mat1, Mat2, Mat8, PShell, ShellSection,
                                                 material_from_fields, pshell_from_fields,
                                                 pshell_section, stack_sections)
from structures.common.errors import InputError, MissingReferenceError

E, NU, RHO = 1.0e6, 0.25, 2.5
MAT = {1: Mat1.from_fields(1, E, None, NU, RHO)}

# MacNeal-Harder patch: 4 corner grids + 4 interior grids, 5 distorted quads
PATCH_XY = np.array([[0.0, 0.0], [0.24, 0.0], [0.24, 0.12], [0.0, 0.12],
                     [0.04, 0.02], [0.18, 0.03], [0.16, 0.08], [0.08, 0.08]])
PATCH_QUADS = np.array([[0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7], [4, 5, 6, 7]])
PATCH_TRIAS = np.concatenate([PATCH_QUADS[:, [0, 1, 2]], PATCH_QUADS[:, [0, 2, 3]]])
INTERIOR = np.arange(4, 8)


def section(ne: int, t: float = 0.001, mid3: int | None = 1, nsm: float = 0.0) -> ShellSection:
    return pshell_section(PShell(1, t, 1, 1, mid3=mid3, nsm=nsm), MAT, ne)


def rotation(seed: int) -> np.ndarray:
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def rigid_modes(xyz: np.ndarray) -> np.ndarray:
    """(6nn, 6) exact rigid-body displacement fields of grids at xyz (nn, 3)."""
    nn = xyz.shape[0]
    U = np.zeros((nn, 6, 6))
    for k in range(3):
        U[:, k, k] = 1.0
        axis = np.eye(3)[k]
        U[:, :3, 3 + k] = np.cross(axis, xyz)
        U[:, 3 + k, 3 + k] = 1.0
    return U.reshape(6 * nn, 6)


QUAD_FLAT = np.array([[0.0, 0.0, 0.0], [1.2, 0.1, 0.0], [1.0, 0.9, 0.0], [-0.1, 1.1, 0.0]])
QUAD_WARPED = QUAD_FLAT + np.array([[0, 0, 0.03], [0, 0, -0.03], [0, 0, 0.03], [0, 0, -0.03]])


@pytest.mark.parametrize("mid3", [1, None], ids=["shear-flexible", "Kirchhoff"])
@pytest.mark.parametrize("case", ["flat quad", "warped quad", "tria"])
def test_six_rigid_body_modes(case, mid3):
    xyz = {"flat quad": QUAD_FLAT, "warped quad": QUAD_WARPED, "tria": QUAD_FLAT[:3]}[case]
    xyz = xyz @ rotation(3).T + np.array([5.0, -2.0, 1.0])
    kernel = tria3_matrices if case == "tria" else quad4_matrices
    K, _ = kernel(xyz[None], section(1, t=0.01, mid3=mid3), np.array([0.4]))
    K = K[0]
    w = np.linalg.eigvalsh(K)
    assert np.all(np.abs(w[:6]) < 1e-11 * w[-1])
    assert w[6] > 1e-9 * w[-1]                      # nothing else is singular (drilling included)
    residual = K @ rigid_modes(xyz)
    assert np.abs(residual).max() < 1e-11 * np.abs(K).max() * np.abs(xyz).max()


def assemble_patch(kernel, conn, xyz, sec):
    n = xyz.shape[0]
    K_e, _ = kernel(xyz[conn], sec, np.zeros(len(conn)))
    K = np.zeros((6 * n, 6 * n))
    for e, nodes in enumerate(conn):
        dofs = (6 * nodes[:, None] + np.arange(6)).ravel()
        K[np.ix_(dofs, dofs)] += K_e[e]
    return K


def solve_patch(K, exact, interior):
    """Prescribe the exact field on the boundary grids, solve the interior grids' 6 DOFs."""
    free = (6 * interior[:, None] + np.arange(6)).ravel()
    fixed = np.setdiff1d(np.arange(K.shape[0]), free)
    q_free = np.linalg.solve(K[np.ix_(free, free)], -K[np.ix_(free, fixed)] @ exact[fixed])
    return q_free, exact[free]


def membrane_field(xyz):
    """u = 1e-3 (x + y/2), v = 1e-3 (y + x/2) (MacNeal-Harder); drilling = (v,x - u,y)/2 = 0."""
    q = np.zeros((xyz.shape[0], 6))
    q[:, 0] = 1e-3 * (xyz[:, 0] + xyz[:, 1] / 2)
    q[:, 1] = 1e-3 * (xyz[:, 1] + xyz[:, 0] / 2)
    return q.ravel(), np.array([1e-3, 1e-3, 1e-3])


def bending_field(xyz):
    """w = 1e-3 (x^2 + xy + y^2)/2, R1 = w,y, R2 = -w,x; kappa = [w,xx, w,yy, 2 w,xy] (sign-free)."""
    x, y = xyz[:, 0], xyz[:, 1]
    q = np.zeros((xyz.shape[0], 6))
    q[:, 2] = 1e-3 * (x * x + x * y + y * y) / 2
    q[:, 3] = 1e-3 * (x / 2 + y)
    q[:, 4] = -1e-3 * (x + y / 2)
    return q.ravel(), np.array([1e-3, 1e-3, 1e-3])


@pytest.mark.parametrize("mid3", [1, None], ids=["shear-flexible", "Kirchhoff"])
@pytest.mark.parametrize("field", [membrane_field, bending_field], ids=["membrane", "bending"])
@pytest.mark.parametrize("kernel,conn", [(quad4_matrices, PATCH_QUADS),
                                         (tria3_matrices, PATCH_TRIAS)], ids=["quad4", "tria3"])
def test_patch(kernel, conn, field, mid3):
    """Interior grids reproduce the constant-strain/curvature field; energy = area * e.C.e / 2."""
    xyz = np.column_stack([PATCH_XY, np.zeros(len(PATCH_XY))])
    sec = section(len(conn), mid3=mid3)
    K = assemble_patch(kernel, conn, xyz, sec)
    exact, strain = field(xyz)
    q_free, q_exact = solve_patch(K, exact, INTERIOR)
    np.testing.assert_allclose(q_free, q_exact, rtol=0, atol=1e-9 * np.abs(exact).max())
    C = sec.A[0] if field is membrane_field else sec.D[0]
    energy_exact = 0.5 * 0.24 * 0.12 * strain @ C @ strain
    np.testing.assert_allclose(0.5 * exact @ K @ exact, energy_exact, rtol=1e-9)


def test_patch_in_a_tilted_plane():
    """The membrane patch, rotated in space, still passes (frame handling)."""
    Q = rotation(7)
    xyz = np.column_stack([PATCH_XY, np.zeros(len(PATCH_XY))])
    exact, _ = membrane_field(xyz)
    exact_rot = (exact.reshape(-1, 2, 3) @ Q.T).ravel()
    K = assemble_patch(quad4_matrices, PATCH_QUADS, xyz @ Q.T, section(5))
    q_free, q_exact = solve_patch(K, exact_rot, INTERIOR)
    np.testing.assert_allclose(q_free, q_exact, rtol=0, atol=1e-9 * np.abs(exact).max())


@pytest.mark.parametrize("lumped", [False, True])
def test_total_mass(lumped):
    t, nsm = 0.02, 0.3
    sec = section(1, t=t, nsm=nsm)
    quad = np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0], [1.7, 1.2, 0.0], [0.1, 0.9, 0.0]])
    quad_area = 0.5 * abs(np.cross(quad[2] - quad[0], quad[3] - quad[1])[2])
    tria_area = 0.5 * abs(np.cross(quad[1] - quad[0], quad[2] - quad[0])[2])
    for kernel, xyz, area in [(quad4_matrices, quad, quad_area), (tria3_matrices, quad[:3], tria_area)]:
        Q = rotation(11)
        _, M = kernel((xyz @ Q.T)[None], sec, np.zeros(1), lumped=lumped)
        U = rigid_modes(xyz @ Q.T)
        m_rigid = U[:, :3].T @ M[0] @ U[:, :3]
        np.testing.assert_allclose(m_rigid, (RHO * t + nsm) * area * np.eye(3), rtol=1e-12,
                                   atol=1e-14)


@pytest.mark.parametrize("kernel,xyz", [(quad4_matrices, QUAD_WARPED), (tria3_matrices, QUAD_FLAT[:3])],
                         ids=["quad4", "tria3"])
def test_rotation_in_space(kernel, xyz):
    Q = rotation(5)
    sec = section(1, t=0.05)
    K, M = kernel(xyz[None], sec, np.array([0.2]))
    K2, M2 = kernel((xyz @ Q.T + 3.0)[None], sec, np.array([0.2]))
    nn = xyz.shape[0]
    T = np.kron(np.eye(2 * nn), Q)
    np.testing.assert_allclose(K2[0], T @ K[0] @ T.T, rtol=0, atol=1e-10 * np.abs(K).max())
    np.testing.assert_allclose(M2[0], T @ M[0] @ T.T, rtol=0, atol=1e-12 * np.abs(M).max())
    np.testing.assert_allclose(np.linalg.eigvalsh(K2[0]), np.linalg.eigvalsh(K[0]), rtol=0,
                               atol=1e-10 * np.abs(K).max())


def element_matrices(materials, pshell):
    sec = pshell_section(pshell, materials, 2)
    return quad4_matrices(np.stack([QUAD_FLAT, QUAD_WARPED]), sec, np.array([0.3, -0.7]))[0], sec


def test_mat8_isotropic_equals_mat1():
    g = E / (2 * (1 + NU))
    mat8 = {1: Mat8(1, E, E, NU, g, g, g, RHO)}
    K1, s1 = element_matrices(MAT, PShell(1, 0.01, 1, 1, mid3=1))
    K8, s8 = element_matrices(mat8, PShell(1, 0.01, 1, 1, mid3=1))
    for name in ("A", "D", "S", "mass_per_area"):
        np.testing.assert_allclose(getattr(s8, name), getattr(s1, name), rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(K8, K1, rtol=0, atol=1e-12 * np.abs(K1).max())


def test_mat2_equal_matrix_equals_mat1():
    Q = MAT[1].plane_stress()
    g = MAT[1].g
    mats = {1: MAT[1], 2: Mat2(2, Q[0, 0], Q[0, 1], 0.0, Q[1, 1], 0.0, Q[2, 2], RHO),
            3: Mat2(3, g, 0.0, 0.0, g, 0.0, 0.0, RHO)}
    K1, _ = element_matrices(mats, PShell(1, 0.01, 1, 1, mid3=1))
    K2, s2 = element_matrices(mats, PShell(1, 0.01, 2, 2, mid3=3))
    np.testing.assert_allclose(s2.S[0], 0.01 * 5 / 6 * g * np.eye(2), rtol=1e-14)
    np.testing.assert_allclose(K2, K1, rtol=0, atol=1e-12 * np.abs(K1).max())


def test_material_angle_rotates_orthotropy():
    """MAT8 (E1, E2) at theta = 90 deg is MAT8 (E2, E1) at theta = 0 (with G1Z, G2Z swapped)."""
    a = {1: Mat8(1, 3e6, 1e6, 0.3, 4e5, 2e5, 1e5, RHO)}
    b = {1: Mat8(1, 1e6, 3e6, 0.1, 4e5, 1e5, 2e5, RHO)}          # nu21 = 0.3 * 1/3
    sa, sb = (pshell_section(PShell(1, 0.01, 1, 1, mid3=1), m, 1) for m in (a, b))
    Ka, _ = quad4_matrices(QUAD_WARPED[None], sa, np.array([np.pi / 2]))
    Kb, _ = quad4_matrices(QUAD_WARPED[None], sb, np.array([0.0]))
    np.testing.assert_allclose(Ka, Kb, rtol=0, atol=1e-10 * np.abs(Ka).max())


def rotated_plane_stress(Q: np.ndarray, theta: float) -> np.ndarray:
    """Q in element axes for material axis 1 at +theta from element x, by tensor rotation.

    Independent of the kernel's Voigt transformation: each unit engineering strain is turned into a
    2x2 tensor, expressed in material axes (columns of Rm), multiplied by Q and brought back.
    """
    c, s = np.cos(theta), np.sin(theta)
    Rm = np.array([[c, -s], [s, c]])                     # columns: material axes in element axes
    out = np.zeros((3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = 1.0
        eps_el = np.array([[e[0], e[2] / 2], [e[2] / 2, e[1]]])
        eps_m = Rm.T @ eps_el @ Rm
        sig_m_v = Q @ np.array([eps_m[0, 0], eps_m[1, 1], 2 * eps_m[0, 1]])
        sig_m = np.array([[sig_m_v[0], sig_m_v[2]], [sig_m_v[2], sig_m_v[1]]])
        sig_el = Rm @ sig_m @ Rm.T
        out[:, j] = [sig_el[0, 0], sig_el[1, 1], sig_el[0, 1]]
    return out


def test_material_angle_direction():
    """theta = +30 deg (material 1 axis from element x towards y) equals a MAT2 holding the
    tensor-rotated matrices at theta = 0 (membrane, bending and transverse shear)."""
    th = np.deg2rad(30.0)
    mat8 = Mat8(1, 3e6, 1e6, 0.3, 4e5, 2e5, 1e5)
    Qe = rotated_plane_stress(mat8.plane_stress(), th)
    c, s = np.cos(th), np.sin(th)
    Rm = np.array([[c, -s], [s, c]])
    Se = Rm @ np.diag([2e5, 1e5]) @ Rm.T
    mats = {1: mat8, 2: Mat2(2, Qe[0, 0], Qe[0, 1], Qe[0, 2], Qe[1, 1], Qe[1, 2], Qe[2, 2]),
            3: Mat2(3, Se[0, 0], Se[0, 1], 0.0, Se[1, 1], 0.0, 0.0)}
    sec8 = pshell_section(PShell(1, 0.01, 1, 1, mid3=1), mats, 1)
    sec2 = pshell_section(PShell(2, 0.01, 2, 2, mid3=3), mats, 1)
    K8, _ = quad4_matrices(QUAD_WARPED[None], sec8, np.array([th]))
    K2, _ = quad4_matrices(QUAD_WARPED[None], sec2, np.zeros(1))
    np.testing.assert_allclose(K8, K2, rtol=0, atol=1e-10 * np.abs(K2).max())


@pytest.mark.parametrize("kernel,conn", [(quad4_matrices, PATCH_QUADS),
                                         (tria3_matrices, PATCH_TRIAS)], ids=["quad4", "tria3"])
def test_membrane_bending_coupling_energy(kernel, conn):
    """With MID4, the energy of constant (eps, kappa) is area * (eps.A.eps/2 + eps.B.kappa +
    kappa.D.kappa/2) for strains eps(z) = eps0 + z kappa, kappa = -[w,xx, w,yy, 2 w,xy], z along
    the element normal (so the sign of B is checked, not only its size)."""
    xyz = np.column_stack([PATCH_XY, np.zeros(len(PATCH_XY))])
    sec = pshell_section(PShell(1, 0.01, 1, 1, mid3=1, mid4=1), MAT, len(conn))
    K = assemble_patch(kernel, conn, xyz, sec)
    q_m, eps = membrane_field(xyz)
    q_b, w2 = bending_field(xyz)
    kappa = -w2
    q = q_m + q_b
    area = 0.24 * 0.12
    expected = area * (0.5 * eps @ sec.A[0] @ eps + eps @ sec.B[0] @ kappa
                       + 0.5 * kappa @ sec.D[0] @ kappa)
    np.testing.assert_allclose(0.5 * q @ K @ q, expected, rtol=1e-9)
    assert abs(eps @ sec.B[0] @ kappa) > 0.1 * abs(expected)      # the coupling term matters


def test_pshell_semantics():
    mats = {1: MAT[1], 4: MAT[1]}
    membrane = pshell_section(PShell(1, 0.01, mid1=1), mats)
    assert not membrane.D.any() and not membrane.S.any() and not membrane.shear_rigid[0]
    kirchhoff = pshell_section(PShell(1, 0.01, 1, 1, bending_ratio=2.0), mats)
    assert kirchhoff.shear_rigid[0] and not kirchhoff.S.any()
    np.testing.assert_allclose(kirchhoff.D[0], 2.0 * 0.01 ** 3 / 12 * MAT[1].plane_stress())
    coupled = pshell_section(PShell(1, 0.01, 1, 1, mid3=1, shear_ratio=0.5, mid4=4, nsm=0.7), mats)
    np.testing.assert_allclose(coupled.B[0], 0.01 ** 2 * MAT[1].plane_stress())
    np.testing.assert_allclose(coupled.S[0], 0.5 * 0.01 * MAT[1].g * np.eye(2))
    assert coupled.mass_per_area[0] == pytest.approx(RHO * 0.01 + 0.7)
    with pytest.raises(MissingReferenceError, match="MID2 = 9"):
        pshell_section(PShell(1, 0.01, 1, 9), mats)
    with pytest.raises(InputError, match="MID4 requires"):
        PShell(1, 0.01, mid1=1, mid4=4)
    with pytest.raises(InputError, match="thickness"):
        PShell(1, 0.0, 1, 1)


def test_mat1_blank_fields_follow_nastran():
    assert Mat1.from_fields(1, 2.6, None, 0.3).g == pytest.approx(1.0)
    assert Mat1.from_fields(1, None, 1.0, 0.3).e == pytest.approx(2.6)
    assert Mat1.from_fields(1, 2.6, 1.0, None).nu == pytest.approx(0.3)
    blank2 = Mat1.from_fields(1, 2.6, None, None)
    assert (blank2.g, blank2.nu) == (0.0, 0.0)


def test_from_fields_adapters():
    m = material_from_fields(8, "MAT8", {"E1": 3e6, "E2": 1e6, "NU12": 0.3, "G12": 4e5, "RHO": 2.0})
    assert isinstance(m, Mat8) and m.transverse_shear() is None
    p = pshell_from_fields(5, {"T": 0.1, "MID1": 8, "MID2": 8, "MID3": None, "12I/T**3": None})
    sec = pshell_section(p, {8: m})
    assert sec.shear_rigid[0] and p.bending_ratio == 1.0
    with pytest.raises(InputError, match="MAT9"):
        material_from_fields(1, "MAT9", {})


def test_inputs_untouched_and_stacking():
    xyz = np.stack([QUAD_WARPED, QUAD_FLAT])
    xyz.setflags(write=False)
    theta = np.array([0.1, 0.2])
    theta.setflags(write=False)
    sec = stack_sections([section(1), section(1, t=0.02, mid3=None)])
    K, M = quad4_matrices(xyz, sec, theta, lumped=True)
    K_single, _ = quad4_matrices(xyz[1:], sec.take(slice(1, 2)), theta[1:])
    np.testing.assert_array_equal(K[1], K_single[0])
    with pytest.raises(InputError, match="disagree"):
        quad4_matrices(xyz, section(3), theta)


def test_bad_geometry_raises():
    bowtie = QUAD_FLAT[[0, 2, 1, 3]]
    with pytest.raises(InputError, match="Jacobian|degenerate"):
        quad4_matrices(bowtie[None], section(1), np.zeros(1))
    with pytest.raises(InputError, match="collinear"):
        tria3_matrices(np.array([[[0.0, 0, 0], [1, 0, 0], [2, 0, 0]]]), section(1), np.zeros(1))
