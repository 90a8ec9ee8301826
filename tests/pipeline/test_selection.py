"""Primary / secondary mode selection (pipeline.selection) and its figures.

Analytic cases are hand-made participation Datasets whose answer is worked out in the comments;
the exact search is checked against brute-force enumeration of every subset; the real-sweep check
runs the BAH deck through the pipeline's chain and compares with the same enumeration.
"""
from __future__ import annotations

import io
import warnings
from itertools import combinations
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.selection import (ordinal, select_modes, selection_study, selection_table,
                                smallest_cover, study_table)
from pipeline.selection_plots import ROLE_COLOURS, plot_participation, plot_selection_study
from structures.common.errors import InputError
from structures.common.files import read_dataset, write_dataset

DATA = Path(__file__).resolve().parents[2] / "data" / "bah_wing"


def participation(P, modes, rigid=(), flutter_mode=None, mach=0.2, name="EFEW"):
    """A participation.nc Dataset (pipeline.chain layout) from rows of shares [%]."""
    P = np.asarray(P, dtype=float).reshape(-1, len(modes))
    n = len(P)
    fm = np.arange(1, n + 1) if flutter_mode is None else np.asarray(flutter_mode)
    point = "flutter_point"
    return xr.Dataset(
        {"participation": ((point, "mode"), P, {"units": "%"})},
        coords={"case": (point, np.zeros(n, int)), "mach": (point, np.full(n, mach)),
                "density": (point, np.full(n, 1.225)), "velocity": (point, 100.0 + 10 * np.arange(n)),
                "frequency": (point, np.full(n, 3.0)), "root": (point, np.arange(n)),
                "flutter_mode": (point, fm), "mode": ("mode", np.asarray(modes, int)),
                "rigid": ("mode", np.isin(modes, rigid)),
                "fe_frequency": ("mode", np.where(np.isin(modes, rigid), 0.0,
                                                  np.asarray(modes, float)))},
        attrs={"configuration": name, "units": "si", "rigid_hz": 0.05})


def roles(sel, config="EFEW"):
    r = sel["role"].sel(configuration=config)
    return {role: [int(m) for m in sel["mode"].values[r.values == role]]
            for role in ("rigid", "primary", "secondary")}


def brute_force(P, rigid, target):
    """Reference: the smallest set of flexible columns reaching ``target`` [%] in every row, by
    enumerating every subset (largest minimum total, then lowest ids, on a tie)."""
    flex = np.flatnonzero(~rigid)
    base = P[:, rigid].sum(axis=1)
    for k in range(len(flex) + 1):
        good = []
        for c in combinations(flex, k):
            total = base + P[:, list(c)].sum(axis=1)
            if np.all(total >= target - 1e-6):
                good.append((-np.round(total.min(), 9), c))
        if good:
            return list(min(good)[1])
    raise AssertionError("no subset reaches the target")


# --- analytic cases -----------------------------------------------------------------------------

def test_exact_search_finds_two_modes_where_greedy_needs_three():
    # two roots, no rigid modes, threshold 60 %: modes 3 = (50, 10), 4 = (10, 50), 5 = (35, 35),
    # 6 = (5, 5). {3, 4} gives (60, 60): two modes suffice. Mode 5 has the largest share in both
    # roots, so picking by largest share (or max-min greedy) starts with 5 and then needs 3 and 4:
    # (85, 45) -> (95, 95), three modes.
    P = [[50, 10, 35, 5], [10, 50, 35, 5]]
    sel = select_modes({"EFEW": participation(P, [3, 4, 5, 6])}, primary=0.6, secondary=0.98)
    assert roles(sel)["primary"] == [3, 4]
    assert str(sel["search"].sel(configuration="EFEW").values) == "exact"
    np.testing.assert_allclose(sel["primary_total"].values, [60.0, 60.0], atol=1e-12)
    # secondary from {5, 6} on top of (60, 60): 5 -> (95, 95) < 98, so both: (100, 100)
    assert roles(sel)["secondary"] == [5, 6]
    np.testing.assert_allclose(sel["secondary_total"].values, [100.0, 100.0], atol=1e-12)
    # the greedy fallback (search bound 0) on the same data picks three modes
    cols, exact = smallest_cover(np.array(P, float), np.zeros(2), 60.0, max_nodes=0)
    assert not exact and list(cols) == [0, 1, 2]


def test_tie_goes_to_the_largest_minimum_total():
    # one mode reaches 40 % in both roots either way: mode 3 = (40, 55) has min 40 and the larger
    # sum; mode 4 = (45, 42) has min 42 -> mode 4. Secondary (98 %) from {3, 5} on (45, 42):
    # 3 -> (85, 97), 5 -> (60, 45), both -> (100, 100).
    P = [[40, 45, 15], [55, 42, 3]]
    sel = select_modes({"EFEW": participation(P, [3, 4, 5])}, primary=0.4, secondary=0.98)
    assert roles(sel)["primary"] == [4]
    assert roles(sel)["secondary"] == [3, 5]


def test_exact_tie_goes_to_the_lower_mode_id():
    # rigid 50 %, modes 3 and 4 both 20 %, mode 5 10 %: 70 % needs one of 3 / 4 (same totals) -> 3;
    # 80 % on top of 70: 4 -> 90, 5 -> 80: both reach it, 4 has the larger total.
    P = [[50, 20, 20, 10]]
    sel = select_modes({"EFEW": participation(P, [1, 3, 4, 5], rigid=[1])}, primary=0.7, secondary=0.8)
    assert roles(sel) == {"rigid": [1], "primary": [3], "secondary": [4]}


def test_rigid_modes_count_towards_both_thresholds():
    # rigid 30 + 25 = 55 %; flexible 3 = 36, 4 = 9. Primary 90: 55 + 36 = 91 -> {3}; without the
    # rigid share 3 and 4 would give only 45. Secondary 98: 91 + 9 = 100 -> {4}.
    P = [[30, 25, 36, 9]]
    sel = select_modes({"EFEW": participation(P, [1, 2, 3, 4], rigid=[1, 2])})
    assert roles(sel) == {"rigid": [1, 2], "primary": [3], "secondary": [4]}
    assert sel["primary_total"].values[0] == pytest.approx(91.0, abs=1e-12)
    assert sel["secondary_total"].values[0] == pytest.approx(100.0, abs=1e-12)


def test_rigid_modes_alone_reach_the_primary_threshold():
    # rigid 92 %: no primary mode; secondary 98 needs 6 more: mode 3 (5) is short, mode 4 (3) too,
    # both give 100 -> {3, 4}
    P = [[92, 5, 3]]
    sel = select_modes({"EFEW": participation(P, [1, 3, 4], rigid=[1])})
    assert roles(sel) == {"rigid": [1], "primary": [], "secondary": [3, 4]}
    assert sel["primary_total"].values[0] == pytest.approx(92.0)


def test_secondary_modes_are_disjoint_from_primary():
    # 3 = 60, 4 = 30, 5 = 8, 6 = 2: primary 90 -> {3, 4}; secondary 98 from the rest -> {5}
    P = [[60, 30, 8, 2]]
    sel = select_modes({"EFEW": participation(P, [3, 4, 5, 6])})
    r = roles(sel)
    assert r["primary"] == [3, 4] and r["secondary"] == [5]
    assert not set(r["primary"]) & set(r["secondary"])
    # secondary total = primary total + the secondary shares
    assert sel["secondary_total"].values[0] == pytest.approx(sel["primary_total"].values[0] + 8.0)


def test_two_roots_needing_different_modes_give_the_union():
    # root 1: rigid 10, mode 3 = 85, mode 4 = 5; root 2: rigid 10, 3 = 2, 4 = 83, 5 = 5.
    # {3}: (95, 12); {4}: (15, 93); {3, 4}: (100, 95) -> primary {3, 4}; secondary 98: + 5 -> (100, 100)
    P = [[10, 85, 5, 0], [10, 2, 83, 5]]
    sel = select_modes({"EFEW": participation(P, [1, 3, 4, 5], rigid=[1])})
    assert roles(sel)["primary"] == [3, 4]
    assert roles(sel)["secondary"] == [5]
    np.testing.assert_allclose(sel["primary_total"].values, [100.0, 95.0], atol=1e-12)
    # each root alone needs a single mode (the study), together two
    study = selection_study({"EFEW": participation(P, [1, 3, 4, 5], rigid=[1])}, [0.9])
    assert study["n_modes"].values.tolist() == [[1, 1]]
    assert study["n_primary"].values.tolist() == [[2]]
    assert str(study["primary_modes"].values[0, 0]) == "3, 4"


def test_only_the_first_flutter_modes_are_critical():
    # the 3rd flutter mode is carried by mode 5 alone; with flutter_modes = 2 it does not count
    P = [[10, 85, 5, 0], [10, 80, 10, 0], [10, 0, 0, 90]]
    ds = participation(P, [1, 3, 4, 5], rigid=[1], flutter_mode=[1, 2, 3])
    assert roles(select_modes({"EFEW": ds}, flutter_modes=2))["primary"] == [3]
    assert roles(select_modes({"EFEW": ds}, flutter_modes=3))["primary"] == [3, 5]
    sel = select_modes({"EFEW": ds})
    assert sel["critical"].values.tolist() == [True, True, False]
    assert int(sel["critical_roots"].values[0]) == 2


def test_a_configuration_without_flutter_crossings():
    flutter = participation([[10, 85, 5]], [1, 3, 4], rigid=[1])
    none = participation(np.zeros((0, 3)), [1, 3, 4], rigid=[1], name="FFFW")
    sel = select_modes({"EFEW": flutter, "FFFW": none})
    assert roles(sel, "FFFW") == {"rigid": [1], "primary": [], "secondary": []}
    assert str(sel["search"].sel(configuration="FFFW").values) == "no critical roots"
    assert sel.attrs["without_critical_roots"] == "FFFW"
    assert "FFFW" in sel.attrs["note"]
    assert "configuration FFFW: no critical flutter roots" in selection_table(sel)
    assert sel.sizes["flutter_point"] == 1
    study = selection_study({"EFEW": flutter, "FFFW": none}, [0.9])
    assert study["critical_roots"].values.tolist() == [1, 0]
    assert "FFFW: no critical flutter roots" in study_table(study)


def test_configurations_with_different_modes_share_the_mode_dimension():
    a = participation([[10, 85, 5]], [1, 3, 4], rigid=[1])
    b = participation([[10, 60, 25, 5]], [1, 3, 4, 6], rigid=[1], name="FFFW")
    sel = select_modes({"EFEW": a, "FFFW": b})
    assert sel["mode"].values.tolist() == [1, 3, 4, 6]
    assert np.isnan(sel["fe_frequency"].sel(configuration="EFEW", mode=6))
    assert str(sel["role"].sel(configuration="EFEW", mode=6).values) == ""
    assert np.isnan(sel["participation"].values[0, 3])
    assert roles(sel, "FFFW")["primary"] == [3, 4]
    assert sel["point_configuration"].values.tolist() == ["EFEW", "FFFW"]


@pytest.mark.parametrize("primary, secondary, key", [
    (0.0, 0.98, "primary"), (-0.1, 0.98, "primary"), (90.0, 98.0, "primary"),
    (0.95, 0.9, "secondary"), (0.9, 1.2, "secondary"), (float("nan"), 0.98, "primary")])
def test_thresholds_are_validated(primary, secondary, key):
    ds = participation([[10, 85, 5]], [1, 3, 4], rigid=[1])
    with pytest.raises(InputError, match=rf"\[selection\] {key}.*Fix:"):
        select_modes({"EFEW": ds}, primary=primary, secondary=secondary)


def test_bad_inputs_are_refused():
    ds = participation([[10, 85, 5]], [1, 3, 4], rigid=[1])
    with pytest.raises(InputError, match="sums to 90.*Fix:"):
        select_modes({"EFEW": participation([[10, 75, 5]], [1, 3, 4], rigid=[1])})
    with pytest.raises(InputError, match="lacks coordinates.*rigid"):
        select_modes({"EFEW": ds.drop_vars("rigid")})
    with pytest.raises(InputError, match="pairing.*FE mode 7.*Fix:"):
        select_modes({"EFEW": ds}, pairing={"EFEW": {7: 1}})
    with pytest.raises(InputError, match="pairing.*'FFFW'"):
        select_modes({"EFEW": ds}, pairing={"FFFW": {3: 1}})
    with pytest.raises(InputError, match="flutter_modes"):
        select_modes({"EFEW": ds}, flutter_modes=0)
    with pytest.raises(InputError, match="no configuration"):
        select_modes({})
    with pytest.raises(InputError, match="--thresholds"):
        selection_study({"EFEW": ds}, [])
    with pytest.raises(InputError, match=r"--thresholds: thresholds \[90.0\].*Fix:"):
        selection_study({"EFEW": ds}, [0.85, 90.0])
    with pytest.raises(InputError, match="flutter_modes"):
        selection_study({"EFEW": ds}, [0.9], flutter_modes=0)
    with pytest.raises(InputError, match="unit systems"):
        select_modes({"EFEW": ds, "FFFW": ds.assign_attrs(units="english_in")})


def test_pairing_fills_the_test_modes_and_the_table():
    ds = participation([[10, 85, 5]], [1, 3, 4], rigid=[1])
    sel = select_modes({"EFEW": ds}, pairing={"EFEW": {3: 7, 4: 9}})
    assert sel["test_mode"].sel(configuration="EFEW").values.tolist() == [0, 7, 9]
    lines = selection_table(sel).splitlines()
    row = next(line for line in lines if line.split()[:1] == ["3"])
    assert row.split() == ["3", "3", "7", "primary", "85.0"]


def test_table_follows_table_6_layout():
    P = [[8.0, 1.0, 86.0, 4.5, 0.5], [2.0, 0.0, 9.0, 0.6, 88.4]]
    sel = select_modes({"EFEW": participation(P, [1, 2, 3, 4, 6], rigid=[1, 2])})
    text = selection_table(sel)
    lines = [line.split() for line in text.splitlines()]
    # rows: rigid modes, primary modes, Total, secondary modes, Total, the rest
    order = [row[0] for row in lines if row and row[0] in {"1", "2", "3", "4", "6", "Total"}]
    assert order == ["1", "2", "3", "6", "Total", "4", "Total"]
    totals = [row[-2:] for row in lines if row and row[0] == "Total"]
    # root 1: 8 + 1 + 86 + 0.5 = 95.5 and + 4.5 = 100; root 2: 2 + 9 + 88.4 = 99.4, + 0.6 = 100
    assert totals == [["95.5", "99.4"], ["100.0", "100.0"]]
    assert ["M=0.200", "M=0.200"] in [row[-2:] for row in lines]
    assert ["1st", "2nd"] in [row[-2:] for row in lines]
    assert any(row[:2] == ["V", "[m/s]"] for row in lines)


def test_selection_round_trips_through_netcdf(tmp_path):
    P = [[10, 85, 5, 0], [10, 2, 83, 5]]
    sel = select_modes({"EFEW": participation(P, [1, 3, 4, 5], rigid=[1]),
                        "FFFW": participation(np.zeros((0, 4)), [1, 3, 4, 5], rigid=[1])},
                       pairing={"EFEW": {3: 7}})
    back = read_dataset(write_dataset(sel, tmp_path / "selection.nc"))
    assert selection_table(back) == selection_table(sel)
    assert back["role"].values.astype(str).tolist() == sel["role"].values.tolist()
    assert back.attrs["primary_threshold"] == 0.9 and back.attrs["secondary_threshold"] == 0.98
    assert back["participation"].attrs["units"] == "%"
    assert back["velocity"].attrs["units"] == "m/s" and back["frequency"].attrs["units"] == "Hz"


# --- properties ---------------------------------------------------------------------------------

@st.composite
def random_case(draw):
    n_points = draw(st.integers(1, 4))
    n_rigid = draw(st.integers(0, 2))
    n_flex = draw(st.integers(1, 7))
    n = n_rigid + n_flex
    w = np.array(draw(st.lists(st.floats(0.0, 1.0), min_size=n * n_points, max_size=n * n_points)))
    w = w.reshape(n_points, n) + 1e-3
    P = 100.0 * w / w.sum(axis=1, keepdims=True)
    modes = list(range(1, n + 1))
    return participation(P, modes, rigid=modes[:n_rigid], flutter_mode=np.ones(n_points, int))


@settings(max_examples=60, deadline=None)
@given(random_case(), st.floats(0.05, 1.0), st.floats(0.0, 1.0))
def test_exact_search_matches_brute_force(ds, primary, extra):
    secondary = primary + extra * (1.0 - primary)
    sel = select_modes({"EFEW": ds}, primary=primary, secondary=secondary)
    P, rigid = ds["participation"].values, ds["rigid"].values
    flex_ids = ds["mode"].values
    expect_primary = brute_force(P, rigid, 100 * primary)
    assert roles(sel)["primary"] == [int(flex_ids[j]) for j in expect_primary]
    rest = rigid.copy()
    rest[expect_primary] = True  # the primary modes count like the rigid ones for the secondary
    expect_secondary = brute_force(P, rest, 100 * secondary)
    assert roles(sel)["secondary"] == [int(flex_ids[j]) for j in expect_secondary]
    assert np.all(sel["primary_total"].values >= 100 * primary - 1e-6)
    assert np.all(sel["secondary_total"].values >= 100 * secondary - 1e-6)
    # the greedy fallback still reaches the threshold (with at least as many modes)
    flex = ~rigid
    cols, exact = smallest_cover(P[:, flex], P[:, rigid].sum(axis=1), 100 * primary, max_nodes=0)
    assert len(cols) >= len(expect_primary)
    assert np.all(P[:, rigid].sum(axis=1) + P[:, flex][:, cols].sum(axis=1) >= 100 * primary - 1e-6)


@settings(max_examples=60, deadline=None)
@given(random_case(), st.lists(st.floats(0.05, 1.0), min_size=1, max_size=6))
def test_study_needs_more_modes_for_higher_thresholds(ds, thresholds):
    study = selection_study({"EFEW": ds}, thresholds)
    assert np.all(np.diff(study["threshold"].values) > 0)
    assert np.all(np.diff(study["n_modes"].values, axis=0) >= 0)
    assert np.all(np.diff(study["n_primary"].values, axis=0) >= 0)
    # one root alone needs at most what all roots together need, and a root's count is exact
    assert np.all(study["n_modes"].values <= study["n_primary"].values)
    P, rigid = ds["participation"].values, ds["rigid"].values
    for t, counts in zip(study["threshold"].values, study["n_modes"].values):
        assert counts.tolist() == [len(brute_force(P[[p]], rigid, 100 * t)) for p in range(len(P))]


# --- the real sweep: BAH wing through the pipeline's chain --------------------------------------

@pytest.fixture(scope="module")
def bah_participation():
    """Participation of the BAH wing's flutter roots at M 0.2 and three densities, 30-1200 m/s."""
    from flutter.solve import FlutterRequest, solve_flutter
    from pipeline.chain import deck_modes, flutter_chain, flutter_participation

    deck = DATA / "bah_plane.bdf"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the deck's k range and box size warnings
        chain = flutter_chain(deck, deck_modes(deck), flutter_ids=[502], units="si")
        request = FlutterRequest(sid=1, method="PK", density=(0.4, 0.8, 1.225), mach=(0.2,),
                                 values=tuple(np.arange(30.0, 1201.0, 15.0)))
        results = solve_flutter(chain["modes"], chain["gaf"], [request], units="si")
    return chain, flutter_participation(results, chain["modes"], units="si", configuration="bah")


def test_selection_on_the_bah_sweep_matches_enumeration(bah_participation):
    chain, part = bah_participation
    # the deck's own FLUTTER 502 point (Nastran: 394.0 m/s, 3.18 Hz) is the 1st root at 1.225
    first = chain["participation"]
    assert first["velocity"].values[0] == pytest.approx(394.0, rel=0.01)
    P, rigid = part["participation"].values, part["rigid"].values
    np.testing.assert_allclose(P.sum(axis=1), 100.0, atol=1e-9)
    crit = part["flutter_mode"].values <= 2
    assert crit.sum() == 6  # 1st and 2nd flutter mode at each of the three densities
    sel = select_modes({"bah": part}, pairing={"bah": {3: 1, 6: 2}})
    r = roles(sel, "bah")
    assert r["rigid"] == [1, 2]
    modes = part["mode"].values
    assert r["primary"] == [int(modes[j]) for j in brute_force(P[crit], rigid, 90.0)]
    primary = np.isin(modes, r["primary"])
    assert r["secondary"] == [int(modes[j]) for j in brute_force(P[crit], rigid | primary, 98.0)]
    # the 1st flutter mode is carried by mode 3 (2.45 Hz), the 2nd by mode 6 (9.0 Hz): the union
    assert r["primary"] == [3, 6]
    assert np.all(sel["primary_total"].values[crit] >= 90.0)
    assert np.all(sel["secondary_total"].values[crit] >= 98.0)
    assert str(sel["search"].values[0]) == "exact"
    study = selection_study({"bah": part}, [0.5, 0.9, 0.95, 0.98])
    assert study["n_primary"].values[:, 0].tolist() == [
        len(brute_force(P[crit], rigid, 100 * t)) for t in (0.5, 0.9, 0.95, 0.98)]
    assert study["n_modes"].values[0].tolist() == [1] * 6


# --- figures ------------------------------------------------------------------------------------

def test_figures(bah_participation):
    _, part = bah_participation
    sel = select_modes({"bah": part})
    fig = plot_participation(sel)
    axes = fig.get_axes()
    assert len(axes) == 6
    colours = {tuple(np.round(b.get_facecolor(), 3)) for b in axes[0].patches}
    from matplotlib.colors import to_rgba
    assert tuple(np.round(to_rgba(ROLE_COLOURS["primary"]), 3)) in colours
    assert tuple(np.round(to_rgba(ROLE_COLOURS["rigid"]), 3)) in colours
    study = selection_study({"bah": part}, [0.5, 0.9, 0.95, 0.98])
    fig = plot_selection_study(study)
    lines = fig.get_axes()[0].get_lines()
    assert len(lines) == 6 + 1  # one per critical root, one for the joint selection
    np.testing.assert_array_equal(lines[-1].get_ydata(), study["n_primary"].values[:, 0])
    for f in (fig, plot_participation(select_modes({"E": participation(np.zeros((0, 2)), [1, 2])}))):
        buffer = io.BytesIO()
        f.savefig(buffer, format="png")
        assert buffer.tell() > 1000


def test_ordinal_names_of_flutter_modes():
    # English ordinals: 11th-13th (and 111th-113th) take "th", 21st / 22nd / 23rd do not
    names = {1: "1st", 2: "2nd", 3: "3rd", 4: "4th", 11: "11th", 12: "12th", 13: "13th",
             21: "21st", 22: "22nd", 23: "23rd", 101: "101st", 111: "111th", 112: "112th"}
    assert {n: ordinal(n) for n in names} == names
