"""diagnose(): settings, the published ranking and the round record on constructed tables, and
end-to-end blind cases of the truth generator's frame (tests/pipeline/diagnose/truth, never
imported by the workflow). The verdict rules are in test_verdict.py."""
from __future__ import annotations

import importlib
import json
from dataclasses import replace
from math import log
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from pipeline.case import read_case
from pipeline.diagnose.apply import apply_effect
from pipeline.diagnose.effects import Candidate, Location, candidates, distributed
from pipeline.diagnose import DiagnoseSettings, diagnose, preflight
from pipeline.diagnose.inputs import configurations_from_case, settings_from_case
from pipeline.diagnose.verdict import decide
from pipeline.diagnose.mirror import sites
from pipeline.diagnose.rounds import chi2_split, ranking_table, round_record
from pipeline.diagnose.workflow import unnamed
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset
from structures.suspension import rigid_body_readings
from tests.pipeline.diagnose.truth import frame, make_case


@pytest.mark.parametrize("field, value", [("kinds", ("bogus",)), ("max_effects", 0),
                                          ("holdout", 1), ("refit", 0),
                                          ("frequency_noise", 0.0), ("margin", -1.0),
                                          ("shape_noise", -0.1), ("nmodes", 0),
                                          ("model_scatter", -0.01)])
def test_settings_refuse_bad_values(field, value):
    with pytest.raises(InputError, match=field if field != "kinds" else "kinds"):
        DiagnoseSettings(**{field: value})


def test_no_configurations_refused():
    with pytest.raises(InputError, match="no configurations"):
        diagnose(())


# ------------------------------------------------------------------------ blind frame cases
def _run(tmp_path, kind: str, seed: int = 0):
    case_path = make_case("frame", kind, seed, tmp_path / f"{kind}_{seed}")
    truth = json.loads((case_path.parent / "truth.json").read_text())
    case = read_case(case_path)
    return diagnose(configurations_from_case(case), settings_from_case(case)), truth


def _near_truth(effect, truth) -> bool:
    loc = effect.candidate.location
    grids = set(truth["neighbours"]["grids"]) | set(truth["grids"])
    elements = set(truth["neighbours"]["elements"]) | set(truth["elements"])
    return bool(set(loc.grids) & grids or set(loc.elements) & elements
                or set(loc.properties) & set(truth["properties"]))


class GapDidNotShrink(AssertionError):
    """A gap metric that the issue requires to drop did not (an expected failure can name it)."""


@pytest.mark.slow
@pytest.mark.parametrize("kind", ["lumped_mass", "boundary_stiffness", "member_taper"])
def test_frame_effect_named_where_it_is(tmp_path, kind):
    # 60-130 s each on one core. Measured on seed 0 (blind study at fccf93c, with the load-path
    # rule of 20d7570): lumped masses at grids 3209 and 3007, then a spring at grid 5102 x
    # (truth 3008, 3009, 3209): held-out frequency RMS 10.24 -> 1.83 %, cross-orthogonality
    # 0.613 -> 0.501 (held-out rows 0.586 -> 0.501); taper PID 23 (truth PID 23, the member in 8
    # pieces; round 2's spring at grid 6002 y ties with a load path): 1.54 -> 0.80 %,
    # 0.568 -> 0.072 (held-out rows 0.568 -> 0.048); boundary spring, at c761420: grid 5002 y
    # (truth 5002): 0.88 -> 0.71 %, 0.607 -> 0.496 (held-out rows 0.497 -> 0.490)
    result, truth = _run(tmp_path, kind)
    assert result.verdict == "effect"
    first = result.effects[0]
    assert first.candidate.kind == kind and _near_truth(first, truth)
    before, after = result.gap_before, result.gap_after
    for key in ("frequency_rms_held_out", "max_cross_orthogonality_offdiag",
                "max_cross_orthogonality_offdiag_held_out"):
        if not after[key] < before[key]:
            raise GapDidNotShrink(f"{key}: {before[key]} -> {after[key]}")


@pytest.mark.slow
def test_frame_outside_is_not_named(tmp_path):
    # measured on seed 0 (a brace from the tail to the fin, blind study at fccf93c and the load
    # path rule of 20d7570): ambiguous, the best fit a taper of the tail boom PID 51 (BIC 383.4)
    # and a spring between grids 4004 and 4202 (382.1) within the margin of each other
    result, _ = _run(tmp_path, "outside")
    assert result.verdict in ("ambiguous", "unexplained")
    assert result.verdict != "ambiguous" or result.separating_measurement


@pytest.mark.slow
def test_frame_frequency_only_runs_and_says_what_it_cannot_tell(tmp_path):
    # measured on seed 0 "none": verdict none, 20 modes paired by nearest frequency; ~45 s (the
    # default suite's frequency-only case is the wing box's, test_truth_wingbox)
    case_path = make_case("frame", "none", 0, tmp_path / "none_0")
    case = read_case(case_path)
    confs = [replace(c, gvt=c.gvt.drop_vars("shape")) for c in configurations_from_case(case)]
    result = diagnose(confs, settings_from_case(case))
    assert result.verdict == "none"
    assert any("frequency-only" in note for note in result.notes)
    assert result.gap_before["mac_min"] is None
    assert result.gap_before["max_cross_orthogonality_offdiag"] is None
    record = result.to_json()
    assert record["verdict"] == "none" and record["effect"] is None
    assert json.loads(json.dumps(record)) == record                       # JSON-clean


def test_suspension_modes_in_the_test_data_are_left_out(tmp_path):
    """The frame's GVT with six suspension modes put in front, as many GVT files list them
    (rigid-body motions at the sensors, 0.2-0.5 Hz, 5 % shape noise): preflight sets them aside
    with a note and builds the same reference as from the elastic modes alone; frequency-only,
    the same by frequency (below half the first elastic analysis frequency, 2.8 Hz)."""
    case = read_case(make_case("frame", "none", 0, tmp_path / "none_0"))
    (conf,) = configurations_from_case(case)
    gvt = conf.gvt
    position = conf.model.grids.xyz[conf.model.grids.index(gvt["grid"].values)]
    rng = np.random.default_rng(0)
    rigid = rng.standard_normal((6, 6)) @ rigid_body_readings(position,
                                                              gvt["component"].values).T
    rigid += 0.05 * np.sqrt(np.mean(rigid ** 2, axis=1, keepdims=True)) * \
        rng.standard_normal(rigid.shape)
    hung = make_gvt_dataset(np.concatenate([np.linspace(0.2, 0.5, 6), gvt["frequency"].values]),
                            np.vstack([rigid, gvt["shape"].values]), gvt["grid"].values,
                            gvt["component"].values, mode=np.arange(1, 7 + gvt.sizes["mode"]),
                            source="frame GVT with its suspension", units="si")
    plain, _ = preflight([conf], DiagnoseSettings())
    for data in (hung, hung.drop_vars("shape")):
        refs, notes = preflight([replace(conf, gvt=data)], DiagnoseSettings())
        np.testing.assert_array_equal(refs[0].test_frequency, plain[0].test_frequency)
        assert any(n.startswith("frame: test modes [1, 2, 3, 4, 5, 6] (0.2-0.5 Hz) are "
                                "suspension modes") for n in notes), notes


def test_preflight_checks_the_data_without_screening(tmp_path):
    """The frame's 20 test modes: one reference with every mode paired, the training split of
    holdout 3 (modes 3, 6, ... held out: 14 train), notes; too few elastic analysis modes (24
    modes, 6 of them rigid) refused after the modal solve; repeated names refused; a holdout
    above the 20 paired modes, which would leave splits with no mode held out, refused, and 20
    holding out one mode accepted."""
    case = read_case(make_case("frame", "none", 0, tmp_path / "none_0"))
    confs = configurations_from_case(case)
    refs, notes = preflight(confs, DiagnoseSettings())
    assert len(refs) == 1 and refs[0].test_frequency.size == 20
    assert int(refs[0].train.sum()) == 14 and refs[0].has_shapes
    assert any("sensor DOFs" in n for n in notes)
    with pytest.raises(InputError, match="nmodes"):
        preflight(confs, DiagnoseSettings(nmodes=24))
    with pytest.raises(InputError, match="repeat"):
        preflight(confs * 2, DiagnoseSettings())
    with pytest.raises(InputError, match=r"holdout = 21 but only 20 elastic test modes.*at most "
                                         r"20"):
        preflight(confs, DiagnoseSettings(holdout=21))
    (ref,), _ = preflight(confs, DiagnoseSettings(holdout=20))
    assert int((~ref.train).sum()) == 1


def test_too_few_analysis_modes_refused_before_any_computation(tmp_path, monkeypatch):
    """nmodes below the test modes' count is refused from the settings and the GVT alone: the
    modal solve is never reached."""
    preflight_module = importlib.import_module("pipeline.diagnose.preflight")
    case = read_case(make_case("frame", "none", 0, tmp_path / "none_0"))
    confs = configurations_from_case(case)
    monkeypatch.setattr(preflight_module, "compute_modes", lambda *a: pytest.fail("solved"))
    with pytest.raises(InputError) as err:
        preflight(confs, DiagnoseSettings(nmodes=10))
    for needle in ("configuration frame", "20 test modes", "nmodes = 10", "at least 26", "Fix"):
        assert needle in str(err.value), (needle, str(err.value))


def test_zero_test_frequency_refused_before_any_computation(tmp_path, monkeypatch):
    """A test mode at 0 Hz (a GVT format allows it) is refused from the GVT alone, naming the
    modes: it used to pass every check."""
    preflight_module = importlib.import_module("pipeline.diagnose.preflight")
    case = read_case(make_case("frame", "none", 0, tmp_path / "none_0"))
    (conf,) = configurations_from_case(case)
    frequency = conf.gvt["frequency"].values.copy()
    frequency[[0, 4]] = 0.0
    gvt = conf.gvt.assign(frequency=("mode", frequency))
    monkeypatch.setattr(preflight_module, "compute_modes", lambda *a: pytest.fail("solved"))
    with pytest.raises(InputError) as err:
        preflight([replace(conf, gvt=gvt)], DiagnoseSettings())
    modes = conf.gvt["mode"].values[[0, 4]].tolist()
    for needle in ("configuration frame", f"test modes {modes} have frequency 0 Hz", "Fix"):
        assert needle in str(err.value), (needle, str(err.value))


def _rows(modal: float, stated: float, n: int = 100, n_modal: int = 90) -> np.ndarray:
    """(n,) residual with chi^2 ``modal`` in its first entry (modal rows: the first n_modal)
    and ``stated`` in entry n_modal (a weighing row)."""
    r = np.zeros(n)
    r[0], r[n_modal] = np.sqrt(modal), np.sqrt(stated)
    return r


def _split_problem(n_modal: int = 90, n: int = 100):
    """A Problem stand-in whose fits' ``evaluations`` are their residual vectors."""
    modal = np.arange(n) < n_modal
    return SimpleNamespace(n_theta=2, modal_rows=lambda: modal, residual=lambda theta, r: r)


def test_published_ranking_is_the_one_that_decided():
    """n = 100 rows, 90 modal, 10 candidates screened, 2 nominal parameters. Refits A (modal
    chi^2 261, weighing 9) and B (240, 90) (p 3), linearised C r0 + S x (330, 9; 1 + 2
    parameters), "none" (450, 90; p 2). Modal dispersion of A: c = 261 / 87 = 3; scores
    A 87 + 9 + 3 ln 100, B 80 + 90 + 3 ln 100, C 110 + 9 + 3 ln 100, none 150 + 90 + 2 ln 100
    - 2 ln 10: relative to A 0, 23, 74, 144 - ln 100 - 2 ln 10, by hand; decide's lead (over
    the runner-up B) is B's published score and its c is 3."""
    def cand(kind, grid):
        return Candidate(kind, Location(grids=(grid,)), f"{kind} {grid}", ("x",), (0.0,), (1.0,),
                         (0.1,))

    a, b, c = cand("lumped_mass", 1), cand("member_taper", 9), cand("boundary_stiffness", 5)
    problem = _split_problem()
    refits = [SimpleNamespace(candidate=a, theta=None, evaluations=_rows(261.0, 9.0), chi2=270.0,
                              n_params=3),
              SimpleNamespace(candidate=b, theta=None, evaluations=_rows(240.0, 90.0),
                              chi2=330.0, n_params=3)]
    r0 = _rows(450.0, 90.0)
    step = _rows(330.0, 9.0) - r0
    rows = [SimpleNamespace(candidate=x, signature=step[:, None] * k, values=np.array([1.0]))
            for x, k in ((a, 0.5), (b, 0.5), (c, 1.0))]
    none = SimpleNamespace(theta=None, evaluations=r0, chi2=540.0, n_params=2)
    table = ranking_table(problem, r0, rows, refits, none, 100, 10)
    hand = {"lumped_mass": 0.0, "member_taper": 74.0, "boundary_stiffness": 23.0,
            "none": 144.0 - log(100.0) - 2.0 * log(10.0)}
    assert [t.kind for t in table] == ["lumped_mass", "boundary_stiffness", "member_taper",
                                       "none"]
    for t in table:
        assert t.score == pytest.approx(hand[t.kind], rel=1e-12, abs=1e-12)
    assert [t.refitted for t in table] == [True, False, True, True]
    _, best, runner, lead, _, disp = decide(
        (450.0, 90.0, 2), [(x.candidate.kind, x.candidate.location, m, st, x.n_params)
                           for x, (m, st) in zip(refits, ((261.0, 9.0), (240.0, 90.0)))],
        10.0, 100, 10, n_modal=90)
    assert (best, runner) == (0, 1) and lead == pytest.approx(table[2].score, rel=1e-12)
    assert disp == pytest.approx(3.0, rel=1e-12)


def test_sites_of_the_named_kind_within_the_margin_are_listed_with_their_scores():
    """The same stand-in rows as the published ranking: the named spring at grid 1 (refitted,
    modal chi^2 261, weighing 9: c = 3, score 87 + 9 + 3 ln 100), springs linearised at grid 5
    (modal 270: (270 - 261) / 3 = 3 behind, listed), at grid 2 (264: 1 behind, but its
    neighbour) and at grid 7 (300: 13 behind, past the margin 10), a refitted mass at grid 9
    (another kind, never listed), and a refitted spring at grid 6 (modal 267: 2 behind) that
    ``set_aside`` leaves out (it predicts the named fit's data, or the held-out modes contradict
    it). Nothing refitted is listed, so the note names no separating measurement; with a margin
    of 1 nothing is listed."""
    from pipeline.diagnose.rounds import sites_elsewhere

    def cand(kind, grid):
        return Candidate(kind, Location(grids=(grid,)), f"{kind} {grid}", ("x",), (0.0,), (1.0,),
                         (0.1,))

    named, mass = cand("boundary_stiffness", 1), cand("lumped_mass", 9)
    problem = _split_problem()
    fits = [SimpleNamespace(candidate=named, theta=None, evaluations=_rows(261.0, 9.0),
                            n_params=3),
            SimpleNamespace(candidate=mass, theta=None, evaluations=_rows(300.0, 9.0),
                            n_params=3),
            SimpleNamespace(candidate=cand("boundary_stiffness", 6), theta=None,
                            evaluations=_rows(267.0, 9.0), n_params=3)]
    r0 = _rows(450.0, 90.0)
    rows = []
    for grid, chi2 in ((5, 270.0), (2, 264.0), (7, 300.0)):
        step = _rows(chi2, 9.0) - r0
        rows.append(SimpleNamespace(candidate=cand("boundary_stiffness", grid),
                                    signature=step[:, None], values=np.array([1.0])))
    none = SimpleNamespace(theta=None, evaluations=r0, n_params=2)

    def near(a, b):
        return {a.grids[0], b.grids[0]} <= {1, 2}

    asked = []

    def set_aside(j):
        asked.append(j)
        return j == 2

    spread, note = sites_elsewhere(problem, r0, rows, fits, 0, none, 100, 10, 10.0, near,
                                   set_aside)
    assert asked == [2]                                  # only refits are asked about
    assert [(e["label"], e["refitted"], e["location"]["grids"]) for e in spread] == [
        ("boundary_stiffness 5", False, [5])]
    assert spread[0]["score"] == pytest.approx((270.0 - 261.0) / 3.0, rel=1e-12)
    assert note == ("boundary_stiffness boundary_stiffness 1 beats every other kind and 'none' "
                    "by the margin 10 but not its own kind at boundary_stiffness 5 (+3.0): the "
                    "kind is named, its site uncertain")
    assert sites_elsewhere(problem, r0, rows, fits, 0, none, 100, 10, 1.0, near,
                           set_aside) == ((), None)


def test_chi2_split_separates_the_modal_rows():
    """Two configurations: one with shapes (3 modes, modes 1 and 3 training, 2 kept shape
    coordinates each, 2 weighed quantities), one frequency-only (2 modes, mode 2 training, no
    weighing); the mass scale's prior sigma 0.02 at theta 0.04 is 2. Rows in the residual's
    order: the first configuration's 2 x (1 + 2) modal rows and 2 weighing rows, the second's 1
    modal row, the prior: chi^2 modal 1 + 9 + 4 + 0 + 1 + 1 + 16 = 32, stated 9 + 16 + 4 = 29,
    by hand."""
    from pipeline.diagnose.calibrate import Problem
    from pipeline.diagnose.evidence import Evaluation

    keep = np.ones((3, 3), bool)
    keep[np.arange(3), np.arange(3)] = False
    refs = (SimpleNamespace(train=np.array([True, False, True]), has_shapes=True,
                            shape_keep=keep, mass_scale={"weight": 1.0, "x_cg": 1.0},
                            whitening=None),
            SimpleNamespace(train=np.array([False, True]), has_shapes=False, shape_keep=None,
                            mass_scale={}, whitening=None))
    evs = [Evaluation(None, np.arange(3), np.array([1.0, 50.0, -3.0]),
                      np.array([[2.0, 0.0], [50.0, 50.0], [1.0, -1.0]]), np.array([3.0, -4.0]),
                      None),
           Evaluation(None, np.arange(2), np.array([70.0, 4.0]), np.zeros((2, 0)), np.zeros(0),
                      None)]
    problem = Problem(("E1", "mass"), refs, (), (), (), np.array([np.inf, 0.02]))
    modal = problem.modal_rows()
    assert modal.tolist() == [True] * 6 + [False] * 2 + [True, False]
    fit = SimpleNamespace(theta=np.array([0.05, 0.04]), evaluations=evs)
    assert chi2_split(problem, fit) == (pytest.approx(32.0, rel=1e-12),
                                         pytest.approx(29.0, rel=1e-12))


def test_round_record_judges_held_out_modes_on_the_training_dispersion():
    """n = 400 rows, 390 modal: fits A (modal chi^2 774, weighing 20) and B (1000, 0) (p 3),
    "none" (1980, 20; p 2): decide's modal dispersion c = 774 / 387 = 2, recorded as it is.
    Held-out modes (10 entries each) "none" 8, 3000, 12; A 8, 25, 12 reproduces mode 2: all
    kept, (3020 - 45) / 2 = 1487.5; B 8, 5000, 10: mode 2 left out, (20 - 18) / 2 = 1."""
    def fit(label, chi2):
        cand = Candidate("lumped_mass", Location(grids=(1,)), label, ("mass",), (0.0,), (1.0,),
                         (0.1,))
        return SimpleNamespace(candidate=cand, chi2=chi2, n_params=3, bic=0.0,
                               values=np.array([0.01]))

    none = SimpleNamespace(chi2=2000.0, n_params=2, bic=0.0)
    held = (np.array([8.0, 3000.0, 12.0]), [np.array([8.0, 25.0, 12.0]),
                                            np.array([8.0, 5000.0, 10.0])], np.array([10, 10, 10]))
    none_row, rows = (1980.0, 20.0, 2), [("lumped_mass", 1, 774.0, 20.0, 3),
                                        ("lumped_mass", 2, 1000.0, 0.0, 3)]
    *_, c = decide(none_row, rows, 10.0, 400, n_modal=390, held_out=held)
    record = round_record(0, "effect", [fit("A", 794.0), fit("B", 1000.0)], 0, 1, none, held,
                           400, (none_row, rows, 390, c))
    assert record["dispersion"] == pytest.approx(2.0, rel=1e-12)
    assert (record["n_modal"], record["none_chi2_modal"]) == (390, 1980.0)
    assert record["best"]["chi2_modal"] == 774.0 and record["best"]["chi2"] == 794.0
    assert record["best"]["held_out_modes_kept"] == [True, True, True]
    assert record["best"]["held_out_evidence"] == pytest.approx(1487.5, rel=1e-12)
    assert record["runner_up"]["held_out_modes_kept"] == [True, False, True]
    assert record["runner_up"]["held_out_evidence"] == pytest.approx(1.0, rel=1e-12)


def test_separating_measurement_across_an_added_grid():
    """Model b gained a grid (a whole joint hung on a new grid): its modes have 6 more DOFs,
    appended; the comparison runs on the DOFs of both and names the most different one."""
    import xarray as xr

    from pipeline.diagnose.gap import separating_measurement

    def modes(shape):
        n = shape.shape[1]
        return xr.Dataset({"shape": (("mode", "dof"), shape)},
                          coords={"grid": ("dof", np.repeat(np.arange(1, n // 6 + 1), 6)),
                                  "component": ("dof", np.tile(np.arange(1, 7), n // 6))})

    a = np.ones((1, 12))
    b = np.concatenate([np.ones((1, 12)), np.full((1, 6), 50.0)], axis=1)
    b[0, 7] = 3.0                                              # grid 2 component 2 differs
    ref = SimpleNamespace(test_mode=np.array([7]), name="c", has_shapes=True,
                          sensor_index=np.arange(12), shape_sigma=np.array([0.05]))
    problem = SimpleNamespace(refs=(ref,))

    def fit(shape, label):
        ev = SimpleNamespace(frequency=np.zeros(1), modes=modes(shape), paired=np.array([0]))
        return SimpleNamespace(evaluations=[ev], candidate=SimpleNamespace(kind="k", label=label))

    text = separating_measurement(problem, fit(a, "A"), fit(b, "B"))
    assert "grid 2 component 2" in text


@pytest.mark.parametrize("pair_chi2, side_chi2, kept", [(373.8, 382.1, False),
                                                        (340.0, 382.1, True)])
def test_a_pair_is_named_only_when_it_beats_its_side_alone_by_the_margin(monkeypatch, pair_chi2,
                                                                          side_chi2, kept):
    """The frame's 'none' seed 8 (measured): a mirror pair of grounded springs at chi^2 373.8
    against 382.1 for one of its sides, same parameter count, 375 modal rows (c = 1): the lead
    8.3 < 10, so the pair is left out and the side (refitted here, it was not among the fits)
    stays; a pair at 340.0 leads by 42 and stays, the side's fit added beside it."""
    from pipeline.diagnose import rounds, workflow
    from pipeline.diagnose.mirror import _pair
    from pipeline.diagnose.screen import Screened

    def spring(grid):
        return Candidate("boundary_stiffness", Location(grids=(grid,)), f"grid {grid} y",
                         ("k_y",), (0.0,), (1.0,), (0.1,), (("direction", "y"), ("k_ref", 1.0)))

    side, image = spring(6102), spring(6002)
    pair = _pair(side, image, ((1.0,), (1.0,)))
    other = spring(2009)

    def fit(cand, chi2):
        return SimpleNamespace(candidate=cand, chi2=chi2, n_params=3)

    problem = SimpleNamespace(modal_rows=lambda: np.ones(375, bool))
    for module in (workflow, rounds):
        monkeypatch.setattr(module, "chi2_split", lambda problem, f: (f.chi2, 0.0))
    refitted = []

    def refit(problem, theta, effects, row, **kw):
        refitted.append(row.candidate)
        return fit(row.candidate, side_chi2)

    monkeypatch.setattr(workflow, "refit", refit)
    rows = [Screened(c, np.array([0.02]), 0.0, drop, None)
            for c, drop in ((pair, 30.0), (side, 20.0), (image, 5.0), (other, 3.0))]
    fits = [fit(pair, pair_chi2), fit(other, 395.0)]
    none = fit(None, 406.0)
    out, dropped = workflow._prefer_one_side(problem, None, (), rows, fits, none, 375, 10.0, None)
    assert refitted == [side]                     # the better-screened side, refitted once
    assert [f.candidate for f in out] == ([pair, other, side] if kept else [other, side])
    assert dropped is (None if kept else pair)


def test_a_named_joint_is_not_offered_again():
    """Hung at its independent grid, engine mount RBE2 7501 stays rigid on a new grid: the next
    round's library holds a joint of 7501 at that grid, which :func:`unnamed` leaves out with
    every other joint of 7501 (a second spring in series would refit the same joint); its
    mirror image 7601 and the other kinds at the same grids stay."""
    x56 = read_model(Path(__file__).parents[3] / "data" / "x56_like" / "x56_efew.bdf")
    joint = next(c for c in candidates(x56, ("joint_flexibility",))
                 if c.label == "RBE2 7501 (5011-5021)")
    named = [(joint, np.array([30.0, -0.2]))]
    hung = apply_effect(x56, joint, named[0][1])
    (moved,) = [r for r in hung.rigid if r.eid == 7501]
    assert moved.independent[0][0] not in x56.grids.ids
    again = candidates(hung, ("joint_flexibility", "lumped_mass"))
    assert any(c.location.elements == (7501,) and moved.independent[0][0] in c.location.grids
               for c in again)
    kept = unnamed(again, named)
    assert not any(7501 in s.location.elements for c in kept for s in sites(c)
                   if s.kind == "joint_flexibility")
    assert any(c.location.elements == (7601,) for c in kept)
    assert any(c.kind == "lumped_mass" and c.location.grids == (5021,) for c in kept)


def test_a_mass_per_grid_covers_its_grids(tmp_path):
    """Named with one share per grid of 3007's neighbourhood (3006, 3007, 3008, 3107, 3207), a
    mass leaves the next round's library without the masses on those grids alone (the point
    masses, the spreads of 3107 and 3007 over them, and the mirror pairs with a site among
    them: its shares are free there), as a point mass named at 3007 leaves out 3007 and its
    pairs; a spread reaching past them (3008's, to 3009), the masses elsewhere and the other
    kinds at those grids stay."""
    model = read_model(frame.write_frame(tmp_path))
    cands = candidates(model, ("lumped_mass", "boundary_stiffness"))
    point = next(c for c in cands if c.label == "grid 3007")
    rich, values = distributed(model, point, [0.02, 0.0])
    kept = {c.label for c in unnamed(cands, [(rich, values)])}
    gone = {c.label for c in cands} - kept
    alone = {"grid 3006", "grid 3007", "grid 3008", "grid 3107", "grid 3207",
             "grid 3107 spread over 3007, 3207", "grid 3007 spread over 3006, 3008, 3107, 3207"}
    assert alone | {"grid 2007 and its mirror image grid 3007"} <= gone
    assert all(c.kind == "lumped_mass" and (c.label in alone or "mirror image grid 3" in c.label)
               for c in cands if c.label in gone)
    assert {"grid 3008 spread over 3007, 3009, 3108, 3208", "grid 3009", "grid 3007 z",
            "grid 2007"} <= kept
