"""Measured mass properties from the case file: validated, compared by ``pipeline correlate``."""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from pipeline.case import read_case
from pipeline.cli import main
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset, write_uff
from structures.massprops import compare_mass_properties, mass_properties
from structures.modal import compute_modes
from structures.common.files import read_dataset

DATA = Path(__file__).resolve().parents[1] / "data"
EXAMPLE = Path(__file__).resolve().parents[2] / "data" / "bah_wing"


@pytest.fixture()
def case_dir(tmp_path):
    for name in ("bah_plane.bdf", "structure_bah.inc", "aero_bah.inc", "interface_bah.inc"):
        shutil.copy(DATA / "bah_plane" / name, tmp_path / name)
    modes = compute_modes(read_model(tmp_path / "bah_plane.bdf"), 8)
    pick = modes.isel(dof=np.flatnonzero(modes["component"].values <= 3)).sel(mode=[3, 4, 6, 7])
    gvt = make_gvt_dataset(pick["frequency"].values * 1.02, pick["shape"].values,
                           pick["grid"].values, pick["component"].values, mode=[1, 2, 3, 4],
                           xyz=np.column_stack([pick["x"], pick["y"], pick["z"]]))
    write_uff(gvt, tmp_path / "gvt.unv")
    return tmp_path


def test_correlate_prints_and_writes_mass_comparison(case_dir, capsys):
    props = mass_properties(read_model(case_dir / "bah_plane.bdf"))
    measured = {"weight": props.weight * 1.05, "x_cg": props.cg[0] * 0.9, "Iyy": props.inertia[1, 1]}
    (case_dir / "case.toml").write_text(
        'name = "m"\n[[configurations]]\nname = "a"\ndeck = "bah_plane.bdf"\ngvt = "gvt.unv"\n'
        f'nmodes = 8\nmeasured_mass = {{ weight = {measured["weight"]!r}, x_cg = '
        f'{measured["x_cg"]!r}, Iyy = {measured["Iyy"]!r} }}\n')
    out = case_dir / "corr.nc"
    assert main(["correlate", str(case_dir / "case.toml"), "--out", str(out)]) == 0
    assert "Mass properties (model vs measured)" in capsys.readouterr().out
    corr = read_dataset(out)
    rel = corr["mass_relative_error"].sel(quantity=["weight", "x_cg", "Iyy"]).values
    np.testing.assert_allclose(rel, [100 * (1 / 1.05 - 1), 100 * (1 / 0.9 - 1), 0.0], atol=1e-9)


def test_unknown_or_bad_measured_quantities_raise(case_dir):
    (case_dir / "case.toml").write_text(
        'name = "m"\n[[configurations]]\nname = "a"\ndeck = "bah_plane.bdf"\n'
        'measured_mass = { wieght = 1.0 }\n')
    with pytest.raises(InputError, match=r"unknown quantities \['wieght'\]; valid: \['weight'"):
        read_case(case_dir / "case.toml")
    (case_dir / "case.toml").write_text(
        'name = "m"\n[[configurations]]\nname = "a"\ndeck = "bah_plane.bdf"\n'
        'measured_mass = { weight = -3.0 }\n')
    with pytest.raises(InputError, match="weight = -3.0 must be positive"):
        read_case(case_dir / "case.toml")


def test_cg_in_other_units_is_refused_before_any_stage(case_dir, capsys):
    """The BAH plane's CG given in millimetres (its deck is in metres): `pipeline run` and
    `pipeline correlate` stop with exit 2 naming the configuration and the coordinate before
    any computation; `pipeline run` leaves no run folder."""
    props = mass_properties(read_model(case_dir / "bah_plane.bdf"))
    (case_dir / "case.toml").write_text(
        'name = "m"\n[[configurations]]\nname = "a"\ndeck = "bah_plane.bdf"\ngvt = "gvt.unv"\n'
        f'nmodes = 8\nmeasured_mass = {{ x_cg = {1000 * props.cg[0]!r} }}\n')
    run = case_dir / "run"
    assert main(["run", str(case_dir / "case.toml"), "--out", str(run)]) == 2
    err = capsys.readouterr().err
    for needle in ("configuration a, measured_mass: the measured CG lies outside the model",
                   f"x_cg = {1000 * props.cg[0]:g}", "Fix: give the CG in the deck's length unit"):
        assert needle in err, (needle, err)
    assert not run.exists()
    assert main(["correlate", str(case_dir / "case.toml"), "--out",
                 str(case_dir / "corr.nc")]) == 2
    assert "the measured CG lies outside the model" in capsys.readouterr().err
    assert not (case_dir / "corr.nc").exists()


def test_comparison_of_model_with_itself_is_zero():
    props = mass_properties(read_model(DATA / "bah_plane" / "bah_plane.bdf"))
    same = {k: v for k, v in props.as_dict().items() if k != "mass" and v != 0.0}
    comparison = compare_mass_properties(props, same)
    np.testing.assert_allclose(comparison["relative_error"].values, 0.0, atol=1e-12)


def test_measured_mass_from_a_json_file(tmp_path):
    """``measured_mass = "mass.json"`` in a case file reads the issue's JSON layout."""
    for name in ("bah_plane.bdf", "structure_bah.inc", "aero_bah.inc", "interface_bah.inc"):
        shutil.copy(EXAMPLE / name, tmp_path / name)
    (tmp_path / "mass.json").write_text('{"weight": 19177.9, "cg": [0.1, 3.1, 0.0]}')
    (tmp_path / "case.toml").write_text('name = "m"\n[[configurations]]\nname = "a"\n'
                                        'deck = "bah_plane.bdf"\nmeasured_mass = "mass.json"\n')
    config = read_case(tmp_path / "case.toml").configurations[0]
    assert dict(config.measured_mass) == {"weight": 19177.9, "x_cg": 0.1, "y_cg": 3.1, "z_cg": 0.0}
    (tmp_path / "case.toml").write_text('name = "m"\n[[configurations]]\nname = "a"\n'
                                        'deck = "bah_plane.bdf"\nmeasured_mass = "none.json"\n')
    with pytest.raises(InputError, match="measured_mass 'none.json'.*does not exist"):
        read_case(tmp_path / "case.toml")
