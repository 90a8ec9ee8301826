"""pipeline.loop: the loop's tuning terms from a selection and the stop rule, on hand-made data
whose answers are worked out by hand in each test."""
from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np
import pytest
import xarray as xr

import structures.tuning
from pipeline.loop import (MASS_TOLERANCE, START_BUFFER, evaluate_targets, loop_terms,
                           relaxed_at_start, tuned_test_modes)
from structures.acceptance import MIL_STD_1540C, NASA_STD_5002
from structures.common.errors import InputError


def _selection(roles, tests, config="a"):
    return xr.Dataset({"role": (("configuration", "mode"), np.array([roles], dtype=object)),
                       "test_mode": (("configuration", "mode"), np.array([tests]))},
                      coords={"configuration": [config], "mode": np.arange(1, len(roles) + 1)})


def _correlation(freq_error, paired, S):
    """Three test modes 1..3 against five FE modes 1..5."""
    return xr.Dataset({"frequency_error": ("test_mode", np.asarray(freq_error, float)),
                       "paired_fe_mode": ("test_mode", np.asarray(paired)),
                       "cross_orthogonality": (("test_mode", "fe_mode"), np.asarray(S, float))},
                      coords={"test_mode": [1, 2, 3], "fe_mode": [1, 2, 3, 4, 5]})


SEL = _selection(["rigid", "rigid", "primary", "primary", "secondary"], [0, 0, 1, 2, 3])


def test_tuned_test_modes_follow_the_pairing():
    assert tuned_test_modes(SEL, "a") == ([1, 2], [3])


def test_loop_terms_by_hand():
    objective, constraints, modes = loop_terms(SEL, ["a"], MIL_STD_1540C, {"a": {"weight": 1.0}})
    assert dict(objective) == {"a:frequency:1": 1.0, "a:frequency:2": 1.0,
                               "a:cross_orthogonality:1-2": 1.0, "a:cross_orthogonality:2-1": 1.0}
    expected = {"a:frequency:3": 0.03 ** 2,
                **{f"a:cross_orthogonality:{i}-{j}": 0.1 ** 2
                   for i, j in ((1, 3), (3, 1), (2, 3), (3, 2))},
                **{f"a:orthogonality:{i}-{j}": 0.1 ** 2 for i, j in ((1, 2), (1, 3), (2, 3))},
                "a:mass:weight": (MASS_TOLERANCE / 100) ** 2}
    assert dict(constraints).keys() == expected.keys()
    for name, eps in constraints:
        assert eps == pytest.approx(expected[name], rel=1e-15)
    assert modes == {"a": (1, 2, 3)}
    # NASA-STD-5002: secondary frequency limit 10 %
    _, constraints, _ = loop_terms(SEL, ["a"], NASA_STD_5002, {})
    assert dict(constraints)["a:frequency:3"] == pytest.approx(0.1 ** 2)


def test_loop_terms_without_paired_primary_modes_raise():
    sel = _selection(["rigid", "primary", "", "", ""], [0, 0, 1, 2, 3])
    with pytest.raises(InputError, match="nothing to tune"):
        loop_terms(sel, ["a"], MIL_STD_1540C, {})


def test_targets_by_hand():
    S = np.full((3, 5), 0.01)
    S[0, 3] = 0.05          # test 1 against FE 4 (the pair of test 2): within 0.10
    S[1, 2] = 0.20          # test 2 against FE 3 (the pair of test 1): misses 0.10
    S[2, 2] = 0.50          # test 3 (secondary) against FE 3: not a primary-block term
    corr = _correlation([1.0, -4.0, 2.0], [3, 4, 5], S)
    t = evaluate_targets(SEL, {"a": corr}, MIL_STD_1540C, stage=0, last_stage=2)
    assert not t["met"] and t["stop_reason"] == ""
    failing = {(f["check"], f["test_mode"], f["fe_mode"]): f["value"] for f in t["failing"]}
    assert failing == {("frequency error [%]", 2, 4): -4.0,
                       ("cross-orthogonality off-diagonal", 2, 3): pytest.approx(0.20)}
    # NASA-STD-5002: 5 % primary frequency passes test mode 2; the off-diagonal still fails
    t = evaluate_targets(SEL, {"a": corr}, NASA_STD_5002, stage=2, last_stage=2)
    assert [f["check"] for f in t["failing"]] == ["cross-orthogonality off-diagonal"]
    assert "last stage" in t["stop_reason"]
    S[1, 2] = 0.09
    t = evaluate_targets(SEL, {"a": _correlation([1.0, -2.9, 9.0], [3, 4, 5], S)},
                         MIL_STD_1540C, stage=1, last_stage=2)
    assert t["met"] and t["failing"] == [] and "stage 1" in t["stop_reason"]


def test_targets_unpaired_primary_mode_fails_and_no_roots_stops():
    sel = _selection(["rigid", "rigid", "primary", "primary", ""], [0, 0, 1, 0, 0])
    corr = _correlation([0.0, 0.0, 0.0], [3, 4, 5], np.zeros((3, 5)))
    t = evaluate_targets(sel, {"a": corr}, MIL_STD_1540C, stage=0, last_stage=1)
    assert [(f["check"], f["fe_mode"]) for f in t["failing"]] == [("paired test mode", 4)]
    none = _selection(["rigid", "rigid", "", "", ""], [0, 0, 1, 2, 3])
    t = evaluate_targets(none, {"a": corr}, MIL_STD_1540C, stage=0, last_stage=1)
    assert t["met"] and "no critical flutter root" in t["stop_reason"]


@dataclass(frozen=True)
class _Problem:
    constraints: tuple


class _Evaluator:
    """Stands in for structures.tuning.Evaluator: four constraints (two J <= eps, two MAC J >= eps)
    and one objective term, with index values fixed by hand."""

    calls: list = []

    def __init__(self, problem):
        self.space = SimpleNamespace(x0=np.array([1.0, 2.0]))
        self.names = ["a:frequency:3", "a:mass:weight", "a:mac:1", "a:mac:2", "a:frequency:1"]
        self.limits = np.array([9e-4, 1e-4, 0.9, 0.9, np.nan])
        self.lower_is_better = np.array([True, True, False, False, True])
        self.con_index = np.array([0, 1, 2, 3])

    def evaluate(self, x):
        _Evaluator.calls.append(np.asarray(x))
        return np.array([4e-4, 3e-4, 0.95, 0.8, 0.5]), None


def test_relaxed_at_start_by_hand(monkeypatch):
    monkeypatch.setattr(structures.tuning, "Evaluator", _Evaluator)
    _Evaluator.calls.clear()
    problem, relaxed = relaxed_at_start(_Problem(constraints=(("a:*", 1.0),)))
    np.testing.assert_array_equal(_Evaluator.calls[-1], [1.0, 2.0])   # the decks' design
    # met constraints keep their limit; a violated J <= eps gets J(start) x 1.02, a violated
    # MAC J >= eps gets J(start) / 1.02; the objective term (no limit) is not a constraint
    assert START_BUFFER == 1.02
    assert dict(problem.constraints) == pytest.approx(
        {"a:frequency:3": 9e-4, "a:mass:weight": 3e-4 * 1.02, "a:mac:1": 0.9,
         "a:mac:2": 0.8 / 1.02}, rel=1e-15)
    assert relaxed == [("a:mass:weight", 1e-4, pytest.approx(3.06e-4, rel=1e-15)),
                       ("a:mac:2", 0.9, pytest.approx(0.8 / 1.02, rel=1e-15))]
    relaxed_at_start(_Problem(constraints=()), start=np.array([3.0, 4.0]))
    np.testing.assert_array_equal(_Evaluator.calls[-1], [3.0, 4.0])   # the given start
