"""Importing modes computed elsewhere: MYSTRAN OP2 (a Nastran-format OP2) and F06 tables."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import InputError
from structures.modal import compute_modes
from structures.modes import read_modes, write_modes
from structures.nastran_results import modes_from_op2, read_f06_eigenvalues

DATA = Path(__file__).resolve().parents[1] / "data"
MYS = DATA / "mystran_pt145"


@pytest.fixture(scope="module")
def imported():
    return modes_from_op2(MYS / "pt145_modes.OP2", MYS / "pt145_modes.bdf")


def test_op2_modes_match_our_solver_on_the_same_deck(imported):
    """The deck has lumped mass and no rotary inertia, MYSTRAN's and Nastran's convention alike."""
    ours = compute_modes(read_model(MYS / "pt145_modes.bdf"), 4)
    np.testing.assert_allclose(imported["frequency"], ours["frequency"], rtol=1e-6)
    a, b = imported["shape"].values, ours["shape"].values
    mac = (a @ b.T) ** 2 / np.outer((a * a).sum(1), (b * b).sum(1))
    np.testing.assert_allclose(np.diag(mac), 1.0, atol=1e-6)  # OP2 stores float32


def test_op2_shapes_rotated_to_basic_and_mass_normalised(imported):
    # Grids use CD = 1 (x swept 15 deg): bending is still pure basic z translation.
    shape = imported["shape"].sel(mode=1)
    tz = shape.where(shape.component == 3, drop=True)
    tx = shape.where(shape.component == 1, drop=True)
    assert np.abs(tz).max() > 0 and np.abs(tx).max() == 0
    np.testing.assert_allclose(imported["generalized_mass"], 1.0, rtol=1e-6)
    assert imported.attrs["source"] == "OP2"


def test_f06_table_agrees_with_op2(imported):
    table = read_f06_eigenvalues(MYS / "pt145_modes.F06")
    np.testing.assert_allclose(table.frequency.values, imported["frequency"].values, rtol=1e-6)


def test_modes_round_trip_netcdf(imported, tmp_path):
    write_modes(imported, tmp_path / "m.nc")
    back = read_modes(tmp_path / "m.nc")
    np.testing.assert_array_equal(back["shape"].values, imported["shape"].values)
    np.testing.assert_array_equal(back["grid"].values, imported["grid"].values)


def test_missing_op2_and_f06_without_table_raise(tmp_path):
    with pytest.raises(InputError, match="no such OP2"):
        modes_from_op2(tmp_path / "none.op2", MYS / "pt145_modes.bdf")
    with pytest.raises(InputError, match="no REAL EIGENVALUES"):
        read_f06_eigenvalues(DATA / "mystran_pt145" / "pt145_modes.bdf")
