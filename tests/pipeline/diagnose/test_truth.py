"""The blind study's truth generator (tests/pipeline/diagnose/truth): deterministic, readable by
the pipeline, and each hidden effect changes what it should.

References: the truth decks the generator keeps (``decks=``), read here card by card with
pyNastran, against the analysis deck; hand sums of the CONM2 masses; the case read back by
``pipeline.case.read_case`` and ``structures.gvt.load_gvt``. One seed of the frame per kind
(~15 s together) and the shipped example once with no effect (~5 s).
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pipeline.case import read_case
from structures.bdf import read_model
from structures.common.nastran import read_pynastran
from structures.gvt import load_gvt
from structures.modal import compute_modes
from tests.pipeline.diagnose.truth import STRUCTURES, TRUTH_KINDS, make_case

SEED = 0
#: The truth's modes compared (6 rigid / suspension + the GVT's 20 of the frame).
N_RIGID, N_TEST = 6, 20


@pytest.fixture(scope="module")
def frame_cases(tmp_path_factory):
    """Every kind on the frame, seed 0, truth decks kept: {kind: (case folder, truth deck)}."""
    root = tmp_path_factory.mktemp("frame")
    out = {}
    for kind in TRUTH_KINDS:
        case = make_case("frame", kind, SEED, root / kind, decks=root / kind / "decks")
        out[kind] = (case.parent, root / kind / "decks" / "truth_frame.bdf")
    return out


def _truth(folder: Path) -> dict:
    return json.loads((folder / "truth.json").read_text())


def _cards(path: Path, kind: str) -> dict:
    bdf = read_pynastran(path)
    return {eid: e for pool in (bdf.elements, bdf.rigid_elements, bdf.masses)
            for eid, e in pool.items() if e.type == kind}


def _elastic(path: Path) -> np.ndarray:
    f = compute_modes(read_model(path), N_RIGID + N_TEST + 4)["frequency"].values
    return f[N_RIGID:N_RIGID + N_TEST]


def test_names_of_the_contract():
    assert STRUCTURES == ("x56", "frame", "wingbox", "windy")
    assert TRUTH_KINDS == ("lumped_mass", "joint_flexibility", "member_taper", "member_curvature",
                           "boundary_stiffness", "none", "outside")


def test_truth_path_adds_nothing(tmp_path):
    """The truth's route (pyNastran parse, edit, write, our reader) on an untouched deck gives the
    analysis deck's modes and weight exactly: every difference in a truth is its effect or its
    scatter."""
    from tests.pipeline.diagnose.truth import frame

    deck = frame.write_frame(tmp_path)
    read_pynastran(deck).write_bdf(str(tmp_path / "round_trip.bdf"), enddata=True)
    np.testing.assert_allclose(_elastic(tmp_path / "round_trip.bdf"), _elastic(deck), rtol=1e-12)
    assert (sum(m.mass for m in _cards(tmp_path / "round_trip.bdf", "CONM2").values())
            == pytest.approx(sum(m.mass for m in _cards(deck, "CONM2").values()), rel=1e-12))


def test_deterministic(frame_cases, tmp_path):
    again = make_case("frame", "member_taper", SEED, tmp_path / "again").parent
    first = frame_cases["member_taper"][0]
    for name in ("case.toml", "frame.bdf", "gvt_frame.unv", "mass_frame.json", "truth.json"):
        assert (again / name).read_bytes() == (first / name).read_bytes(), name


def test_noise_scales_the_same_draws(frame_cases, tmp_path):
    """At (2 %, 10 %) noise the case is the same but for its noise, which is twice the default's
    draw by draw, and at (0, 0) it is the truth's modes (reference: the truth deck's own modes).
    Tolerances: the UFF's numbers carry 6 digits (2e-6 relative, measured)."""
    first, deck = frame_cases["member_taper"]
    loud, exact = (make_case("frame", "member_taper", SEED, tmp_path / name, noise=noise).parent
                   for name, noise in (("loud", (0.02, 0.10)), ("exact", (0.0, 0.0))))
    for name in ("case.toml", "frame.bdf", "mass_frame.json"):
        assert (loud / name).read_bytes() == (first / name).read_bytes(), name
    assert _truth(loud)["noise"] == {"frequency": 0.02, "shape": 0.10}
    quiet, noisy, zero = (load_gvt(folder / "gvt_frame.unv") for folder in (first, loud, exact))
    truth = compute_modes(read_model(deck), N_RIGID + N_TEST)["frequency"].values[N_RIGID:]
    np.testing.assert_allclose(zero["frequency"].values, truth, rtol=1e-5)
    f0, s0 = zero["frequency"].values, zero["shape"].values
    np.testing.assert_allclose(noisy["frequency"].values / f0 - 1,
                               2.0 * (quiet["frequency"].values / f0 - 1), atol=1e-5)
    np.testing.assert_allclose(noisy["shape"].values - s0, 2.0 * (quiet["shape"].values - s0),
                               atol=1e-5 * np.abs(s0).max())


def test_case_read_by_the_pipeline(frame_cases):
    folder, _ = frame_cases["none"]
    case = read_case(folder / "case.toml")
    (config,) = case.configurations
    gvt = load_gvt(config.gvt)
    assert gvt.sizes == {"mode": N_TEST, "dof": 120}
    assert gvt["mode"].values.tolist() == list(range(7, 7 + N_TEST))
    assert set(gvt["component"].values.tolist()) == {1, 2, 3}
    grids = set(read_model(config.deck).grids.ids.tolist())
    assert set(gvt["grid"].values.tolist()) <= grids
    assert set(config.measured_mass) == {"weight", "x_cg", "y_cg", "z_cg", "Ixx", "Iyy", "Izz",
                                         "Ixy", "Izx", "Iyz"}
    assert 0.5 < gvt["frequency"].values[0] < 10.0          # first elastic mode: a few Hz


def test_mass_only_where_mass_is_added(frame_cases):
    """Same seed, same scatter: the weighing differs from the no-effect case by the added mass
    alone (hand sum of the truth's CONM2s); stiffness effects leave weight unchanged, and all
    but the bowed member (which moves grids carrying mass) leave CG and inertia unchanged."""
    mass = {k: json.loads((f / "mass_frame.json").read_text()) for k, (f, _) in frame_cases.items()}
    none = mass["none"]
    added = _truth(frame_cases["lumped_mass"][0])["parameters"]["masses"]
    analysis_total = sum(m.mass for m in _cards(frame_cases["none"][0] / "frame.bdf",
                                                "CONM2").values())
    assert 0.01 <= sum(m for _, m, _ in added) / analysis_total <= 0.05
    assert mass["lumped_mass"]["weight"] - none["weight"] == pytest.approx(
        sum(m for _, m, _ in added), rel=1e-6)      # 8-character CONM2 fields
    for kind in ("joint_flexibility", "member_taper", "member_curvature", "boundary_stiffness",
                 "outside"):
        assert mass[kind]["weight"] == pytest.approx(none["weight"], rel=1e-12), kind
        if kind != "member_curvature":
            np.testing.assert_allclose(mass[kind]["inertia_cg"], none["inertia_cg"], rtol=1e-9,
                                       atol=1e-9, err_msg=kind)
            np.testing.assert_allclose(mass[kind]["cg"], none["cg"], atol=1e-12, err_msg=kind)


def test_frequency_shift_in_the_intended_range(frame_cases):
    """Every effect moves some of the 20 measured elastic frequencies by 3-15 % against the same
    scattered aircraft without it (our solver on the kept truth decks); nothing else moves."""
    base = _elastic(frame_cases["none"][1])
    for kind in TRUTH_KINDS:
        if kind == "none":
            continue
        shift = np.max(np.abs(_elastic(frame_cases[kind][1]) / base - 1.0))
        assert 0.03 <= shift <= 0.15, (kind, shift)
        assert _truth(frame_cases[kind][0])["max_frequency_shift"] == pytest.approx(shift,
                                                                                    rel=1e-6)


def test_location_and_neighbours(frame_cases):
    """truth.json names analysis ids, and its neighbour set holds every grid sharing a line or
    rigid element with the location (from the analysis deck's cards)."""
    analysis = read_pynastran(frame_cases["none"][0] / "frame.bdf")
    conn = [tuple(e.node_ids[:2]) for e in analysis.elements.values()]
    conn += [(r.gn, *r.Gmi) for r in analysis.rigid_elements.values()]
    for kind in TRUTH_KINDS:
        t = _truth(frame_cases[kind][0])
        assert t["kind"] == kind and t["structure"] == "frame" and t["seed"] == SEED
        if kind == "none":
            assert t["grids"] == t["elements"] == t["properties"] == [] and t["size"] == 0.0
            continue
        assert set(t["grids"]) <= set(analysis.nodes)
        assert set(t["elements"]) <= set(analysis.elements) | set(analysis.rigid_elements)
        assert set(t["properties"]) <= set(analysis.properties)
        near = {g for c in conn if set(c) & set(t["grids"]) for g in c}
        assert near <= set(t["neighbours"]["grids"]), kind
        assert set(t["elements"]) <= set(t["neighbours"]["elements"])


def test_lumped_mass_cards(frame_cases):
    folder, deck = frame_cases["lumped_mass"]
    t = _truth(folder)
    new = set(_cards(deck, "CONM2")) - set(_cards(folder / "frame.bdf", "CONM2"))
    cards = [_cards(deck, "CONM2")[e] for e in sorted(new)]
    assert 1 <= len(cards) <= 3 and {c.nid for c in cards} == set(t["grids"])
    assert all(min(np.asarray(c.I)[[0, 2, 5]]) > 0 for c in cards)       # with inertia


def test_joint_is_six_springs(frame_cases):
    folder, deck = frame_cases["joint_flexibility"]
    t = _truth(folder)
    bdf = read_pynastran(deck)
    springs = [e for e in bdf.elements.values() if e.type == "CELAS2"]
    assert len(springs) == 6 and sorted(s.c1 for s in springs) == [1, 2, 3, 4, 5, 6]
    a, b = springs[0].node_ids
    assert {tuple(s.node_ids) for s in springs} == {(a, b)}
    np.testing.assert_allclose(bdf.nodes[a].get_position(), bdf.nodes[b].get_position())
    assert {a, b} & set(t["grids"]) and t["elements"][0] in bdf.rigid_elements


def test_taper_remeshes_a_member(frame_cases):
    """The named member's CBARs are replaced by 4-8 segments between its end grids whose
    sections scale as a solid section's (A ~ r^2, I ~ r^4) with r tapering to 0.5-0.8."""
    folder, deck = frame_cases["member_taper"]
    t = _truth(folder)
    bdf = read_pynastran(deck)
    assert not set(t["elements"]) & set(bdf.elements)
    analysis = read_pynastran(folder / "frame.bdf")
    new = [e for eid, e in bdf.elements.items() if e.type == "CBAR" and eid not in analysis.elements]
    assert len(new) >= max(4, len(t["elements"]))
    assert not {e.pid for e in new} & set(analysis.properties)
    a = np.array([bdf.properties[e.pid].A for e in new])
    i1 = np.array([bdf.properties[e.pid].i1 for e in new])
    np.testing.assert_allclose(i1 / i1.max(), (a / a.max()) ** 2, rtol=1e-3)   # 8-char fields
    r = np.sqrt(a / a.max())
    assert 0.5 < r.min() < 0.9


def test_curvature_bows_a_member(frame_cases):
    folder, deck = frame_cases["member_curvature"]
    t = _truth(folder)
    bdf = read_pynastran(deck)
    ends = [np.asarray(bdf.nodes[g].get_position()) for g in (t["grids"][0], t["grids"][-1])]
    axis = (ends[1] - ends[0]) / np.linalg.norm(ends[1] - ends[0])
    length = sum(np.linalg.norm(np.diff([read_pynastran(folder / "frame.bdf").nodes[g].
                                         get_position() for g in t["grids"]], axis=0), axis=1))
    analysis = set(read_pynastran(folder / "frame.bdf").nodes)
    interior = [g for g in bdf.nodes if g not in analysis] + t["grids"][1:-1]
    off = [np.linalg.norm(np.cross(np.asarray(bdf.nodes[g].get_position()) - ends[0], axis))
           for g in interior]
    assert interior and 0.05 * 0.95 <= max(off) / length <= 0.15 + 1e-9


def test_boundary_is_grounded(frame_cases):
    folder, deck = frame_cases["boundary_stiffness"]
    t = _truth(folder)
    springs = list(_cards(deck, "CELAS2").values())
    assert 1 <= len(springs) <= 2
    assert all(s.node_ids[0] == t["grids"][0] and not s.node_ids[1] for s in springs)
    f = compute_modes(read_model(deck), N_RIGID + 2)["frequency"].values
    assert np.count_nonzero(f[:N_RIGID] < 1e-3) == N_RIGID - len(springs)


def test_outside_is_a_new_load_path(frame_cases):
    folder, deck = frame_cases["outside"]
    t = _truth(folder)
    (rod,) = _cards(deck, "CROD").values()
    assert sorted(rod.node_ids) == sorted(t["grids"])
    analysis = read_pynastran(folder / "frame.bdf")
    conn = [set(e.node_ids[:2]) for e in analysis.elements.values()]
    conn += [{r.gn, *r.Gmi} for r in analysis.rigid_elements.values()]
    near = [{g for c in conn if end in c for g in c} for end in t["grids"]]
    assert not near[0] & near[1]                 # three or more elements apart


def test_none_is_scatter_only(frame_cases):
    folder, deck = frame_cases["none"]
    truth, analysis = read_pynastran(deck), read_pynastran(folder / "frame.bdf")
    assert set(truth.nodes) == set(analysis.nodes) and set(truth.elements) == set(analysis.elements)
    ratio = np.array([truth.properties[p].i1 / analysis.properties[p].i1 for p in analysis.properties])
    assert np.all(np.abs(ratio - 1.0) <= 2 * 0.03 + 1e-9) and np.std(ratio) > 0.005


def test_x56_case_has_both_configurations(tmp_path):
    case = read_case(make_case("x56", "none", SEED, tmp_path))
    assert [c.name for c in case.configurations] == ["efew", "fffw"]
    weights = []
    for config in case.configurations:
        gvt = load_gvt(config.gvt)
        assert gvt.sizes == {"mode": 22, "dof": 120}
        weights.append(config.measured_mass["weight"])
    assert weights[1] - weights[0] == pytest.approx(2 * (30 - 1) + 6 * (30 - 0.5), rel=0.05)


def test_suspension_hangs_the_truth_and_lists_its_modes(frame_cases, tmp_path):
    """make_case(suspension=True): the same effect drawn as without it; the truth deck holds
    nine grounded CELAS2 (three grids: a mirror pair and a grid on y = 0, x, y, z each); the GVT
    lists its six suspension modes first (modes 1-6, the truth's own lowest six at 0 noise, all
    below the first elastic one), then the elastic modes 7 ..; the wing box refuses."""
    plain = frame_cases["lumped_mass"][0]
    folder = make_case("frame", "lumped_mass", SEED, tmp_path / "hung", suspension=True,
                       decks=tmp_path / "decks", noise=(0.0, 0.0)).parent
    t = _truth(folder)
    assert (t["grids"], t["parameters"]) == (_truth(plain)["grids"], _truth(plain)["parameters"])
    grids = [s["grid"] for s in t["suspension"]]
    xyz = read_model(folder / "frame.bdf").grids
    y = xyz.xyz[xyz.index(grids)][:, 1]
    assert y[0] == pytest.approx(-y[1]) and y[0] != 0.0 and y[2] == 0.0
    deck = tmp_path / "decks" / json.loads((tmp_path / "decks" / "truth_decks.json").read_text())[
        "frame"]
    springs = [s for s in _cards(deck, "CELAS2").values() if not s.node_ids[1]]
    assert sorted((s.node_ids[0], s.c1) for s in springs) == sorted(
        (g, c) for g in grids for c in (1, 2, 3))
    gvt = load_gvt(folder / "gvt_frame.unv")
    np.testing.assert_array_equal(gvt["mode"].values, np.arange(1, N_RIGID + N_TEST + 1))
    truth = compute_modes(read_model(deck), N_RIGID + N_TEST)["frequency"].values
    np.testing.assert_allclose(gvt["frequency"].values, truth, rtol=1e-5)
    assert truth[N_RIGID - 1] < 0.5 * truth[N_RIGID] and truth[0] > 1e-2
    with pytest.raises(Exception, match="clamped"):
        make_case("wingbox", "none", 0, tmp_path / "wb", suspension=True)
