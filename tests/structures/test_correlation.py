"""Tests of structures.correlation: MAC, SEREP (paper eqs. 11-14, 20, 23), correlation Dataset.

The analysis model is a free-free 3D beam frame built here with numpy (fuselage, wing and tail with
ribs, lumped engine and gear masses; 101 grids, 606 DOFs), so every reference is computed
independently: the full mass matrix M is known, and SEREP results are compared with the exact
Phi^T M Phi products. The same frame is also written as a Nastran deck and run through
structures.bdf.read_model + structures.modal.compute_modes for the perturbed-model test.
"""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import xarray as xr

from structures.acceptance import MIL_STD_1540C, NASA_STD_5002
from structures.correlation import (CorrelationSettings, correlate, cross_orthogonality, expand_test_shapes,
                                    mac, orthogonality, serep_coordinates, serep_expand, serep_mass)
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset


# ------------------------------------------------------------------------------- synthetic model
def _beam_k(xa, xb, E, G, A, Iy, Iz, J):
    """12x12 Euler-Bernoulli 3D beam stiffness in the basic frame (Przemieniecki)."""
    d = xb - xa
    L = np.linalg.norm(d)
    ex = d / L
    ref = np.array([0.0, 0.0, 1.0]) if abs(ex[2]) < 0.9 else np.array([1.0, 0.0, 0.0])
    ey = np.cross(ref, ex)
    ey /= np.linalg.norm(ey)
    ez = np.cross(ex, ey)
    k = np.zeros((12, 12))
    for (i, j), v in {(0, 0): E * A / L, (3, 3): G * J / L}.items():
        k[np.ix_([i, i + 6], [j, j + 6])] += v * np.array([[1, -1], [-1, 1]])
    bz = E * Iz / L**3 * np.array([[12, 6 * L, -12, 6 * L], [6 * L, 4 * L**2, -6 * L, 2 * L**2],
                                    [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L**2, -6 * L, 4 * L**2]])
    by = E * Iy / L**3 * np.array([[12, -6 * L, -12, -6 * L], [-6 * L, 4 * L**2, 6 * L, 2 * L**2],
                                    [-12, 6 * L, 12, 6 * L], [-6 * L, 2 * L**2, 6 * L, 4 * L**2]])
    k[np.ix_([1, 5, 7, 11], [1, 5, 7, 11])] += bz
    k[np.ix_([2, 4, 8, 10], [2, 4, 8, 10])] += by
    R = np.vstack([ex, ey, ez])
    T = scipy.linalg.block_diag(R, R, R, R)
    return T.T @ k @ T, L


E_MOD, G_MOD, RHO, NSM = 70e9, 27e9, 2700.0, 2.0   # SI; NSM = non-structural mass per length


def frame_geometry(wing_bending=1.0, wing_torsion=1.0, gear_mass=1.0):
    """Free-free aircraft-like beam frame: fuselage along x; wing and horizontal tail along +-y with
    stiff chordwise ribs carrying leading/trailing-edge grids (so that torsion shows in
    translations); engine and gear masses. 101 grids, ids 10, 20, ...

    Returns a dict: xyz (n, 3), elems [(a, b, prop)], props {prop: A/Iy/Iz/J} (Iy: vertical
    bending of the wing), lumped [(node, mass)], groups {name: grid ids} for sensor placement.
    """
    xyz, elems = [], []

    def node(p):
        xyz.append(np.asarray(p, dtype=float))
        return len(xyz) - 1

    props = {"fus": dict(A=5e-3, Iy=4e-5, Iz=4e-5, J=8e-5),
             "wing": dict(A=3e-3, Iy=1.2e-6 * wing_bending, Iz=2e-5, J=2.4e-6 * wing_torsion),
             "tail": dict(A=1e-3, Iy=3e-7, Iz=3e-6, J=5e-7),
             "rib": dict(A=1e-3, Iy=2e-5, Iz=2e-5, J=2e-5)}
    fus = [node((x, 0.0, 0.0)) for x in np.linspace(0.0, 10.0, 11)]
    elems += [(a, b, "fus") for a, b in zip(fus[:-1], fus[1:])]
    surfaces = {"wing": (fus[4], 4.0, 0.0, np.linspace(1.0, 12.0, 12), 0.6),
                "tail": (fus[10], 10.0, 0.5, np.array([1.0, 2.0, 3.0]), 0.3)}
    edges, axes = {"wing": [], "tail": []}, {"wing": [], "tail": []}
    for key, (root, x0, z0, span, half_chord) in surfaces.items():
        for side in (1.0, -1.0):
            prev = root
            for y in span:
                axis = node((x0, side * y, z0))
                le, te = node((x0 - half_chord, side * y, z0)), node((x0 + half_chord, side * y, z0))
                elems += [(prev, axis, key), (le, axis, "rib"), (axis, te, "rib")]
                axes[key].append(axis)
                edges[key] += [le, te]
                prev = axis
    lumped = [(axes["wing"][4], 60.0), (axes["wing"][16], 60.0), (fus[2], 25.0 * gear_mass),
              (axes["wing"][1], 15.0 * gear_mass), (axes["wing"][13], 15.0 * gear_mass)]
    grids = (np.arange(len(xyz)) + 1) * 10
    groups = {"fuselage": grids[fus], "wing_axis": grids[axes["wing"]], "tail_axis": grids[axes["tail"]],
              "edges": grids[edges["wing"] + edges["tail"]]}
    return dict(xyz=np.array(xyz), elems=elems, props=props, lumped=lumped, grids=grids, groups=groups)


def frame_model(**factors):
    """K, M (6n x 6n, lumped mass with rotary inertia), grid ids (n,), xyz (n, 3) of the frame."""
    geo = frame_geometry(**factors)
    xyz = geo["xyz"]
    n = xyz.shape[0]
    K, M = np.zeros((6 * n, 6 * n)), np.zeros((6 * n, 6 * n))
    for a, b, name in geo["elems"]:
        p = geo["props"][name]
        ke, L = _beam_k(xyz[a], xyz[b], E_MOD, G_MOD, **p)
        idx = np.r_[6 * a:6 * a + 6, 6 * b:6 * b + 6]
        K[np.ix_(idx, idx)] += ke
        m = RHO * p["A"] * L / 2 + NSM * L / 2
        ex = (xyz[b] - xyz[a]) / L
        rot = m * L**2 / 12 * (np.eye(3) - np.outer(ex, ex)) + m * (p["Iy"] + p["Iz"]) / p["A"] * np.outer(ex, ex)
        for nd in (a, b):
            M[6 * nd + np.arange(3), 6 * nd + np.arange(3)] += m
            M[np.ix_(6 * nd + np.arange(3, 6), 6 * nd + np.arange(3, 6))] += rot
    for nd, mass in geo["lumped"]:
        M[6 * nd + np.arange(3), 6 * nd + np.arange(3)] += mass
    return K, M, geo["grids"], xyz


def write_frame_deck(path, **factors):
    """The same frame as a Nastran deck (CBAR/PBAR/MAT1/CONM2, coupled mass), for read_model."""
    geo = frame_geometry(**factors)
    pid = {name: i + 1 for i, name in enumerate(geo["props"])}
    lines = ["SOL 103", "CEND", "BEGIN BULK", "PARAM,COUPMASS,1", f"MAT1,1,{E_MOD:.6e},{G_MOD:.6e},,{RHO}"]
    lines += [f"GRID,{g},,{x:.6f},{y:.6f},{z:.6f}" for g, (x, y, z) in zip(geo["grids"], geo["xyz"])]
    # Nastran CBAR with v = basic z: plane 1 is vertical for wing/tail/fuselage, so I1 = vertical bending
    lines += [f"PBAR,{pid[n]},1,{p['A']:.6e},{p['Iy']:.6e},{p['Iz']:.6e},{p['J']:.6e},{NSM}"
              for n, p in geo["props"].items()]
    lines += [f"CBAR,{k + 1},{pid[n]},{geo['grids'][a]},{geo['grids'][b]},0.,0.,1."
              for k, (a, b, n) in enumerate(geo["elems"])]
    lines += [f"CONM2,{1000 + k},{geo['grids'][nd]},,{m:.6e}" for k, (nd, m) in enumerate(geo["lumped"])]
    lines.append("ENDDATA")
    path.write_text("\n".join(lines) + "\n")
    return path


def modes_dataset(K, M, grids, xyz, nmodes):
    """Mass-normalised modes Dataset in the layout of DESIGN.md section 6."""
    lam, phi = scipy.linalg.eigh(K, M, subset_by_index=[0, nmodes - 1])
    n = grids.size
    return xr.Dataset(
        {"frequency": (("mode",), np.sqrt(np.abs(lam)) / (2 * np.pi), {"units": "Hz"}),
         "shape": (("mode", "dof"), phi.T), "generalized_mass": (("mode",), np.ones(nmodes))},
        coords={"mode": np.arange(1, nmodes + 1), "grid": ("dof", np.repeat(grids, 6)),
                "component": ("dof", np.tile(np.arange(1, 7), n)), "x": ("dof", np.repeat(xyz[:, 0], 6)),
                "y": ("dof", np.repeat(xyz[:, 1], 6)), "z": ("dof", np.repeat(xyz[:, 2], 6))},
        attrs={"source": "test frame", "deck": "frame", "units": "SI"})


def gvt_from(modes, modes_sel, dof_sel, *, rng=None, f_noise=0.0, s_noise=0.0, scale=None):
    """A 'measured' GVT Dataset from chosen modes and DOFs, with optional noise and scaling."""
    sub = modes.sel(mode=modes_sel).isel(dof=dof_sel)
    shape = sub["shape"].values.copy()
    freq = sub["frequency"].values.copy()
    if rng is not None:
        freq = freq * (1 + f_noise * rng.standard_normal(freq.size))
        rms = np.sqrt(np.mean(shape**2, axis=1, keepdims=True))
        shape = shape + s_noise * rms * rng.standard_normal(shape.shape)
    if scale is not None:
        shape = shape * np.asarray(scale)[:, None]
    return make_gvt_dataset(freq, shape, sub["grid"].values, sub["component"].values, mode=modes_sel,
                            damping=np.full(freq.size, 0.01), source="synthetic")


def sensors_120(modes):
    """120 measured DOFs: z at the 60 edge grids, x/y/z at the 11 fuselage grids, x at the 24 wing-axis
    grids and y at 3 tail-axis grids."""
    comp, grid = modes["component"].values, modes["grid"].values
    sg = frame_geometry()["groups"]
    pick = ((np.isin(grid, sg["edges"]) & (comp == 3)) | (np.isin(grid, sg["fuselage"]) & (comp <= 3))
            | (np.isin(grid, sg["wing_axis"]) & (comp == 1)) | (np.isin(grid, sg["tail_axis"][:3]) & (comp == 2)))
    idx = np.nonzero(pick)[0]
    assert idx.size == 120
    return idx


@pytest.fixture(scope="module")
def base():
    K, M, grids, xyz = frame_model()
    return K, M, modes_dataset(K, M, grids, xyz, 30)


FLEX = list(range(7, 21))  # the 14 lowest flexible modes act as the test modes


# ------------------------------------------------------------------------------------ kernels
def test_mac_analytic_values():
    a = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    b = np.array([[1.0, 1.0], [1.0, 0.0], [0.0, 0.0]])
    np.testing.assert_allclose(mac(a, b), [[0.5, 1.0], [0.5, 0.0]], atol=1e-15)
    np.testing.assert_allclose(mac(a, -3.0 * b), mac(a, b), atol=1e-15)


def test_serep_mass_reproduces_modal_orthogonality(base):
    """Phi^T M_A Phi = I for the SEREP modes (eqs. 12-13), and M_A is symmetric PSD of rank m."""
    _, _, modes = base
    phi = modes["shape"].values[:12].T
    m_a = serep_mass(phi)
    np.testing.assert_allclose(phi.T @ m_a @ phi, np.eye(12), atol=1e-10)
    np.testing.assert_allclose(m_a, m_a.T, atol=1e-12 * np.abs(m_a).max())
    assert np.linalg.matrix_rank(m_a) == 12


def test_serep_all_dofs_measured_reproduces_modes_exactly(base):
    _, _, modes = base
    phi = modes["shape"].values.T
    expanded = serep_expand(phi, np.arange(phi.shape[0]), phi[:, 6:20])
    np.testing.assert_allclose(expanded, phi[:, 6:20], atol=1e-12 * np.abs(phi).max())


def test_serep_sensor_subset_returns_own_modes(base):
    _, _, modes = base
    gvt = gvt_from(modes, FLEX, sensors_120(modes))
    expanded = expand_test_shapes(modes, gvt)
    ref = modes.sel(mode=FLEX)["shape"].values
    assert np.abs(expanded["shape"].values - ref).max() <= 1e-10 * np.abs(ref).max()


def test_self_correlation_is_identity(base):
    _, _, modes = base
    gvt = gvt_from(modes, FLEX, sensors_120(modes), scale=np.linspace(0.5, 3.0, len(FLEX)))
    corr = correlate(modes, gvt)
    np.testing.assert_allclose(corr["orthogonality"].values, np.eye(len(FLEX)), atol=1e-10)
    s = corr["cross_orthogonality"].sel(fe_mode=FLEX).values
    np.testing.assert_allclose(s, np.eye(len(FLEX)), atol=1e-10)
    others = corr["cross_orthogonality"].drop_sel(fe_mode=FLEX).values
    assert np.abs(others).max() < 1e-10
    np.testing.assert_array_equal(corr["paired_fe_mode"].values, FLEX)
    np.testing.assert_allclose(corr["frequency_error"].values, 0.0, atol=1e-10)
    np.testing.assert_allclose(corr["paired_mac"].values, 1.0, atol=1e-12)
    assert corr["pass_all"].values.all()
    # the raw generalised mass is the square of the scale applied to the unit-mass shapes
    np.testing.assert_allclose(corr["test_generalized_mass"].values, np.linspace(0.5, 3.0, len(FLEX))**2,
                               rtol=1e-10)


def test_normalisation_of_eq20_against_explicit_serep_mass(base):
    """Normalised S_ij = Phi_GAset_i^T M_A Phi_j / sqrt(M_ii (Phi_j^T M_A Phi_j)), formed explicitly."""
    K, M, _ = base
    Kp, Mp, grids, xyz = frame_model(wing_bending=1.1, gear_mass=1.3)
    modes = modes_dataset(K, M, grids, xyz, 24)
    test = modes_dataset(Kp, Mp, grids, xyz, 24)
    sens = sensors_120(modes)
    gvt = gvt_from(test, FLEX, sens, scale=np.linspace(-2.0, 5.0, len(FLEX)))
    corr = correlate(modes, gvt)
    phi_a = modes["shape"].values.T
    m_a = serep_mass(phi_a)                                       # eqs. 12-13, n_AD x n_AD
    phi_ga = serep_expand(phi_a, sens, gvt["shape"].values.T)     # eq. 14
    m_bar = phi_ga.T @ m_a @ phi_ga                               # eq. 11
    s_bar = phi_ga.T @ m_a @ phi_a                                # eq. 20
    d = np.sqrt(np.diag(m_bar))
    np.testing.assert_allclose(corr["orthogonality"].values, m_bar / np.outer(d, d), atol=1e-9)
    dn = np.sqrt(np.diag(phi_a.T @ m_a @ phi_a))
    np.testing.assert_allclose(corr["cross_orthogonality"].values, s_bar / np.outer(d, dn), atol=1e-9)
    # the A-set choice changes nothing in M and S (Phi_g Phi_Aset = I)
    corr_t = correlate(modes, gvt, CorrelationSettings(a_set="translational"))
    np.testing.assert_allclose(corr_t["cross_orthogonality"].values, corr["cross_orthogonality"].values,
                               atol=1e-9)
    np.testing.assert_allclose(corr_t["orthogonality"].values, corr["orthogonality"].values, atol=1e-9)
    # the kernels used on their own agree too
    q = serep_coordinates(phi_a[sens], gvt["shape"].values.T)
    np.testing.assert_allclose(orthogonality(q)[0], corr["orthogonality"].values, atol=1e-12)
    np.testing.assert_allclose(cross_orthogonality(q, np.eye(24)), corr["cross_orthogonality"].values, atol=1e-12)


def test_sign_flip_changes_neither_pairing_nor_mac(base):
    _, _, modes = base
    sens = sensors_120(modes)
    flips = np.where(np.arange(len(FLEX)) % 3 == 0, -1.0, 1.0)
    ref = correlate(modes, gvt_from(modes, FLEX, sens))
    flipped = correlate(modes, gvt_from(modes, FLEX, sens, scale=flips))
    np.testing.assert_array_equal(flipped["paired_fe_mode"].values, ref["paired_fe_mode"].values)
    np.testing.assert_allclose(flipped["mac"].values, ref["mac"].values, atol=1e-12)
    s = flipped["cross_orthogonality"].sel(fe_mode=FLEX).values
    np.testing.assert_allclose(np.diag(s), flips, atol=1e-10)   # the sign is kept in S


def test_swapped_close_modes_are_paired_and_flagged(base):
    """Close test modes 16/17 (4.55/4.57 Hz) given each other's shapes, as in the paper's 12/13
    interchange."""
    _, _, modes = base
    sens = sensors_120(modes)
    gvt = gvt_from(modes, FLEX, sens)
    shape = gvt["shape"].values.copy()
    i, j = FLEX.index(16), FLEX.index(17)
    shape[[i, j]] = shape[[j, i]]
    swapped = gvt.copy(data={**{k: v.values for k, v in gvt.data_vars.items()}, "shape": shape})
    for pair_by in ("mac", "cross_orthogonality"):
        corr = correlate(modes, swapped, CorrelationSettings(pair_by=pair_by))
        expect = np.array(FLEX)
        expect[[i, j]] = [17, 16]
        np.testing.assert_array_equal(corr["paired_fe_mode"].values, expect)
        assert corr["interchanged"].sel(test_mode=[16, 17]).values.all()
        assert not corr["interchanged"].drop_sel(test_mode=[16, 17]).values.any()
        assert corr.attrs["interchanges"] == "16<->17"


def test_a_test_mode_resembling_a_rigid_mode_is_paired_with_an_elastic_one(base):
    """Test mode 12's shape replaced by 0.8 rigid mode 2 + 0.6 of itself (a poorly measured mode
    with a rigid-body component): its best MAC is the rigid mode's, but a rigid-body mode has no
    elastic test counterpart. With the rigid modes named (``rigid_motion``, as compute_modes
    names them) it pairs with its elastic self; without the names every mode is a candidate and
    it takes the 0 Hz mode, a 100 % frequency error (the stage-1 efew report of the example)."""
    _, _, modes = base
    sens = sensors_120(modes)
    gvt = gvt_from(modes, FLEX, sens)
    shape = gvt["shape"].values.copy()
    i = FLEX.index(12)
    own, rigid = (modes["shape"].sel(mode=m).values[sens] for m in (12, 2))
    shape[i] = (0.8 * rigid / np.linalg.norm(rigid) + 0.6 * own / np.linalg.norm(own))
    mixed = gvt.copy(data={**{k: v.values for k, v in gvt.data_vars.items()}, "shape": shape})
    names = np.array(["x", "y", "z", "rx", "ry", "rz"] + [""] * (modes.sizes["mode"] - 6))
    named = modes.assign_coords(rigid_motion=("mode", names))
    corr = correlate(named, mixed)
    np.testing.assert_array_equal(corr["paired_fe_mode"].values, FLEX)
    assert abs(float(corr["frequency_error"].sel(test_mode=12))) < 1e-9
    unnamed = correlate(modes, mixed)
    assert int(unnamed["paired_fe_mode"].sel(test_mode=12)) == 2
    assert float(unnamed["frequency_error"].sel(test_mode=12)) == pytest.approx(-100.0, abs=0.01)


# ---------------------------------------------------------------------------------- bad input
def test_fewer_measured_dofs_than_serep_modes_raises(base):
    _, _, modes = base
    gvt = gvt_from(modes, FLEX, sensors_120(modes)[:20])
    with pytest.raises(InputError, match=r"20 DOFs but 30 modes"):
        correlate(modes, gvt)


def test_rank_deficient_sensor_set_raises(base):
    _, _, modes = base
    only_x_on_fuselage = np.nonzero((modes["component"].values == 1) & (modes["grid"].values <= 110))[0]
    gvt = gvt_from(modes, [7, 8], only_x_on_fuselage)
    with pytest.raises(InputError, match="rank-deficient"):
        correlate(modes, gvt, CorrelationSettings(serep_modes=tuple(range(1, 10))))


def test_unknown_node_raises_naming_it(base):
    _, _, modes = base
    gvt = gvt_from(modes, FLEX, sensors_120(modes))
    grid = gvt["grid"].values.copy()
    grid[grid == 20] = 99999
    bad = make_gvt_dataset(gvt["frequency"].values, gvt["shape"].values, grid, gvt["component"].values,
                           mode=FLEX, source="bad.unv")
    with pytest.raises(InputError, match=r"bad.unv: nodes \[99999\] are not grids of the model"):
        correlate(modes, bad)


# ------------------------------------------------------------------- perturbed-model synthetic GVT
@pytest.fixture(scope="module", params=["numpy", "deck"])
def perturbed(request, base, tmp_path_factory):
    """'Test article': wing vertical bending stiffness +8 %, wing torsion -7 %, gear masses +25 %.

    ``numpy``: the frame assembled in this file; ``deck``: the frame written as a Nastran deck with
    the perturbed PBAR/CONM2 values and run through read_model + compute_modes (coupled mass).
    Truth (no SEREP, no noise): the test modes' cross-orthogonality and orthogonality with the
    analysis model's FULL mass matrix, S = Phi_p^T M Phi_A and O = Phi_p^T M Phi_p, Phi_p scaled
    to unit generalised mass in M.
    """
    factors = dict(wing_bending=1.08, wing_torsion=0.93, gear_mass=1.25)
    if request.param == "numpy":
        K, M, modes = base
        Kp, Mp, grids, xyz = frame_model(**factors)
        truth = modes_dataset(Kp, Mp, grids, xyz, 30)
    else:
        from structures.assembly import assemble
        from structures.bdf import read_model
        from structures.modal import compute_modes
        folder = tmp_path_factory.mktemp("decks")
        model = read_model(write_frame_deck(folder / "analysis.bdf"))
        system = assemble(model, "deck")
        modes = compute_modes(model, 30, system=system)
        M = system.m_basic
        truth = compute_modes(read_model(write_frame_deck(folder / "test_article.bdf", **factors)), 30)
    pp = truth.sel(mode=FLEX)["shape"].values.T
    pp = pp / np.sqrt(np.diag(pp.T @ (M @ pp)))
    s_true = pp.T @ (M @ modes["shape"].values.T)
    o_true = pp.T @ (M @ pp)
    pair_true = np.abs(s_true).argmax(axis=1) + 1
    assert np.unique(pair_true).size == len(FLEX)             # a one-to-one correspondence
    return modes, truth, s_true, o_true, pair_true, request.param


def _expected_flags(modes, f_test, s_true, o_true, pair_true, primary):
    """Pass/fail of the two standard checks from the truth, without the library."""
    f_err = 100.0 * (modes["frequency"].values[pair_true - 1] - f_test) / f_test
    sp = np.abs(s_true[:, pair_true - 1])
    off = sp - np.diag(np.diag(sp))
    s_off = np.maximum(off.max(axis=1), off.max(axis=0))
    o_off = np.abs(o_true - np.diag(np.diag(o_true))).max(axis=1)
    out = {}
    for c in (MIL_STD_1540C, NASA_STD_5002):
        f_lim = np.where(primary, c.frequency_primary, c.frequency_secondary)
        out[c.name] = {"pass_frequency": (np.abs(f_err) <= f_lim, np.abs(np.abs(f_err) - f_lim)),
                       "pass_cross_orthogonality_diagonal": (np.diag(sp) >= c.cross_orthogonality_diagonal,
                                                             np.abs(np.diag(sp) - c.cross_orthogonality_diagonal)),
                       "pass_cross_orthogonality_off_diagonal": (s_off <= c.cross_orthogonality_off_diagonal,
                                                                 np.abs(s_off - c.cross_orthogonality_off_diagonal)),
                       "pass_orthogonality": (o_off <= c.orthogonality_off_diagonal,
                                              np.abs(o_off - c.orthogonality_off_diagonal))}
    return f_err, out


def test_perturbed_model_noise_free_matches_truth(perturbed):
    """SEREP with 120 DOFs and 30 modes reproduces the full-mass truth to 1e-3; every check flag
    whose truth value is more than 1e-3 from its limit is exactly as the truth says."""
    modes, truth, s_true, o_true, pair_true, _ = perturbed
    gvt = gvt_from(truth, FLEX, sensors_120(modes))
    primary = np.isin(FLEX, FLEX[:7])
    corr = correlate(modes, gvt, primary_modes=FLEX[:7])
    np.testing.assert_array_equal(corr["paired_fe_mode"].values, pair_true)
    # interchange: a later test mode paired with an earlier analysis mode (e.g. 15/16/17 in "numpy")
    inverted = pair_true[:, None] > pair_true[None, :]
    upper = np.triu(inverted, 1)
    np.testing.assert_array_equal(corr["interchanged"].values, upper.any(axis=1) | upper.any(axis=0))
    f_err, flags = _expected_flags(modes, gvt["frequency"].values, s_true, o_true, pair_true, primary)
    np.testing.assert_allclose(corr["frequency_error"].values, f_err, atol=1e-10)
    assert np.abs(corr["cross_orthogonality"].values - s_true).max() < 1e-3
    assert np.abs(corr["orthogonality"].values - o_true).max() < 1e-3
    # the gear-mass change makes the test modes non-orthogonal in the analysis mass: ~1e-2 terms
    assert 5e-3 < np.abs(o_true - np.eye(len(FLEX))).max() < 0.05
    decided = 0
    for check, per_var in flags.items():
        for var, (expect, margin) in per_var.items():
            got = corr[var].sel(check=check).values
            sure = margin > 1e-3
            np.testing.assert_array_equal(got[sure], expect[sure], err_msg=f"{check} {var}")
            decided += sure.sum()
    assert decided >= 0.95 * 2 * 4 * len(FLEX)
    mil = corr["pass_all"].sel(check="MIL-STD-1540C").values
    nasa = corr["pass_all"].sel(check="NASA-STD-5002").values
    assert np.all(mil <= nasa) and mil.sum() < len(FLEX)     # NASA limits are looser; MIL fails some


def test_perturbed_model_with_noise(perturbed):
    """1 % frequency and 5 % shape noise: frequency errors and frequency flags exact against the
    noisy test frequencies; S and O within 0.1 of the truth (the noise term is ~0.03 rms); the
    clear failures (modes 16/17 coupled, |S_ij| ~ 0.31) are detected by both checks."""
    modes, truth, s_true, o_true, pair_true, kind = perturbed
    gvt = gvt_from(truth, FLEX, sensors_120(modes), rng=np.random.default_rng(7), f_noise=0.01,
                   s_noise=0.05)
    primary = np.isin(FLEX, FLEX[:7])
    corr = correlate(modes, gvt, primary_modes=FLEX[:7])
    np.testing.assert_array_equal(corr["paired_fe_mode"].values, pair_true)
    f_err, flags = _expected_flags(modes, gvt["frequency"].values, s_true, o_true, pair_true, primary)
    np.testing.assert_allclose(corr["frequency_error"].values, f_err, atol=1e-10)
    for check in flags:
        np.testing.assert_array_equal(corr["pass_frequency"].sel(check=check).values,
                                      flags[check]["pass_frequency"][0])
    assert np.abs(corr["cross_orthogonality"].values - s_true).max() < 0.1
    assert np.abs(corr["orthogonality"].values - o_true).max() < 0.1
    # clear failures (truth off-diagonal above 0.2, e.g. the coupled modes 16/17 of "numpy") are caught
    sp = np.abs(s_true[:, pair_true - 1])
    off_true = np.max(sp - np.diag(np.diag(sp)), axis=1)
    clear = off_true > 0.2
    assert not corr["pass_cross_orthogonality_off_diagonal"].values[:, clear].any()
    if kind == "numpy":
        assert clear[[FLEX.index(16), FLEX.index(17)]].all()


# -------------------------------------------------------------------------------------- figures
def test_figures_show_the_dataset_values(base, tmp_path):
    from structures.correlation_plots import (plot_cross_orthogonality, plot_frequency_comparison, plot_mac,
                                              save_correlation_figures)
    _, _, modes = base
    gvt = gvt_from(modes, FLEX, sensors_120(modes))
    gvt["name"] = ("mode", np.array([f"M{m}" for m in FLEX], dtype=object))
    corr = correlate(modes, gvt)
    ax = plot_mac(corr).axes[0]
    np.testing.assert_allclose(ax.images[0].get_array(), corr["mac"].sel(fe_mode=FLEX).values)
    assert [t.get_text() for t in ax.get_yticklabels()] == [f"{m} M{m}" for m in FLEX]
    ax = plot_cross_orthogonality(corr).axes[0]
    assert ax.images[0].get_clim() == (-1.0, 1.0)
    bars = plot_frequency_comparison(corr).axes[0].patches
    heights = np.array([b.get_height() for b in bars])
    np.testing.assert_allclose(heights, np.r_[corr["test_frequency"].values, corr["paired_fe_frequency"].values])
    paths = save_correlation_figures(corr, tmp_path)
    assert all(p.stat().st_size > 10_000 for p in paths)


def test_significant_coordinates_by_hand():
    """Phi_M = [e1, eps e2] at three DOFs: Phi_M^+ has rows e1 and e2 / eps, so a coordinate's
    noise standard deviation is sigma and sigma / eps. A test shape e1 + d e2 has q = (1, d / eps):
    its second coordinate is d / sigma standard deviations from 0, dropped at 3 < 4, kept at 5."""
    from structures.correlation import significant_coordinates

    eps, sigma = 0.01, 0.02
    phi_m = np.array([[1.0, 0.0], [0.0, eps], [0.0, 0.0]])
    shapes = np.array([[1.0, 3.0 * sigma, 0.0], [1.0, 5.0 * sigma, 0.0]]).T
    q = significant_coordinates(phi_m, shapes, [sigma, sigma], 4.0)
    np.testing.assert_allclose(q, [[1.0, 1.0], [0.0, 5.0 * sigma / eps]], rtol=1e-12)


def test_significant_coordinates_pass_noise_at_the_normal_rate():
    """Pure noise (sigma 0.05 per DOF, 40 DOFs, 5 random modes of very different sizes at the
    DOFs): the share of coordinates beyond 2 standard deviations is the normal distribution's,
    4.55 %, whatever the mode's size (the standard deviation sigma |row of Phi_M^+| is right);
    40,000 coordinates: binomial standard deviation 0.10 %."""
    from structures.correlation import significant_coordinates

    rng = np.random.default_rng(7)
    phi_m = rng.standard_normal((40, 5)) * np.array([1.0, 0.3, 0.05, 0.01, 2.0])
    noise = 0.05 * rng.standard_normal((40, 8000))
    kept = significant_coordinates(phi_m, noise, np.full(8000, 0.05), 2.0) != 0.0
    assert kept.mean() == pytest.approx(0.0455, abs=0.004)
    for k in range(5):
        assert kept[k].mean() == pytest.approx(0.0455, abs=0.008)
