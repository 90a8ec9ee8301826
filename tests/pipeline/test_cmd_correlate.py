"""Tests of ``pipeline correlate``: argument parsing, printed tables, written Dataset, DECK/.nc/.toml."""
from __future__ import annotations

import argparse

import numpy as np
import pytest
import scipy.linalg
import xarray as xr

from pipeline import cmd_correlate
from structures.common.errors import InputError
from structures.gvt import make_gvt_dataset, write_uff
from structures.modes import modes_dataset, write_modes
from structures.common.files import read_dataset


def parse(argv):
    parser = argparse.ArgumentParser(prog="pipeline")
    cmd_correlate.add_parser(parser.add_subparsers(dest="command"))
    return parser.parse_args(argv)


def chain_modes():
    """A free-free chain of 8 grids along x, springs in x, y and z (different per direction),
    point masses: 48 DOFs, modes by scipy.linalg.eigh (rotations carry a tiny inertia only)."""
    n = 8
    K, M = np.zeros((6 * n, 6 * n)), np.eye(6 * n)
    stiff = {0: 4.0e4, 1: 1.0e4, 2: 2.5e4}
    for i in range(n - 1):
        for c, k in stiff.items():
            a, b = 6 * i + c, 6 * (i + 1) + c
            K[np.ix_([a, b], [a, b])] += k * (1.0 + 0.1 * i) * np.array([[1, -1], [-1, 1]])
    for i in range(n):
        K[np.ix_(6 * i + np.arange(3, 6), 6 * i + np.arange(3, 6))] += np.eye(3) * 1e6
        M[np.ix_(6 * i + np.arange(3), 6 * i + np.arange(3))] *= 1.0 + 0.2 * (i % 3)
    lam, phi = scipy.linalg.eigh(K, M, subset_by_index=[0, 19])
    xyz = np.column_stack([np.arange(n), np.zeros(n), np.zeros(n)])
    return modes_dataset(np.sqrt(np.abs(lam)) / (2 * np.pi), phi.T, np.arange(1, n + 1) * 100, xyz,
                         source="test chain", deck="chain")


@pytest.fixture()
def files(tmp_path):
    modes = chain_modes()
    write_modes(modes, tmp_path / "modes.nc")
    pick = modes.isel(dof=np.nonzero(modes["component"].values <= 3)[0]).sel(mode=[4, 5, 6, 7])
    gvt = make_gvt_dataset(pick["frequency"].values * np.array([1.01, 0.98, 1.0, 1.06]), pick["shape"].values,
                           pick["grid"].values, pick["component"].values, mode=[1, 2, 3, 4],
                           name=["X1", "Y1", "Z1", "Y2"], xyz=np.column_stack([pick["x"], pick["y"], pick["z"]]))
    write_uff(gvt, tmp_path / "gvt.unv")
    return tmp_path, modes


def test_modes_file_and_uff_print_tables_and_write_dataset(files, capsys):
    folder, modes = files
    args = parse(["correlate", str(folder / "modes.nc"), str(folder / "gvt.unv"), "--out",
                  str(folder / "corr.nc"), "--primary", "1,2", "--figures", str(folder / "fig")])
    assert cmd_correlate.run(args) == 0
    out = capsys.readouterr().out
    for title in ("Frequencies [Hz] and checks", "MAC (rows", "Orthogonality of GVT modes", "Cross-orthogonality"):
        assert title in out
    assert "1 X1" in out and "4 Y2" in out
    corr = read_dataset(folder / "corr.nc")
    for var in ("mac", "orthogonality", "cross_orthogonality", "frequency_error", "paired_fe_mode", "pass_all"):
        assert var in corr
    assert corr["mac"].dims == ("test_mode", "fe_mode") and corr["orthogonality"].dims == ("test_mode", "test_mode_2")
    np.testing.assert_array_equal(corr["paired_fe_mode"].values, [4, 5, 6, 7])
    # the printed UFF values have 6 digits, so the errors are the applied 1 %, -2 %, 0 %, 6 % to 1e-3 %
    np.testing.assert_allclose(corr["frequency_error"].values, [-100 / 101 * 1, 100 * (1 / 0.98 - 1), 0.0,
                                                               100 * (1 / 1.06 - 1)], atol=1e-3)
    assert corr["primary"].values.tolist() == [True, True, False, False]
    mil = corr["pass_frequency"].sel(check="MIL-STD-1540C").values.tolist()
    nasa = corr["pass_frequency"].sel(check="NASA-STD-5002").values.tolist()
    assert mil == [True, True, True, False] and nasa == [True, True, True, True]
    assert "FAIL(f)" in out and sorted(p.name for p in (folder / "fig").iterdir()) == [
        "cross_orthogonality.png", "frequencies.png", "mac.png", "orthogonality.png"]
    assert isinstance(corr, xr.Dataset)
    assert corr.attrs["max_sensor_offset"] < 1e-5           # GVT nodes written at the grid positions


def test_case_file_gives_deck_and_gvt(files, tmp_path, capsys):
    """A TOML case (the lead's schema: [[configurations]] name/deck/nmodes/mass/gvt) with a deck of
    CELAS2 springs and CONM2 masses."""
    folder, _ = files
    deck = folder / "chain.bdf"
    cards = ["CEND", "BEGIN BULK"]
    for i in range(8):
        cards += [f"GRID,{100 * (i + 1)},,{float(i)},0.,0.", f"CONM2,{900 + i},{100 * (i + 1)},,{1.0 + 0.2 * (i % 3)}"]
    for i in range(7):
        for c, k in ((1, 4.0e4), (2, 1.0e4), (3, 2.5e4)):
            cards.append(f"CELAS2,{10 * i + c},{k * (1.0 + 0.1 * i)},{100 * (i + 1)},{c},{100 * (i + 2)},{c}")
    cards += ["SPC1,1,456," + ",".join(str(100 * (i + 1)) for i in range(8)), "ENDDATA"]
    deck.write_text("\n".join(cards) + "\n")
    (folder / "case.toml").write_text('name = "rod"\n[[configurations]]\nname = "base"\ndeck = "chain.bdf"\n'
                                      'gvt = "gvt.unv"\n')
    args = parse(["correlate", str(folder / "case.toml"), "--out", str(folder / "c.nc")])
    cmd_correlate.run(args)
    corr = read_dataset(folder / "c.nc")
    assert corr.attrs["deck"].endswith("chain.bdf") and corr.sizes["test_mode"] == 4
    # a case's modes are those of pipeline run's modes stage: the configuration's nmodes, else
    # the deck's EIGRL, else 20 (structures.modal.compute_modes)
    assert corr.sizes["fe_mode"] == 20
    # the deck is the chain of chain_modes with rotations constrained: same modes, same pairing
    np.testing.assert_array_equal(corr["paired_fe_mode"].values, [4, 5, 6, 7])
    np.testing.assert_allclose(np.abs(corr["paired_cross_orthogonality"].values), 1.0, atol=1e-4)
    assert "Summary:" in capsys.readouterr().out


def test_missing_gvt_and_bad_primary_raise(files):
    folder, _ = files
    with pytest.raises(InputError, match="GVT file missing"):
        cmd_correlate.run(parse(["correlate", str(folder / "modes.nc")]))
    with pytest.raises(InputError, match=r"primary modes \[9\] are not test modes"):
        cmd_correlate.run(parse(["correlate", str(folder / "modes.nc"), str(folder / "gvt.unv"),
                                 "--primary", "9"]))
