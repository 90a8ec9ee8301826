"""The notes a round adds (:mod:`pipeline.diagnose.round_notes`): each branch says what the
verdict did, with the numbers it used."""
from types import SimpleNamespace

import numpy as np

from pipeline.diagnose.round_notes import (bound_note, held_out_veto_note, load_path_note,
                                           located_note, past_veto_note, reversal_note,
                                           unconfirmed_note, undetermined_note)

MASS = SimpleNamespace(kind="lumped_mass", label="grid 3009")
JOINT = SimpleNamespace(kind="joint_flexibility", label="RBE2 7003")


def test_bound_note_says_whether_the_data_press():
    pressed = bound_note(0, MASS, ["mass"], True, 60.0, 2.0, 10.0)
    assert "data want more" in pressed and "30.0 after the dispersion 2.00" in pressed
    assert "not named" in pressed
    below = bound_note(1, MASS, ["mass"], True, 10.0, 2.0, 10.0)
    assert below.startswith("round 2") and "do not press" in below and "5.0" in below
    inward = bound_note(0, MASS, ["mass"], False, 0.0, 1.0, 10.0)
    assert inward.endswith("moves it inward).")


def test_load_path_note_names_the_path_and_the_outcome():
    path = (SimpleNamespace(grids=(11, 42), stiffness=1234.5), 100.0, 120.0)
    worse = load_path_note(0, MASS, path, "unexplained")
    assert "grids 11 and 42" in worse and "k = 1234" in worse
    assert worse.endswith("outside the library.")
    tie = load_path_note(0, MASS, path, "ambiguous")
    assert "within the margin" in tie and "outside" not in tie


def test_held_out_veto_sums_only_the_modes_either_model_reproduces():
    none = SimpleNamespace(chi2=500.0)
    fit = SimpleNamespace(chi2=300.0)
    modes_none, modes = np.array([10.0, 20.0, 1000.0]), np.array([40.0, 50.0, 5.0])
    record = {"held_out_modes_kept": [True, True, False], "held_out_evidence": -23.0}
    text = held_out_veto_note(0, MASS, none, fit, modes_none, modes, record)
    assert "the 2 held-out modes" in text and "chi^2 30 -> 90" in text
    assert "chi^2 500 -> 300" in text and "not named" in text


def test_past_veto_note_lists_the_vetoed_and_the_evidence():
    text = past_veto_note(2, JOINT, ["lumped_mass grid 5", "member_taper PID 7"], 14.2, 3.25)
    assert text.startswith("round 3") and "grid 5; member_taper PID 7" in text
    assert "by 14.2" in text and "+3.2" in text


def test_unconfirmed_note_quotes_the_lead_and_the_evidence():
    text = unconfirmed_note(1, JOINT, 168.2, -3.6, 10.0)
    assert text.startswith("round 2: joint_flexibility RBE2 7003 beats the rest")
    assert "by 168.2" in text and "margin 10" in text and "(evidence -3.6)" in text
    assert text.endswith("not named.")


def test_reversal_note_quotes_both_rankings():
    fits = [SimpleNamespace(candidate=MASS), SimpleNamespace(candidate=JOINT)]
    scored = ((400.0, 0.0, 0), [("lumped_mass", None, 100.0, 0.0, 1),
                                ("joint_flexibility", None, 105.0, 0.0, 1)], 200)
    held_out = (np.array([50.0, 50.0]), [np.array([40.0, 40.0]), np.array([5.0, 5.0])],
                np.array([True, True]))
    text = reversal_note(0, fits, 1, None, 0.0, scored, 300, 1, held_out, 1.0, "ambiguous")
    assert "prefer lumped_mass grid 3009 to joint_flexibility RBE2 7003 by 5.0" in text
    assert "prefer the latter by 70.0" in text and "together by 65.0" in text
    assert text.endswith("is not named (ambiguous).")
    named = reversal_note(0, fits, 1, 0, 65.0, scored, 300, 1, held_out, 1.0, "effect")
    assert "by 65.0 (grid 3009 the closest)" in named and "no blind check" in named


def test_located_note_says_which_joint_stays():
    a = SimpleNamespace(candidate=JOINT, chi2=200.0)
    b = SimpleNamespace(candidate=SimpleNamespace(kind="joint_flexibility", label="RBE2 7002"),
                        chi2=250.0)
    rich = SimpleNamespace(chi2=180.0)
    stays = located_note(0, [(a, rich), (b, None)], a)
    assert "RBE2 7003 200.0 -> 180.0; RBE2 7002 250.0" in stays and stays.endswith("stays.")
    moved = located_note(0, [(a, None), (b, None)], b)
    assert moved.endswith("RBE2 7002 fits best and is named instead.")


def test_undetermined_note_lists_the_parameters_the_data_leave_open():
    """The frame's joint seed 7 (measured): compliance_rx 320.9 with no error bound (the held-out
    mode 24 alone governs it), the others determined; a parameter at its zero bound is left to
    the bound's note."""
    joint = SimpleNamespace(kind="joint_flexibility", label="RBE2 7005",
                            parameters=("compliance_x", "compliance_rx", "compliance_ry"),
                            lower=(0.0, 0.0, 0.0), upper=(1e6, 1e6, 1e6),
                            reference=(100.0, 100.0, 100.0))
    text = undetermined_note(0, joint, np.array([1472.8, 320.9, 1149.2]),
                             np.array([6.6, np.inf, 1500.0]))
    assert "compliance_rx = 320.9 (no bound), compliance_ry = 1149 +- 1.5e+03" in text
    assert "compliance_x" not in text and "determine them" in text
    assert undetermined_note(0, joint, np.array([1472.8, 0.0, 1149.2]),
                             np.array([6.6, 50.0, 60.0])) is None


def test_undetermined_note_says_when_no_errors_were_estimated():
    joint = SimpleNamespace(kind="joint_flexibility", label="RBE2 7005",
                            parameters=("compliance_x",), lower=(0.0,), upper=(1e6,),
                            reference=(100.0,))
    text = undetermined_note(1, joint, np.array([1472.8]), None)
    assert text.startswith("round 2: RBE2 7005: its standard errors are not estimated")
