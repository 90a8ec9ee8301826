"""Rigid elements: RBE2/RBAR chains move rigidly; RBE3 follows the weighted average motion."""
from __future__ import annotations

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import InputError
from structures.model import RigidElement
from structures.rigid import element_constraints, solve_constraints

BASE = """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,1.,1.,0.
GRID,4,,0.,1.,0.5
GRID,5,,0.5,0.5,0.2
"""


def _model(tmp_path, text):
    path = tmp_path / "r.bdf"
    path.write_text(BASE + text)
    return read_model(path)


def _rigid_motion(grids, q):
    """Basic displacements of every grid for a rigid motion q = (u0, theta) about the origin."""
    u = q[:3] + np.cross(q[3:], grids.xyz)
    return np.hstack([u, np.broadcast_to(q[3:], u.shape)]).ravel()


def test_rbar_chain_reproduces_rigid_motion(tmp_path):
    model = _model(tmp_path, "RBAR,10,1,2,123456,,,123456\nRBAR,11,2,3,123456,,,123456\n")
    n_g = 6 * len(model.grids)
    m_dofs, g_mo = solve_constraints(model.grids, model.rigid, n_g)
    q = np.array([0.1, -0.2, 0.3, 0.02, -0.05, 0.07])
    u = _rigid_motion(model.grids, q)
    np.testing.assert_allclose(g_mo @ u, u[m_dofs], atol=1e-14)
    assert set(m_dofs) == set(range(6, 18))  # grids 2 and 3 dependent, 3 through the chain


def test_rbe3_reference_follows_weighted_average_translation(tmp_path):
    model = _model(tmp_path, "RBE3,20,,5,123,1.0,123,1,2,\n,2.0,123,3,4\n")
    dep, indep, g = element_constraints(model.grids, model.rigid[0])
    u_ind = np.zeros(6 * len(model.grids))
    u_ind[[2, 8, 14, 20]] = [1.0, 1.0, 1.0, 1.0]  # uniform heave of the independent grids
    np.testing.assert_allclose(g @ u_ind[indep], [0.0, 0.0, 1.0], atol=1e-14)
    q = np.array([0.0, 0.0, 0.0, 0.01, 0.02, 0.0])  # a rigid rotation is reproduced exactly
    u = _rigid_motion(model.grids, q)
    np.testing.assert_allclose(g @ u[indep], u[dep], atol=1e-14)


def _weighted_plane_at(xy, weights, w, point):
    """Hand reference: weighted least-squares plane w = a + b x + c y through the data, at point.

    An RBE3 whose independent and dependent components are all T3 reduces to this fit: the rigid
    motion (w0, theta_x, theta_y) gives u_z = w0 + theta_x (y - y_r) - theta_y (x - x_r), a plane.
    """
    basis = np.column_stack([np.ones(len(xy)), xy])
    normal = basis.T @ (weights[:, None] * basis)
    a, b, c = np.linalg.solve(normal, basis.T @ (weights * w))
    return a + b * point[0] + c * point[1]


def test_rbe3_weights_bias_towards_heavier_points(tmp_path):
    # Weight 1 on grid 1, 3 on grids 2, 3, 4; only grid 3 (a corner of the unit square) moves up, so
    # the data are not on a plane and the weights change the fit: by the normal equations written
    # out by hand, [[10, 6, 6], [6, 6, 3], [6, 3, 6]] (a, b, c) = (3, 3, 3) gives a = -1/2,
    # b = c = 2/3 and w(0.5, 0.5) = 1/6; equal weights give the plain average 1/4.
    model = _model(tmp_path, "RBE3,20,,5,3,1.0,3,1,\n,3.0,3,2,3,4\n")
    dep, indep, g = element_constraints(model.grids, model.rigid[0])
    u = np.zeros(6 * len(model.grids))
    u[14] = 1.0  # T3 of grid 3
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    w_data = np.array([0.0, 0.0, 1.0, 0.0])
    reference = _weighted_plane_at(xy, np.array([1.0, 3.0, 3.0, 3.0]), w_data, (0.5, 0.5))
    assert reference == pytest.approx(1.0 / 6.0, abs=1e-14)
    assert _weighted_plane_at(xy, np.ones(4), w_data, (0.5, 0.5)) == pytest.approx(0.25, abs=1e-14)
    np.testing.assert_allclose(g @ u[indep], [1.0 / 6.0], rtol=0, atol=1e-12)


def test_rbar_without_six_independent_dofs_raises(tmp_path):
    bad = RigidElement(1, "RBAR", ((1, "123"),), ((2, "123456"),))
    model = _model(tmp_path, "")
    with pytest.raises(InputError, match="RBAR 1"):
        element_constraints(model.grids, bad)
