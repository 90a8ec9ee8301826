"""Splines: rigid-body reproduction, interpolation at the structural points, bad input."""
from __future__ import annotations

import numpy as np
import pytest

from aero.gaf import spline_matrices
from aero.model import read_aero_model
from aero.splines import beam_weights, ips_weights
from aero_decks import BAH, DATA, wing_grids, write_deck
from structures.common.errors import InputError

RNG = np.random.default_rng(7)
TOL = 1e-10  # exact reproduction up to round-off of the dense solves


def test_ips_reproduces_planes_and_interpolates_grid_values():
    """H&D IPS: any plane w = a + b x + c y is reproduced exactly (also with DZ > 0), DZ = 0
    interpolates arbitrary grid values at the grids; slopes agree with finite differences."""
    g = RNG.uniform(0.0, 10.0, (15, 2))
    p = RNG.uniform(-3.0, 13.0, (40, 2))
    plane = 0.7 - 0.3 * g[:, 0] + 1.1 * g[:, 1]
    for dz in (0.0, 2.5):
        W, Wx, Wy = ips_weights(g, p, dz)
        np.testing.assert_allclose(W @ plane, 0.7 - 0.3 * p[:, 0] + 1.1 * p[:, 1], atol=TOL)
        np.testing.assert_allclose(Wx @ plane, -0.3, atol=TOL)
        np.testing.assert_allclose(Wy @ plane, 1.1, atol=TOL)
    W, _, _ = ips_weights(g, g, 0.0)
    np.testing.assert_allclose(W, np.eye(len(g)), atol=TOL)
    values = RNG.normal(size=len(g))
    Ws, _, _ = ips_weights(g, g, 50.0)  # smoothing: no longer interpolates
    assert np.abs(Ws @ values - values).max() > 1e-3
    h = 1e-6
    W0, Wx, Wy = ips_weights(g, p, 0.0)
    np.testing.assert_allclose((ips_weights(g, p + [h, 0], 0.0)[0] - W0) / h, Wx, atol=1e-5)
    np.testing.assert_allclose((ips_weights(g, p + [0, h], 0.0)[0] - W0) / h, Wy, atol=1e-5)


@pytest.mark.parametrize("dthx,dthy,dz", [(0.0, 0.0, 0.0), (-1.0, 0.0, 0.0), (0.0, -1.0, 0.0),
                                          (0.3, 0.2, 0.5)])
def test_beam_spline_reproduces_rigid_motion(dthx, dthy, dz):
    """Plunge z0, roll phi (Z = phi y, slope phi) and pitch theta (rotation about the axis:
    h = -x theta, dh/dx = -theta) are reproduced exactly whatever is attached and smoothed
    (pitch only when the twist is attached)."""
    y = np.array([0.0, 2.0, 4.5, 7.0, 9.3])
    p = np.column_stack([RNG.uniform(-2, 3, 30), RNG.uniform(-1, 12, 30)])
    z0, phi, theta = 0.4, 0.3, -0.2
    u = np.stack([z0 + phi * y, np.full(5, phi), np.full(5, theta)], axis=-1)  # (n, 3)
    W, Wx, Wy = beam_weights(y, p, dz=dz, dthx=dthx, dthy=dthy)
    th = theta if dthy >= 0 else 0.0
    np.testing.assert_allclose(np.einsum("mnc,nc->m", W, u), z0 + phi * p[:, 1] - p[:, 0] * th,
                               atol=TOL)
    np.testing.assert_allclose(np.einsum("mnc,nc->m", Wx, u), -th, atol=TOL)
    np.testing.assert_allclose(np.einsum("mnc,nc->m", Wy, u), phi, atol=TOL)


def test_beam_spline_interpolates_at_grids():
    """With zero flexibilities the beam passes through the grids' deflections, slopes and twists."""
    y = np.array([0.0, 2.0, 4.5, 7.0])
    x = 0.7
    W, Wx, Wy = beam_weights(y, np.column_stack([np.full(4, x), y]))
    np.testing.assert_allclose(W[:, :, 0], np.eye(4), atol=TOL)          # h <- Z_i
    np.testing.assert_allclose(Wy[:, :, 1], np.eye(4), atol=TOL)         # dh/dy <- rotation about x
    np.testing.assert_allclose(Wx[:, :, 2], -np.eye(4), atol=TOL)        # dh/dx <- -twist
    np.testing.assert_allclose(W[:, :, 2], -x * np.eye(4), atol=TOL)


def _rigid_dofs(grid, component, xyz_of, t=(0.0, 0.0, 0.0), r=(0.0, 0.0, 0.0), about=(0, 0, 0)):
    """Basic-frame rigid displacement u = t + r x (p - about), rotation r, at (grid, component)."""
    out = np.empty(len(grid))
    for i, (g, c) in enumerate(zip(grid, component)):
        u = np.asarray(t) + np.cross(r, xyz_of[int(g)] - np.asarray(about))
        out[i] = u[c - 1] if c <= 3 else r[c - 4]
    return out


def _xyz_of(model):
    return {int(g): p for s in model.splines for g, p in zip(s.grid_ids, s.grid_xyz)}


def test_bah_plane_splines_rigid_plunge_and_pitch():
    """BAH deck (ACSID = CORD2R 2 with x and z flipped, tail SPLINE2 with CID 3 and DZ = 1):
    plunge dz = 1 in basic gives h = -1 along the aero normal (-z basic) on every box; a pitch
    theta about basic y through grid 1 gives h = theta * x_basic and dh/dx_aero = -theta."""
    m = read_aero_model(BAH)
    G = spline_matrices(m)
    xyz = _xyz_of(m)
    plunge = _rigid_dofs(G.grid, G.component, xyz, t=(0, 0, 1.0))
    np.testing.assert_allclose(G.h_colloc @ plunge, -1.0, atol=TOL)
    np.testing.assert_allclose(G.h_load @ plunge, -1.0, atol=TOL)
    np.testing.assert_allclose(G.slope_colloc @ plunge, 0.0, atol=TOL)
    theta = 0.01
    pitch = _rigid_dofs(G.grid, G.component, xyz, r=(0, theta, 0))
    xb_c = m.to_basic(m.mesh.collocation)[:, 0]
    xb_l = m.to_basic(0.5 * (m.mesh.doublet_in + m.mesh.doublet_out))[:, 0]
    np.testing.assert_allclose(G.h_colloc @ pitch, theta * xb_c, atol=TOL)
    np.testing.assert_allclose(G.h_load @ pitch, theta * xb_l, atol=TOL)
    np.testing.assert_allclose(G.slope_colloc @ pitch, -theta, atol=TOL)


@pytest.mark.parametrize("deck", ["pt145/pt145.bdf", "two_mode_flutter/0012_flutter.bdf"])
def test_validation_decks_splines_rigid_motion(deck):
    """PT145 (SPLINE2 along a 15-degree swept CID 1 axis, CAERO1 in CP 1) and the two-mode plate
    (SPLINE1 on 116 grids): any rigid rotation about an arbitrary point is reproduced exactly."""
    m = read_aero_model(DATA / deck)
    G = spline_matrices(m)
    xyz = _xyz_of(m)
    rot, about = np.array([0.011, -0.02, 0.007]), np.array([0.3, -1.2, 0.4])
    u = _rigid_dofs(G.grid, G.component, xyz, t=(0.0, 0.0, 0.05), r=rot, about=about)
    c = m.to_basic(m.mesh.collocation)
    n = m.mesh.normal @ m.aero_frame.axes
    h = np.einsum("bi,bi->b", 0.05 * np.array([0, 0, 1.0]) + np.cross(rot, c - about), n)
    np.testing.assert_allclose(G.h_colloc @ u, h, atol=TOL)
    flow = m.aero_frame.axes[0]
    np.testing.assert_allclose(G.slope_colloc @ u, np.cross(rot, flow) @ n.T, atol=TOL)


def _ips_deck(tmp_path, set_line, extra=""):
    bulk = "\n".join([wing_grids(), "PAERO1,1", "CAERO1,101,1,0,6,4,,,1\n,0.,0.,0.,2.,0.,6.,0.,2.",
                      set_line, "SPLINE1,201,101,101,124,5,0.", extra])
    return read_aero_model(write_deck(tmp_path / "ips.bdf", bulk))


def test_spline1_rigid_body_and_usage(tmp_path):
    """SPLINE1 through the model: plunge, pitch about y (slope = -angle) and roll about x
    (h = phi y) are exact; a USAGE=FORCE spline leaves the downwash rows zero."""
    m = _ips_deck(tmp_path, "SET1,5,1,THRU,12")
    G = spline_matrices(m)
    xyz = _xyz_of(m)
    c, load = m.mesh.collocation, 0.5 * (m.mesh.doublet_in + m.mesh.doublet_out)
    plunge = _rigid_dofs(G.grid, G.component, xyz, t=(0, 0, 0.2))
    np.testing.assert_allclose(G.h_colloc @ plunge, 0.2, atol=TOL)
    pitch = _rigid_dofs(G.grid, G.component, xyz, r=(0, 0.05, 0), about=(0.5, 0, 0))
    np.testing.assert_allclose(G.h_colloc @ pitch, -0.05 * (c[:, 0] - 0.5), atol=TOL)
    np.testing.assert_allclose(G.h_load @ pitch, -0.05 * (load[:, 0] - 0.5), atol=TOL)
    np.testing.assert_allclose(G.slope_colloc @ pitch, -0.05, atol=TOL)
    roll = _rigid_dofs(G.grid, G.component, xyz, r=(0.03, 0, 0))
    np.testing.assert_allclose(G.h_colloc @ roll, 0.03 * c[:, 1], atol=TOL)
    np.testing.assert_allclose(G.slope_colloc @ roll, 0.0, atol=TOL)
    mf = read_aero_model(write_deck(tmp_path / "f.bdf", "\n".join([
        wing_grids(), "PAERO1,1", "CAERO1,101,1,0,6,4,,,1\n,0.,0.,0.,2.,0.,6.,0.,2.",
        "SET1,5,1,THRU,12", "SPLINE1,201,101,101,124,5,0.,IPS,FORCE"])))
    Gf = spline_matrices(mf)
    assert np.all(Gf.h_colloc == 0) and np.all(Gf.slope_colloc == 0)
    np.testing.assert_allclose(Gf.h_load @ plunge, 0.2, atol=TOL)


def test_spline1_interpolates_structural_values_at_their_positions(tmp_path):
    """Boxes whose collocation points coincide with structural grids get exactly the grids' T3."""
    grids = "\n".join(f"GRID,{i + 1},,{x:.6f},{y:.6f},0." for i, (x, y) in enumerate(
        [(0.375, 0.5), (1.375, 1.5), (0.875, 2.5), (1.875, 3.5), (0.375, 4.5), (1.375, 5.5)]))
    bulk = "\n".join([grids, "PAERO1,1", "CAERO1,101,1,0,6,4,,,1\n,0.,0.,0.,2.,0.,6.,0.,2.",
                      "SET1,5,1,THRU,6", "SPLINE1,201,101,101,124,5,0."])
    m = read_aero_model(write_deck(tmp_path / "i.bdf", bulk))
    G = spline_matrices(m)
    t3 = RNG.normal(size=6)
    u = np.zeros(G.grid.size)
    u[G.component == 3] = t3
    u[G.component != 3] = RNG.normal(size=int(np.sum(G.component != 3)))  # ignored by the IPS
    h = G.h_colloc @ u
    for gid, value in zip(range(1, 7), t3):
        hit = np.flatnonzero(np.all(np.isclose(m.mesh.collocation[:, :2],
                                               m.splines[0].grid_xyz[gid - 1, :2]), axis=1))
        assert hit.size == 1
        np.testing.assert_allclose(h[hit[0]], value, atol=TOL)


def test_spline_without_points_in_reach_raises(tmp_path):
    """Two grids (or grids on one line) cannot carry an infinite-plate spline; the error names
    the spline."""
    m = _ips_deck(tmp_path, "SET1,5,1,2")
    with pytest.raises(InputError, match=r"SPLINE1 201.*2 structural point"):
        spline_matrices(m)
    m = _ips_deck(tmp_path, "SET1,5,1,4,7,10")  # x = -0.2 at y = 0, 2, 4, 6: one line
    with pytest.raises(InputError, match=r"SPLINE1 201.*on one line"):
        spline_matrices(m)
