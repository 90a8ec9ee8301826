"""Tests of structures.gvt: UFF 15/55 through pyuff and the tolerant vendor reader, netCDF, validation."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import pyuff
import xarray as xr

from structures.common.errors import InputError
from structures.gvt import (check_dofs_in_model, load_gvt, make_gvt_dataset, read_frequency_table, read_gvt,
                            read_uff, write_gvt, write_uff)

DATA = Path(__file__).resolve().parents[1] / "data" / "gvt"
VENDOR = DATA / "vendor_modes.unv"


def expected_vendor_dataset() -> xr.Dataset:
    """The content of vendor_modes.unv, typed in from the file by hand (not read by the library).

    Node 104 carries only z (its x, y are written as 0 in every mode and count as unmeasured);
    node 104 is absent from mode 8, so its z there is 0 (UFF note 9).
    """
    grid = [101, 101, 101, 102, 102, 102, 103, 103, 103, 104]
    comp = [1, 2, 3, 1, 2, 3, 1, 2, 3, 3]
    shape = [[0.1234, -0.05678, 0.9876, 0.02, 0.0015, 1.0, 0.02, -0.0015, 1.0, -0.3333],
             [0.005, -0.777, 0.0111, -0.01, 0.002, 0.8, 0.01, 0.002, -0.8, 0.0]]
    xyz = np.array([[0, 0, 0]] * 3 + [[4.0, 2.5, 0.0]] * 3 + [[4.0, -2.5, 0.0]] * 3 + [[9.5, 0.0, 0.5]])
    return make_gvt_dataset([1.067, 1.543], shape, grid, comp, mode=[7, 8], damping=[0.012, 0.009],
                            name=["SW1B", "AW1B"], modal_mass=[2.5, 1.75], xyz=xyz, source="expected")


def _same(a: xr.Dataset, b: xr.Dataset, rtol: float = 0.0) -> None:
    assert list(a.data_vars) == list(b.data_vars) and set(a.coords) == set(b.coords)
    for name in list(a.data_vars) + list(a.coords):
        if a[name].dtype == object:
            assert a[name].values.tolist() == b[name].values.tolist(), name
        else:
            np.testing.assert_allclose(a[name].values, b[name].values, rtol=rtol, atol=0.0, err_msg=name)


def test_vendor_file_is_read_by_the_tolerant_reader():
    """CRLF, trailing blanks, D exponents, free-format and run-together fields, 151/164 headers."""
    ds = read_uff(VENDOR)
    assert ds.attrs["reader"] == "tolerant"
    _same(ds, expected_vendor_dataset())


def test_pyuff_written_and_vendor_files_round_trip_to_the_same_dataset(tmp_path):
    vendor = read_uff(VENDOR)
    written = write_uff(expected_vendor_dataset(), tmp_path / "pyuff.unv")
    ours = read_uff(written)
    assert ours.attrs["reader"] == "pyuff"
    _same(ours, vendor)                                  # E13.5 holds these 5-digit values exactly
    # the same pyuff file with vendor quirks forced in goes through the tolerant reader, same result
    text = written.read_text().replace("e+", "D+").replace("e-", "D-").replace("E+", "D+").replace("E-", "D-")
    quirky = tmp_path / "quirky.unv"
    quirky.write_bytes(text.replace("\n", "   \r\n").encode())
    again = read_uff(quirky)
    assert again.attrs["reader"] == "tolerant"
    _same(again, vendor)


def test_six_dof_round_trip(tmp_path):
    rng = np.random.default_rng(3)
    grid = np.repeat([5, 6, 7], 6)
    comp = np.tile(np.arange(1, 7), 3)
    ds = make_gvt_dataset([2.0, 3.5, 7.25], rng.normal(size=(3, 18)), grid, comp, mode=[1, 2, 3],
                          damping=[0.01, 0.02, 0.03], modal_mass=[1.0, 1.0, 2.0], xyz=np.repeat(rng.normal(size=(3, 3)), 6, axis=0))
    back = read_uff(write_uff(ds, tmp_path / "six.unv"))
    assert pyuff.UFF(str(tmp_path / "six.unv")).read_sets(1)["data_ch"] == 3
    _same(back, ds, rtol=5e-6 * 10)                     # E13.5: 6 significant digits (relative 5e-6)
    assert "name" not in back


def test_netcdf_form_is_exact(tmp_path):
    ds = expected_vendor_dataset()
    back = read_gvt(write_gvt(ds, tmp_path / "gvt.nc"))
    _same(back, ds)
    _same(load_gvt(tmp_path / "gvt.nc"), ds)
    _same(load_gvt(VENDOR), ds)
    with pytest.raises(InputError, match=r"unknown suffix '.txt'"):
        load_gvt(tmp_path / "gvt.txt")


def test_complex_mode_is_realised(tmp_path):
    """A complex mode psi = phi exp(i 0.7) with lambda = -zeta w + i w sqrt(1 - zeta^2) gives back
    f = w / 2 pi, zeta and +-phi."""
    phi = np.array([[0.3, -0.2, 1.0], [0.5, 0.1, -0.4]])
    w, zeta = 2 * np.pi * 4.0, 0.02
    psi = phi * np.exp(0.7j)
    rec = pyuff.prepare_55(id1="c", id2="c", id3="c", id4="TORSION", id5="c", model_type=1, analysis_type=3,
                           data_ch=2, spec_data_type=8, data_type=5, n_data_per_node=3, load_case=1, mode_n=4,
                           eig=complex(-zeta * w, w * np.sqrt(1 - zeta**2)), modal_a=0j, modal_b=0j,
                           node_nums=np.array([1, 2]), r1=psi[:, 0], r2=psi[:, 1], r3=psi[:, 2])
    pyuff.UFF(str(tmp_path / "c.unv")).write_sets([rec], mode="overwrite")
    ds = read_uff(tmp_path / "c.unv")
    assert ds.attrs["reader"] == "pyuff"
    np.testing.assert_allclose(ds["frequency"].values, [4.0], rtol=1e-5)
    np.testing.assert_allclose(ds["damping"].values, [zeta], rtol=1e-4)
    got = ds["shape"].values[0]
    sign = np.sign(got @ phi.ravel())
    np.testing.assert_allclose(sign * got, phi.ravel(), atol=1e-5)
    assert ds["name"].values.tolist() == ["TORSION"]


# ------------------------------------------------------------------------------------ bad input
def test_nan_in_shape_raises():
    with pytest.raises(InputError, match=r"NaN/inf in the shape at \(mode, grid, component\) \[\(2, 11, 3\)\]"):
        make_gvt_dataset([1.0, 2.0], [[1.0, 0.5], [0.3, np.nan]], [10, 11], [3, 3], source="nan.unv")


def test_duplicate_mode_numbers_raise(tmp_path):
    with pytest.raises(InputError, match=r"duplicate mode numbers \[7\]"):
        make_gvt_dataset([1.0, 2.0], [[1.0, 0.5], [0.3, 1.0]], [10, 11], [3, 3], mode=[7, 7])
    text = VENDOR.read_bytes().replace(b"2 4 1 7", b"2 4 1 8")
    (tmp_path / "dup.unv").write_bytes(text)
    with pytest.raises(InputError, match=r"dup.unv: duplicate mode numbers \[8\]"):
        read_uff(tmp_path / "dup.unv")


def test_a_mode_recorded_twice_is_refused(tmp_path):
    """The vendor file with mode 7's dataset appended again as mode 9 (a copy made in a
    spreadsheet): refused naming the file and the pair. Two modes one-sided sensors see alike
    (collinear shapes, frequencies apart) and two modes at one frequency with other shapes pass."""
    text = VENDOR.read_bytes()
    start = text.index(b"    55\r\nGVT modes   ")
    block = text[start:text.index(b"    -1\r\n", start)].replace(b"2 4 1 7", b"2 4 1 9")
    (tmp_path / "twice.unv").write_bytes(text + b"    -1\r\n" + block + b"    -1\r\n")
    with pytest.raises(InputError, match=r"twice\.unv: modes \[\(7, 9\)\] are one record given twice"):
        read_uff(tmp_path / "twice.unv")
    with pytest.raises(InputError, match=r"modes \[\(3, 4\)\] are one record .*Fix: keep one"):
        make_gvt_dataset([1.0, 2.0, 2.0, 2.0 * (1 + 1e-8)], [[1.0, 0.5], [0.3, 1.0], [0.2, 1.0],
                                                            [-0.4, -2.0]], [10, 11], [3, 3])
    alike = make_gvt_dataset([2.0, 2.02], [[0.3, 1.0], [0.3, 1.0]], [10, 11], [3, 3])
    assert alike.sizes["mode"] == 2
    assert make_gvt_dataset([2.0, 2.0], [[0.3, 1.0], [1.0, -0.3]], [10, 11], [3, 3]).sizes["mode"] == 2


def test_unknown_nodes_are_named():
    ds = expected_vendor_dataset()
    with pytest.raises(InputError, match=r"nodes \[103, 104\] are not grids of the model"):
        check_dofs_in_model(ds, [101, 102, 200])
    check_dofs_in_model(ds, [101, 102, 103, 104])


def test_local_coordinate_systems_are_refused(tmp_path):
    text = VENDOR.read_bytes().replace(b"       102         0         0        11",
                                       b"       102         5         0        11")
    (tmp_path / "cs.unv").write_bytes(text)
    with pytest.raises(InputError, match=r"nodes \[102\] use a non-global"):
        read_uff(tmp_path / "cs.unv")


def test_other_bad_input():
    with pytest.raises(InputError, match=r"components \[7\] are not in 1..6"):
        make_gvt_dataset([1.0], [[1.0]], [10], [7])
    with pytest.raises(InputError, match=r"duplicate measured DOFs \(grid, component\) \[\(10, 3\)\]"):
        make_gvt_dataset([1.0], [[1.0, 2.0]], [10, 10], [3, 3])
    with pytest.raises(InputError, match=r"modes \[2\] have an all-zero shape"):
        make_gvt_dataset([1.0, 2.0], [[1.0], [0.0]], [10], [3])
    with pytest.raises(InputError, match="no such file"):
        read_uff("/nonexistent/gvt.unv")
    for dofs in ([10], [3], None), (None, None, [[0.0, 0.0, 0.0]]):
        with pytest.raises(InputError, match=r"measured DOFs \(grid, component or xyz\) without "
                                             r"mode shapes"):
            make_gvt_dataset([1.0], None, dofs[0], dofs[1], xyz=dofs[2])


# ------------------------------------------------------------------------- frequencies alone
TABLE = """\ufeff# published GVT, frequencies alone
Name, mode, frequency, damping

AW1B, 8, 1.543, 0.009
SW1B, 7, 1.067,
"""


def test_frequency_table_reads_as_typed_in(tmp_path):
    """A CSV table with a BOM, a comment, a blank line, columns in another order, a blank
    damping: the values typed in by hand, modes sorted, no shape or DOFs; the netCDF form keeps
    it exactly; every reader that needs shapes refuses it naming what takes it."""
    (tmp_path / "f.csv").write_text(TABLE, encoding="utf-8")
    ds = read_frequency_table(tmp_path / "f.csv")
    assert ds["mode"].values.tolist() == [7, 8]
    np.testing.assert_array_equal(ds["frequency"].values, [1.067, 1.543])
    np.testing.assert_array_equal(ds["damping"].values, [0.0, 0.009])
    assert ds["name"].values.tolist() == ["SW1B", "AW1B"]
    assert "shape" not in ds and "dof" not in ds.dims and ds.attrs["reader"] == "table"
    _same(load_gvt(tmp_path / "f.csv", shapes=False), ds)
    write_gvt(ds, tmp_path / "f.nc")
    _same(read_gvt(tmp_path / "f.nc", shapes=False), ds)
    for path in (tmp_path / "f.csv", tmp_path / "f.nc"):
        with pytest.raises(InputError, match=r"f\.(csv|nc): test frequencies without mode shapes: "
                                             r"correlation and tuning .*Fix: .*`pipeline diagnose` "
                                             r"takes frequencies alone"):
            load_gvt(path)


@pytest.mark.parametrize("text, message", [
    ("", r"no header line"),
    ("# only a comment\n", r"no header line"),
    ("mode, frequency\n", r"the table lists no mode"),
    ("mode, freq\n7, 1.0\n", r"line 1: columns \['mode', 'freq'\] must name 'mode' and 'frequency'"
                              r".*\(unknown: \['freq'\]\)"),
    ("mode, frequency, mode\n7, 1.0, 7\n", r"line 1: columns .* once each"),
    ("frequency, damping\n1.0, 0.01\n", r"line 1: columns .* must name 'mode'"),
    ("mode, frequency\n7, 1.0\n8, 2.0, 0.01\n", r"line 3: 3 fields for the 2 columns"),
    ("mode, frequency\n7, 1.0\n8, two\n", r"line 3: frequency 'two' is not a number"),
    ("mode, frequency\n7.5, 1.0\n", r"line 2: mode '7.5' is not a mode number \(an integer"),
    ("mode, frequency\n1e300, 1.0\n", r"line 2: mode '1e300' is not a mode number"),
    ("mode, frequency\n-3, 1.0\n", r"line 2: mode '-3' is not a mode number"),
    ("mode, frequency\n7, 1.0\n7, 2.0\n", r"duplicate mode numbers \[7\]"),
    ("mode, frequency\n7, -1.0\n", r"frequencies of modes \[7\] are not finite and >= 0"),
    ("mode, frequency, damping\n7, 1.0, nan\n", r"damping of modes \[7\] is not finite")])
def test_bad_frequency_table_is_refused_naming_the_line(tmp_path, text, message):
    (tmp_path / "bad.csv").write_text(text)
    with pytest.raises(InputError, match=r"GVT file .*bad\.csv.*" + message):
        load_gvt(tmp_path / "bad.csv", shapes=False)


def test_frequency_table_that_is_not_text_is_refused(tmp_path):
    (tmp_path / "bin.csv").write_bytes(b"mode,frequency\n7,\xff\xfe1.0\n")
    with pytest.raises(InputError, match=r"bin\.csv: not a text table .*Fix: save the table as CSV"):
        load_gvt(tmp_path / "bin.csv", shapes=False)
    with pytest.raises(InputError, match=r"unknown suffix '\.txt'.*'\.csv'"):
        load_gvt(tmp_path / "f.txt")
