"""Tests of structures.indices: values against structures.correlation / massprops, gradients against
central differences, the paper's numbering (eqs. 15-24) and bad input."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).parent))
from tuning_decks import synthetic_gvt, write_aircraft_deck  # noqa: E402

from structures.bdf import read_model  # noqa: E402
from structures.correlation import correlate  # noqa: E402
from structures.design import DesignVariable, apply_design  # noqa: E402
from structures.common.errors import InputError  # noqa: E402
from structures.indices import MASS_QUANTITIES, build_catalogue, mass_quantities  # noqa: E402
from structures.massprops import mass_properties  # noqa: E402
from structures.modal import compute_modes  # noqa: E402
from structures.tuning import TuningConfiguration, TuningProblem, _Configuration, Evaluator  # noqa: E402

TEST_MODES = list(range(7, 15))
VARIABLES = (DesignVariable("spar_I1", [("PBAR", 11, "I1"), ("PBAR", 12, "I1")]),
             DesignVariable("skin_T", [("PSHELL", 21, "T"), ("PSHELL", 22, "T")]),
             DesignVariable("engine", [("CONM2", 900, "M"), ("CONM2", 901, "M")]),
             DesignVariable("fus_I1", [("PBAR", 1, "I1")]))


@pytest.fixture(scope="module")
def setup(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("idx")
    info = write_aircraft_deck(tmp / "start.bdf", n_span=6)
    truth = read_model(write_aircraft_deck(tmp / "truth.bdf", n_span=6, changes={
        ("PBAR", 11, "I1"): 1.1, ("PBAR", 12, "I1"): 1.1, ("PSHELL", 21, "T"): 0.92,
        ("PSHELL", 22, "T"): 0.92, ("CONM2", 900, "M"): 1.08, ("CONM2", 901, "M"): 1.08})["path"])
    gvt = synthetic_gvt(compute_modes(truth, 30), info["grids"], TEST_MODES)
    start = read_model(info["path"])
    props = mass_properties(truth).as_dict()
    targets = {"weight": props["mass"], "x_cg": props["x_cg"], "z_cg": props["z_cg"],
               "Ixx": props["Ixx"], "Iyy": props["Iyy"], "Izz": props["Izz"], "Izx": props["Izx"],
               "y_cg": 0.0}
    cfg = TuningConfiguration("empty", start, gvt, nmodes=24, mass_targets=targets,
                              mass_references={"y_cg": 1.0})
    return cfg, start, gvt


def test_paper_numbering_of_the_catalogue():
    cat = build_catalogue("c", [7, 8, 9, 10], {"weight": 1.0, "Izx": 2.0})
    n, l_m = 4, 6                                                          # eq. 16
    assert list(cat.paper_k[cat.kind == "mass"]) == [1, 10]                # eqs. 1, 10
    assert list(cat.paper_k[cat.kind == "orthogonality"]) == list(range(11, 11 + l_m))
    assert list(cat.paper_k[cat.kind == "frequency"]) == list(range(11 + l_m, 11 + l_m + n))
    l_s = n * n - n                                                        # eq. 22
    assert list(cat.paper_k[cat.kind == "cross_orthogonality"]) == list(range(11 + l_m + n, 11 + l_m + n + l_s))
    assert list(cat.paper_k[cat.kind == "mac"]) == list(range(11 + l_m + n + l_s, 11 + l_m + 2 * n + l_s))
    assert "c:cross_orthogonality:9-7" in cat.names and "c:orthogonality:7-9" in cat.names
    assert "c:orthogonality:9-7" not in cat.names                          # i < j only (eq. 16)


def test_zero_mass_target_needs_a_reference():
    with pytest.raises(InputError, match="y_cg"):
        build_catalogue("c", [7], {"y_cg": 0.0})
    with pytest.raises(InputError, match="unknown mass quantity"):
        build_catalogue("c", [7], {"cg_x": 1.0})


def test_values_match_correlate_and_mass_properties(setup):
    cfg, start, gvt = setup
    conf = _Configuration(cfg, Evaluator(TuningProblem((cfg,), VARIABLES, (("*:frequency:*", 1.0),))).space,
                          "nelson")
    values, _, terms = conf.evaluate(conf.sub.space.x0, False)
    ref = correlate(compute_modes(start, 24), gvt)
    byname = dict(zip(conf.catalogue.names, values))
    paired = ref["paired_fe_mode"].values
    np.testing.assert_array_equal(terms.fe_index + 1, paired)
    for i, ti in enumerate(TEST_MODES):
        assert byname[f"empty:frequency:{ti}"] == pytest.approx(
            (ref["frequency_error"].values[i] / 100) ** 2, rel=1e-6)            # eq. 18
        assert byname[f"empty:mac:{ti}"] == pytest.approx(ref["paired_mac"].values[i], abs=1e-8)
        for j, tj in enumerate(TEST_MODES):
            if i < j:
                assert byname[f"empty:orthogonality:{ti}-{tj}"] == pytest.approx(
                    ref["orthogonality"].values[i, j] ** 2, abs=1e-10)          # eq. 15
            if i != j:
                s_ij = ref["cross_orthogonality"].sel(test_mode=ti, fe_mode=paired[j]).item()
                assert byname[f"empty:cross_orthogonality:{ti}-{tj}"] == pytest.approx(
                    s_ij ** 2, abs=1e-10)                                       # eq. 21
    props = mass_properties(start).as_dict()
    assert byname["empty:mass:weight"] == pytest.approx(
        ((props["mass"] - cfg.mass_targets["weight"]) / cfg.mass_targets["weight"]) ** 2, rel=1e-9)
    assert byname["empty:mass:y_cg"] == pytest.approx(props["y_cg"] ** 2, abs=1e-20)


def test_mass_quantity_gradients_match_finite_differences(setup):
    cfg, start, _ = setup
    from structures.design import bind
    from structures.sensitivity import SubAssembly
    space = bind(VARIABLES, [start])
    sub = SubAssembly(start, space)
    m0 = sub.matrices(space.x0)[2]
    _, _, dm0 = sub.derivatives(space.x0)
    _, grad = mass_quantities(m0, 1.0, dm0)
    for i in range(len(space)):
        h = 1e-4 * space.x0[i]
        xp, xm = space.x0.copy(), space.x0.copy()
        xp[i] += h
        xm[i] -= h
        vp = np.array(list(mass_properties(apply_design(start, space, xp)).as_dict().values()))
        vm = np.array(list(mass_properties(apply_design(start, space, xm)).as_dict().values()))
        fd = (vp - vm) / (2 * h)
        # per unit group (weight, CG, inertias): the symmetric model's y_cg, Ixy, Iyz are round-off
        for group in (slice(0, 1), slice(1, 4), slice(4, 10)):
            scale = np.abs(fd[group]).max()
            err = np.abs(grad[i, group] - fd[group]).max()
            assert err <= 1e-6 * scale, (space.names[i], group, err / scale)
    assert len(MASS_QUANTITIES) == 10


def test_every_index_gradient_matches_finite_differences(setup):
    """dJ_k/dx of every index (eqs. 1-24) against Richardson central differences of J_k with the
    pairing held fixed, step 1e-2 |x|: |error| <= 1e-4 max_k' |dJ/dx| of the same kind."""
    cfg, _, _ = setup
    ev = Evaluator(TuningProblem((cfg,), VARIABLES, (("*:frequency:*", 1.0),)))
    conf = ev.configs[0]
    x = ev.space.x0
    values, grad, terms = conf.evaluate(x, True)
    assert not np.allclose(values[conf.catalogue.kind == "cross_orthogonality"], 0.0)
    fixed = terms.fe_index

    def at(xx):
        from structures.indices import correlation_terms, index_values
        from structures.sensitivity import model_modes
        _, _, m0, lam, phi, n_rigid, _ = model_modes(conf.sub, xx, cfg.nmodes)
        t = correlation_terms(conf.rows @ phi, conf.phi_gm, lam, conf.f_test, n_rigid=n_rigid,
                              fe_index=fixed)
        return index_values(conf.catalogue, mass_quantities(m0, 1.0)[0], t)[0]

    kinds = conf.catalogue.kind
    for i in range(len(x)):
        def central(h):
            xp, xm = x.copy(), x.copy()
            xp[i] += h
            xm[i] -= h
            return (at(xp) - at(xm)) / (2 * h)
        h = 1e-3 * x[i]
        fd = (4 * central(h / 2) - central(h)) / 3
        for kind in np.unique(kinds):
            sel = kinds == kind
            scale = np.abs(grad[sel, i]).max()
            err = np.abs(fd[sel] - grad[sel, i]).max()
            assert err <= 1e-4 * scale + 1e-14, (ev.space.names[i], kind, err / scale)
