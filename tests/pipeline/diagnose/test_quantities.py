"""A named effect's quantities in deck units, checked against the bulk data the workflow writes
(read back by pyNastran, not by this package's reader) and by hand."""
import numpy as np
import pytest
from pyNastran.bdf.bdf import BDF

from pipeline.diagnose.apply import apply_effect, write_effect_deck
from pipeline.diagnose.effects import candidates, directional, distributed
from pipeline.diagnose.result import EffectRecord, effect_json
from structures.bdf import read_model
from structures.bulk_text import card


@pytest.fixture(scope="module")
def x56_cards(x56_deck):
    bdf = BDF(debug=None)
    bdf.read_bdf(str(x56_deck), xref=False)
    return bdf


def _pick(cands, kind, label_part="", pair=False):
    return next(c for c in cands if c.kind == kind and label_part in c.label
                and (c.get("sites") is not None) == pair)


@pytest.fixture
def written(tmp_path, x56_deck, x56):
    """The X-56 deck written with one effect, read by pyNastran."""
    def write(cand, values):
        bdf = BDF(debug=None)
        bdf.read_bdf(str(write_effect_deck(x56_deck, tmp_path / "out.bdf", x56, [(cand, values)])),
                     xref=False)
        return bdf
    return write


def _quantities(cand, values):
    return effect_json(EffectRecord(cand, np.asarray(values, float), 0.0))


@pytest.mark.parametrize("label", ["grid 5021", "grid 3005 spread over"])
def test_lumped_mass_is_the_new_conm2s(x56_candidates, x56_cards, written, label):
    cand = _pick(x56_candidates, "lumped_mass", label)
    record = _quantities(cand, [0.013, 3.0e-4])
    q = record["quantities"]
    bdf = written(cand, [0.013, 3.0e-4])
    new = [m for eid, m in bdf.masses.items() if eid not in x56_cards.masses]
    assert sorted(m.nid for m in new) == list(cand.location.grids)
    for m in new:
        assert m.mass == pytest.approx(q["mass_per_grid"], rel=1e-12)
        i = np.asarray(m.I, float)                                       # I11 I21 I22 I31 I32 I33
        np.testing.assert_allclose(i, [q["inertia_per_grid"], 0.0, q["inertia_per_grid"], 0.0,
                                       0.0, q["inertia_per_grid"]], rtol=1e-12)
    assert sum(m.mass for m in new) == pytest.approx(q["mass"], rel=1e-12)
    # I = m_share r^2 of each share: the radius of gyration is sqrt(inertia) L
    assert q["radius_of_gyration"] ** 2 * q["mass_per_grid"] == \
        pytest.approx(q["inertia_per_grid"], rel=1e-12)
    assert record["sites"][0]["quantities"] == q


def test_a_mass_per_grid_is_the_new_conm2s(x56, x56_candidates, x56_cards, written):
    """A mass with one share per grid (pipeline.diagnose.effects.distributed): a CONM2 at each
    grid of nonzero share carrying ``mass_at_<g>`` and I11 = I22 = I33 = its mass x r^2, none at
    a grid of zero share, the shares summing to ``mass``."""
    rich, _ = distributed(x56, _pick(x56_candidates, "lumped_mass", "grid 3005 spread over"),
                          [0.013, 3.0e-4])
    shares = np.zeros(len(rich.parameters))
    shares[[0, 1]], shares[-1] = (0.009, 0.002), 3.0e-4
    q = _quantities(rich, shares)["quantities"]
    new = {m.nid: m for eid, m in written(rich, shares).masses.items()
           if eid not in x56_cards.masses}
    assert sorted(new) == list(rich.location.grids[:2])
    for g, m in new.items():
        assert m.mass == pytest.approx(q[f"mass_at_{g}"], rel=1e-12)
        i = q[f"mass_at_{g}"] * q["radius_of_gyration"] ** 2
        np.testing.assert_allclose(np.asarray(m.I, float), [i, 0.0, i, 0.0, 0.0, i], rtol=1e-12)
    assert [q[f"mass_at_{g}"] for g in rich.location.grids[2:]] == [0.0] * (len(shares) - 3)
    assert sum(m.mass for m in new.values()) == pytest.approx(q["mass"], rel=1e-12)
    assert q["mass"] == pytest.approx(0.011 / 0.013 * _quantities(
        _pick(x56_candidates, "lumped_mass", "grid 3005 spread over"), [0.013, 3.0e-4])
        ["quantities"]["mass"], rel=1e-12)


def test_joint_is_the_new_cbush_stiffness(x56_candidates, x56_cards, written):
    """The two-parameter joint and its directional form: K_p of the written PBUSH, and
    K_1 / K_4 = (k_t / k_r) 10^rotation by hand."""
    cand = _pick(x56_candidates, "joint_flexibility", "RBE2 7501")
    values = [300.0, -0.6]
    q = _quantities(cand, values)["quantities"]
    bdf = written(cand, values)
    (pbush,) = [p for pid, p in bdf.properties.items() if pid not in x56_cards.properties]
    np.testing.assert_allclose(pbush.Ki, [q[f"K{i}"] for i in range(1, 7)], rtol=1e-12)
    ratio = cand.get("k_translation") / cand.get("k_rotation") * 10.0 ** -0.6
    assert q["K1"] / q["K4"] == pytest.approx(ratio, rel=1e-12)
    rich, c = directional(cand, values)
    assert _quantities(rich, c)["quantities"] == pytest.approx(q, rel=1e-12)


def test_mirror_pair_gives_each_site_its_spring(x56_candidates, x56_cards, written):
    pair = _pick(x56_candidates, "joint_flexibility", "RBE2 7501", pair=True)
    rich, c = directional(pair, [300.0, -0.6])
    c = c * np.arange(1, 7)
    record = _quantities(rich, c)
    bdf = written(rich, c)
    pbushes = [p for pid, p in bdf.properties.items() if pid not in x56_cards.properties]
    assert len(pbushes) == 2 == len(record["sites"])
    for pbush in pbushes:
        np.testing.assert_allclose(pbush.Ki, [record["quantities"][f"K{i}"] for i in range(1, 7)],
                                   rtol=1e-12)
    assert record["sites"][1]["quantities"] == record["sites"][0]["quantities"]


def test_boundary_spring_is_the_new_celas2(x56_candidates, x56_cards, written):
    cand = _pick(x56_candidates, "boundary_stiffness", "grid 1004 z")
    q = _quantities(cand, [0.07])["quantities"]
    bdf = written(cand, [0.07])
    (celas,) = [e for eid, e in bdf.elements.items() if eid not in x56_cards.elements]
    # pyNastran writes a CELAS2 in small field: 7 significant digits
    assert celas.type == "CELAS2" and celas.k == pytest.approx(q["k_z"], rel=5e-7)


def _one_bar(tmp_path, length):
    path = tmp_path / "one_bar.bdf"
    path.write_text("SOL 103\nCEND\nBEGIN BULK\n" + "\n".join(card(*c) for c in [
        ("GRID", 1, None, 0.0, 0.0, 0.0, None, 123456), ("GRID", 2, None, length, 0.0, 0.0),
        ("CBAR", 10, 7, 1, 2, 0.0, 1.0, 0.0), ("PBAR", 7, 1, 3.0, 0.7, 1.3, 1.0),
        ("MAT1", 1, 2.0e5, None, 0.3, 0.0)]) + "\nENDDATA\n")
    return read_model(path)


def test_taper_end_factors_by_hand_and_in_the_pieces(tmp_path):
    """scale 0.1, taper 0.2: s = 1.1 x 0.9 = 0.99 at grid 1 and 1.1 x 1.1 = 1.21 at grid 2; each
    of the eight pieces has A = 3 s^2 at its mid-length, s linear between the ends."""
    model = _one_bar(tmp_path, 4.0)
    cand = _pick(candidates(model, ["member_taper"]), "member_taper")
    q = _quantities(cand, [0.1, 0.2])["quantities"]
    assert (q["size_factor_a"], q["size_factor_b"]) == pytest.approx((0.99, 1.21), rel=1e-14)
    tapered = apply_effect(model, cand, [0.1, 0.2])
    bars = tapered.elements["CBAR"]
    xyz = tapered.grids.xyz[tapered.grids.index(bars.nodes.ravel())].reshape(-1, 2, 3)
    xi = xyz[:, :, 0].mean(axis=1) / 4.0
    s = q["size_factor_a"] + (q["size_factor_b"] - q["size_factor_a"]) * xi
    area = [tapered.properties[int(p)].fields["A"] for p in bars.pids]
    np.testing.assert_allclose(area, 3.0 * s ** 2, rtol=1e-12)


def test_curvature_rise_is_the_mid_grid_offset(tmp_path):
    """A 4 m bar bowed by 0.05 in plane 1 (y): the new grid at mid-length is 0.2 m off the
    chord, the rise."""
    model = _one_bar(tmp_path, 4.0)
    cand = _pick(candidates(model, ["member_curvature"]), "member_curvature")
    q = _quantities(cand, [0.05, 0.0])["quantities"]
    assert (q["rise_1"], q["rise_2"]) == pytest.approx((0.2, 0.0), abs=1e-15)
    bowed = apply_effect(model, cand, [0.05, 0.0])
    mid = bowed.grids.xyz[np.isclose(bowed.grids.xyz[:, 0], 2.0)]
    np.testing.assert_allclose(mid, [[2.0, q["rise_1"], 0.0]], atol=1e-15)


def test_standard_errors_in_the_json(x56_candidates):
    """A named effect's standard errors go beside its parameters, null where not determined
    (inf) and the whole entry null when not estimated."""
    cand = _pick(x56_candidates, "lumped_mass", "grid 5021")
    record = effect_json(EffectRecord(cand, np.array([0.013, 3.0e-4]), 0.0, (),
                                      np.array([0.0011, np.inf])))
    assert record["standard_errors"] == {"mass": 0.0011, "inertia": None}
    assert _quantities(cand, [0.013, 3.0e-4])["standard_errors"] is None
