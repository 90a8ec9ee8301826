"""Public Nastran decks that nobody on this project wrote, against Nastran's own eigenvalue tables.

The decks and F06 excerpts are in ``tests/data`` (see ``tests/data/SOURCES.md``):

* ``goland_wingbox``: Goland wing box from pyNastran (MSC Nastran 2018, SOL 200 ANALYSIS=MODES):
  built-up membrane skin (t = 0.0155), spars, ribs, rod caps and posts, 66 CONM2; one mode.
* ``cofe_72bar``: the 72-bar space truss from NASTRAN_CoFE (MSC Nastran 2019, SOL 103); 10 modes.
* ``dakota_cylinder``: free-free CQUAD4 cylinder with RBE2 end rings and a 1000 lb seismic mass
  (CONM2), PARAM COUPMASS 1 and WTMASS, from Dakota's Nastran example (MSC.Nastran 70.7.2); 20
  modes, 6 of them rigid.

Rigid-body roots: an F06 frequency below 1e-3 times the table's largest is numerical noise of a
zero eigenvalue (the cylinder's are 1e-5..7e-4 Hz against 2,687 Hz); ours must then be below 1e-3
times the first elastic frequency too. Elastic roots are compared to 0.5 %.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import COMMANDS, main
from structures.assembly import assemble
from structures.bdf import read_model
from structures.modal import compute_modes
from structures.nastran_results import read_f06_eigenvalues

DATA = Path(__file__).resolve().parents[1] / "data"
RTOL = 5e-3
RIGID = 1e-3

GOLAND = ("goland_wingbox/goland_final_test.bdf", "goland_wingbox/goland_final_test_excerpt.f06")
BAR72 = ("cofe_72bar/modes.dat", "cofe_72bar/modes_excerpt.f06")
CYLINDER = ("dakota_cylinder/modal.bdf", "dakota_cylinder/modal_excerpt.f06")

#: Cylinder modes (1-based) whose frequencies differ from MSC.Nastran 70.7 by 2.0-2.6 %: the pairs
#: at 5564, 6717 and 8881 Hz (ours 5706.9, 6869.9, 9062.4 Hz with the consistent mass the deck
#: asks for). The others agree to 0.33 % or better.
CYLINDER_OFF = (10, 11, 13, 14, 17, 18)
#: Shift (rad/s)^2 for the cylinder: with the default -(2 pi 0.1 Hz)^2 the 20-mode solve of this
#: model (rigid modes and elastic ones at 2.7-11.8 kHz) returns run-to-run different, wrong roots.
CYLINDER_SHIFT = -(2.0 * np.pi * 100.0) ** 2


def _reference(f06):
    return read_f06_eigenvalues(DATA / f06).frequency.values


def _compare(ours, ref, modes):
    """Relative error of the listed 1-based elastic modes; rigid roots checked on the way."""
    rigid = ref < RIGID * ref.max()
    elastic_min = ref[~rigid].min()
    assert np.all(ours[rigid] < RIGID * elastic_min), ours[rigid]
    idx = np.asarray(modes) - 1
    assert not np.any(rigid[idx])
    return ours[idx] / ref[idx] - 1.0


def test_f06_excerpts_hold_nastrans_numbers():
    """The parsed tables are the F06 lines copied verbatim (guards the reference itself)."""
    assert _reference(GOLAND[1]).tolist() == [1.981382]
    bar = _reference(BAR72[1])
    assert bar.size == 10 and bar[0] == 25.4557 and bar[9] == 136.6591
    cyl = _reference(CYLINDER[1])
    assert cyl.size == 20 and cyl[6] == 2687.641 and cyl[19] == 11792.99
    assert np.all(cyl[:6] < 1e-3) and cyl[6] > 2e3


def test_goland_wingbox_first_mode_matches_msc_nastran():
    """Thin membrane skin, spars and ribs (no bending, MID2 blank), caps and posts, 66 CONM2."""
    ref = _reference(GOLAND[1])
    ours = compute_modes(read_model(DATA / GOLAND[0]), 1)["frequency"].values
    err = _compare(ours, ref, [1])
    assert np.all(np.abs(err) < RTOL), err
    # 2.2e-6 measured: no drilling penalty on membrane-only panels, as Nastran (+3.0e-4 with one)
    assert abs(err[0]) < 1e-5


def test_goland_wingbox_singularities_match_msc_nastran():
    """MSC's F06 lists R4-R6 of the 60 unconstrained grids as singular (ratio 0.00E+00): the
    membrane-only panels get no K6ROT drilling stiffness, so AUTOSPC removes those rotations."""
    system = assemble(read_model(DATA / GOLAND[0]))
    table = system.singularities
    assert len(table) == 180
    assert len(np.unique(table.grid)) == 60
    assert set(np.unique(table.component).tolist()) == {4, 5, 6}


def test_72_bar_truss_matches_msc_nastran():
    ref = _reference(BAR72[1])
    ours = compute_modes(read_model(DATA / BAR72[0]), 10)["frequency"].values
    err = _compare(ours, ref, range(1, 11))
    assert np.all(np.abs(err) < RTOL), err
    assert np.all(np.abs(err) < 1e-6)   # same lumped rod mass as Nastran: agreement to 7 digits


def test_cylinder_matches_msc_nastran_except_the_known_pairs():
    ref = _reference(CYLINDER[1])
    ours = compute_modes(read_model(DATA / CYLINDER[0]), 20,
                         shift=CYLINDER_SHIFT)["frequency"].values
    modes = [m for m in range(7, 21) if m not in CYLINDER_OFF]
    err = _compare(ours, ref, modes)
    assert np.all(np.abs(err) < RTOL), dict(zip(modes, err))


@pytest.mark.xfail(strict=True, reason="three n=2-type mode pairs of the thick (R/t = 5), 16-facet "
                   "cylinder are 2.0-2.6 % stiffer than MSC.Nastran 70.7's QUAD4 with its coupled "
                   "mass; lumped mass matches the 5564 Hz pair (0.01 %) but moves the 2688 Hz pair "
                   "by -0.5 %; cause not identified")
def test_cylinder_known_pairs_match_msc_nastran():
    ref = _reference(CYLINDER[1])
    ours = compute_modes(read_model(DATA / CYLINDER[0]), 20,
                         shift=CYLINDER_SHIFT)["frequency"].values
    err = _compare(ours, ref, CYLINDER_OFF)
    assert np.all(np.abs(err) < RTOL), err


@pytest.mark.xfail(strict=False, reason="default shift -(2 pi 0.1 Hz)^2 with the SuperLU backend: "
                   "the shift-invert Lanczos of this model returns wrong, run-to-run different "
                   "roots (e.g. 2620-2744 Hz for the 2687.6 Hz pair, 4806-5025 Hz for 4926.7 Hz); "
                   "the PARDISO backend, or a shift of -(2 pi 10 Hz)^2 or lower, gives the dense "
                   "solver's roots")
def test_cylinder_with_the_default_shift():
    ref = _reference(CYLINDER[1])
    ours = compute_modes(read_model(DATA / CYLINDER[0]), 20)["frequency"].values
    modes = [m for m in range(7, 21) if m not in CYLINDER_OFF]
    err = _compare(ours, ref, modes)
    assert np.all(np.abs(err) < RTOL), dict(zip(modes, err))


@pytest.mark.parametrize("deck", [GOLAND[0], BAR72[0], CYLINDER[0]])
def test_pipeline_modes_runs(deck, capsys):
    assert main(["modes", str(DATA / deck), "--nmodes", "8"]) == 0
    assert "frequency" in capsys.readouterr().out


@pytest.mark.skipif("pipeline.cmd_check" not in COMMANDS, reason="no `pipeline check` command")
@pytest.mark.parametrize("deck", [GOLAND[0], BAR72[0], CYLINDER[0]])
def test_pipeline_check_runs(deck, capsys):
    assert main(["check", str(DATA / deck), "--nmodes", "8"]) == 0
    out = capsys.readouterr().out
    assert "UNSUPPORTED" not in out
    assert "mechanisms: none" in out
