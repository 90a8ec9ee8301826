"""pipeline.diagnose.inputs: the case's [diagnose] table, checked when the case is read, and the
configurations diagnose reads (deck, GVT, measured mass: only what the case names)."""
from __future__ import annotations

import numpy as np
import pytest

from pipeline.case import read_case
from pipeline.diagnose import ConfigurationData, DiagnoseSettings
from pipeline.diagnose.effects import KINDS
from pipeline.diagnose.inputs import (DIAGNOSE_KEYS, case_diagnose_settings,
                                      configurations_from_case, settings_from_case)
from structures.bdf import read_model
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset, write_uff
from structures.modal import compute_modes
from tests.pipeline.chain_deck import chain_deck


@pytest.fixture()
def folder(tmp_path):
    """chain.bdf and gvt.unv: the chain's elastic modes 7-12 at its translational DOFs."""
    chain_deck(tmp_path / "chain.bdf")
    modes = compute_modes(read_model(tmp_path / "chain.bdf"), 12)
    pick = modes.isel(dof=np.nonzero(modes["component"].values <= 3)[0]).sel(mode=range(7, 13))
    write_uff(make_gvt_dataset(pick["frequency"].values, pick["shape"].values,
                               pick["grid"].values, pick["component"].values,
                               mode=list(range(1, 7))), tmp_path / "gvt.unv")
    return tmp_path


def case_file(folder, body: str = "", config: str = 'gvt = "gvt.unv"\n'):
    path = folder / "case.toml"
    path.write_text('name = "chain"\n[[configurations]]\nname = "base"\ndeck = "chain.bdf"\n'
                    + config + body)
    return path


def test_defaults_are_the_workflow_defaults(folder):
    case = read_case(case_file(folder))
    assert case.diagnose is None
    options = case_diagnose_settings(case)
    assert options.before_tuning is False and options.flutter is False   # no [flutter]
    assert settings_from_case(case) == DiagnoseSettings()
    assert settings_from_case(case).kinds == KINDS


def test_table_values_reach_the_settings(folder):
    case = read_case(case_file(folder, '[diagnose]\nkinds = ["lumped_mass", "boundary_stiffness"]'
                                       '\nmax_effects = 2\nfrequency_noise = 0.02\nshape_noise = '
                                       '0.05\nholdout = 4\nmargin = 6\nrefit = 3\nnmodes = 20\n'
                                       'model_scatter = 0\nbefore_tuning = true\nflutter = false\n'))
    assert case.diagnose.before_tuning is True and case.diagnose.flutter is False
    assert settings_from_case(case) == DiagnoseSettings(
        kinds=("lumped_mass", "boundary_stiffness"), max_effects=2, frequency_noise=0.02,
        shape_noise=0.05, holdout=4, margin=6.0, refit=3, nmodes=20, model_scatter=0.0)
    assert isinstance(settings_from_case(case).margin, float)


def test_flutter_defaults_to_the_cases_flutter_table(folder):
    case = read_case(case_file(folder, '[flutter]\nkernel = "quartic"\n[diagnose]\n'))
    assert case.diagnose.flutter is True


@pytest.mark.parametrize("body, needles", [
    ("colour = 1", ("[diagnose]", "unknown keys ['colour']", "valid:", "before_tuning")),
    ("max_effects = 2.5", ("max_effects = 2.5", "an integer", "Fix")),
    ('before_tuning = "yes"', ("before_tuning", "a boolean", "Fix: write e.g. before_tuning = true")),
    ('kinds = "lumped_mass"', ("kinds", "a list of strings", "Fix")),
    ('kinds = ["lumped_mass", "cable"]', ("kinds ['cable'] not in", "joint_flexibility", "Fix")),
    ("kinds = []", ("kinds [] not in", "Fix")),
    ('kinds = ["lumped_mass", "member_taper", "lumped_mass"]',
     ("list ['lumped_mass'] more than once", "Fix: list each kind once")),
    ("frequency_noise = 0.0", ("frequency_noise = 0.0 must be a positive number",)),
    ("shape_noise = -0.1", ("shape_noise = -0.1 must be positive",)),
    ("holdout = 1", ("holdout = 1 must be an integer >= 2",)),
    ("margin = -1.0", ("margin = -1.0 must be a positive number",)),
    ("refit = 0", ("refit = 0 must be an integer >= 1",)),
    ("nmodes = 0", ("nmodes = 0 must be a positive integer",)),
    ("model_scatter = -0.1", ("model_scatter = -0.1 must be >= 0",)),
    ("frequency_noise = 1.0", ("frequency_noise = 1.0 is a fraction (0.01 = 1 %)",
                               "at most 0.2", "Fix")),
    ("shape_noise = 5", ("shape_noise = 5.0 is a fraction", "at most 1", "Fix")),
    ("model_scatter = 3", ("model_scatter = 3.0 is a fraction", "at most 0.5", "Fix")),
    ("flutter = true", ("flutter = true needs the case's [flutter]", "Fix")),
])
def test_bad_table_raises_naming_the_key_and_the_fix(folder, body, needles):
    path = case_file(folder, "[diagnose]\n" + body + "\n")
    with pytest.raises(InputError) as err:
        read_case(path)
    message = str(err.value)
    assert str(path) in message
    for needle in needles:
        assert needle in message, (needle, message)


def test_every_key_is_documented():
    import pipeline.diagnose.inputs as inputs

    assert all(f"    {key} = " in inputs.__doc__ for key in DIAGNOSE_KEYS)


def test_configuration_without_gvt_is_named(folder):
    with pytest.raises(InputError, match=r"\['base'\] have no GVT file.*Fix: add gvt"):
        read_case(case_file(folder, "[diagnose]\n", config=""))
    case = read_case(case_file(folder, config=""))           # no [diagnose]: pipeline diagnose
    with pytest.raises(InputError, match="base.*no GVT file.*Fix"):
        case_diagnose_settings(case)
    with pytest.raises(InputError, match="configuration base: no GVT file.*Fix"):
        configurations_from_case(case)


def test_configurations_read_what_the_case_names(folder):
    case = read_case(case_file(folder, config='gvt = "gvt.unv"\nmeasured_mass = { weight = 7.2 }\n'))
    (data,) = configurations_from_case(case)
    assert isinstance(data, ConfigurationData) and data.name == "base"
    assert data.deck == folder / "chain.bdf"
    assert data.measured_mass == {"weight": 7.2}
    assert data.gvt.sizes["mode"] == 6 and data.gvt.sizes["dof"] == 18
    assert sorted(data.model.grids.ids.tolist()) == [100, 200, 300, 400, 500, 600]
    (plain,) = configurations_from_case(read_case(case_file(folder)))
    assert plain.measured_mass is None


def test_a_table_of_frequencies_alone_is_diagnosed_and_refused_by_the_run(folder):
    """The chain's six test frequencies as a CSV table (gvt = "gvt.csv"): the diagnosis reads
    them without shapes and its preflight pairs them by nearest frequency, saying what
    frequencies alone cannot tell; pipeline run, whose correlation and tuning need shapes,
    refuses the case before any stage, naming the file and the fix."""
    from pipeline.diagnose import preflight
    from pipeline.diagnose.inputs import check_case_data
    from pipeline.run import run_case
    from structures.gvt import load_gvt

    test = load_gvt(folder / "gvt.unv")
    rows = "".join(f"{m}, {f!r}\n" for m, f in zip(test["mode"].values, test["frequency"].values))
    (folder / "gvt.csv").write_text("# the chain's GVT, frequencies alone\nmode, frequency\n" + rows)
    case = read_case(case_file(folder, config='gvt = "gvt.csv"\n'))
    (data,) = configurations_from_case(case)
    assert "shape" not in data.gvt and "dof" not in data.gvt.dims
    np.testing.assert_array_equal(data.gvt["frequency"].values, test["frequency"].values)
    check_case_data(case)
    (ref,), notes = preflight([data], settings_from_case(case))
    assert not ref.has_shapes and ref.test_frequency.size == 6
    assert any("frequency-only data (6 modes): paired by nearest frequency" in n for n in notes)
    with pytest.raises(InputError) as err:
        run_case(case, folder / "run")
    for needle in (f"case {folder / 'case.toml'}, configuration base", "gvt.csv",
                   "without mode shapes", "pipeline diagnose` takes frequencies alone"):
        assert needle in str(err.value), (needle, str(err.value))
    assert not (folder / "run").exists()
