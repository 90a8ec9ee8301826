"""Units in the printed tables, the `pipeline flutter` lines and the HTML report (structures.units)."""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import xarray as xr

from flutter.results import units_entry
from pipeline.cmd_flutter import _print
from pipeline.report import write_report
from pipeline.tables import mass_table
from structures.common.files import write_dataset, write_json


def _props(wtmass=1.0):
    from structures.massprops import MassProperties

    return MassProperties(mass=2.0, cg=np.array([1.0, 0.0, 0.5]), inertia=np.diag([3.0, 4.0, 5.0]),
                          rigid_body_mass=np.eye(6), reference_point=np.zeros(3), wtmass=wtmass)


def test_mass_table_units():
    si = mass_table(_props(), "si").splitlines()
    assert si[0].split() == ["quantity", "value", "unit"]
    assert si[1].split() == ["mass", "2", "kg"] and si[2].split() == ["x_cg", "1", "m"]
    assert si[5].split() == ["Ixx", "3", "kg", "m^2"]
    ips = mass_table(_props(wtmass=0.00259), "english_in")
    assert "lbf s^2/in (slinch)" in ips and " in\n" in ips
    assert ips.splitlines()[-1].split()[0] == "weight" and ips.rstrip().endswith("lbf")
    assert "model units" in mass_table(_props())


def test_flutter_lines_carry_units(capsys):
    crossing = {"kind": "flutter", "root": 4, "mach": 0.2, "density": 1.225, "velocity": 395.1,
                "frequency": 3.18}
    _print("bah", [dict(crossing, units=units_entry("si")), crossing])
    out = capsys.readouterr().out.splitlines()
    assert out[1].split()[-8:] == ["1.225", "kg/m^3", "V", "395.1", "m/s", "f", "3.18", "Hz"]
    assert "V 395.1 model units" in out[2]


def test_report_headers_carry_units(tmp_path):
    modes = xr.Dataset({"frequency": ("mode", [1.0, 2.0])}, coords={"mode": [1, 2]},
                       attrs={"deck": "x.bdf", "source": "our solver"})
    mp = xr.Dataset({"mass": 2.0, "cg": ("axis", [1.0, 0.0, 0.5]),
                     "inertia": (("axis", "axis_2"), np.diag([3.0, 4.0, 5.0]))})
    crossing = {"kind": "flutter", "root": 1, "mach": 0.45, "density": 1.1e-7, "velocity": 6004.0,
                "frequency": 140.0}
    base = tmp_path / "stage0" / "a"
    write_dataset(modes, base / "modes.nc")
    write_dataset(mp, base / "mass_properties.nc")
    write_json([crossing], base / "flutter" / "summary.json")
    case = SimpleNamespace(name="c", units="english_in", flutter=None, loop=None,
                           configurations=(SimpleNamespace(name="a", deck="x.bdf", gvt=None),))
    page = write_report(case, tmp_path).read_text()
    assert "Unit system: english_in (length [in], velocity [in/s]" in page
    assert "<th>velocity [in/s]</th>" in page and "<th>frequency [Hz]</th>" in page
    assert "<th>Ixx [lbf s^2 in (slinch in^2)]</th>" in page
    assert "<td>2</td><td>1</td><td>0</td><td>0.5</td><td>3</td>" in page
    assert "Stage 0, configuration a: flutter crossings" in page
