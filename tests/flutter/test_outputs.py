"""Participation factors, the flutter file contract, the standard atmosphere and matched points."""
from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr

from aero.strip import section_gaf
from flutter.atmosphere import RHO0, Units, altitude_from_density, atmosphere, flight_labels
from flutter.matched import mach_line, matched_flutter, velocity_sweep_at_altitude
from flutter.participation import crossing_participation, participation_factors, participation_table
from flutter.pk import pk_solve
from flutter.results import write_flutter
from flutter.system import ModalSystem
from pipeline.chain import deck_modes, flutter_chain
from structures.common.errors import InputError
from structures.common.files import read_dataset
from flutter_nastran import DATA

A, E, MU, R2, SIGMA = -0.2, -0.1, 20.0, 0.24, 0.4
B, W_THETA, RHO_S = 1.0, 2 * np.pi * 10.0, 1.225
MACHS = [0.0, 0.3, 0.6, 0.8]


def section():
    m = MU * np.pi * RHO_S * B * B
    xt = E - A
    M = np.array([[m, m * B * xt], [m * B * xt, m * R2 * B * B]])
    K = np.diag([m * (SIGMA * W_THETA) ** 2, m * R2 * B * B * W_THETA ** 2])
    return ModalSystem(M, K)


def gaf_dataset():
    """Theodorsen GAFs with a Prandtl-Glauert lift slope per Mach (so Mach matters)."""
    k = np.concatenate([[1e-3, 0.01], np.linspace(0.02, 5.0, 80)])
    Q = np.array([section_gaf(k, A, B, lift_slope=2 * np.pi / np.sqrt(1 - m * m)) for m in MACHS])
    return xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q)},
                      coords={"mach": MACHS, "k": k, "mode_i": [1, 2], "mode_j": [1, 2]},
                      attrs={"refc": 2 * B, "rhoref": RHO_S})


@pytest.fixture(scope="module")
def sweep():
    return pk_solve(section(), gaf_dataset(), np.linspace(20, 250, 47), density=RHO_S, mach=0.3)


def test_participation_sums_to_100_and_matches_eigenvector(sweep):
    sys_ = section()
    omega, _ = sys_.in_vacuo()
    part = crossing_participation(sweep, sys_.mass, omega)
    assert part.sizes["flutter_mode"] == 1
    P = part.participation.values[0]
    assert abs(P.sum() - 100) < 1e-9
    u = sweep.crossing_eigenvector.values[0]
    Mu = sys_.mass @ u
    np.testing.assert_allclose(P, 100 * np.real(u.conj() * Mu) / np.real(u.conj() @ Mu), rtol=1e-12)
    table = participation_table([({"mach": 0.3, "configuration": "typ"}, part)], primary=[1, 2])
    assert "Total" in table and "1st" in table


def test_participation_diagonal_mass_is_energy_share():
    u = np.array([[1.0, 1j, 0.0], [0.0, 0.0, 2.0]])
    P = participation_factors(u, np.diag([1.0, 3.0, 1.0]))
    np.testing.assert_allclose(P, [[25.0, 75.0, 0.0], [0.0, 0.0, 100.0]])
    with pytest.raises(InputError, match="modal coordinates"):
        participation_factors(u, np.eye(2))


def test_rigid_modes_shown(sweep):
    sys_ = section()
    part = crossing_participation(sweep, sys_.mass, np.array([0.0, 1.0]), rigid_hz=0.05)
    assert bool(part.rigid.values[0]) and not bool(part.rigid.values[1])
    assert float(part.rigid_total[0]) == pytest.approx(float(part.participation.values[0, 0]))


def test_flutter_files_contract(tmp_path, sweep):
    other = pk_solve(section(), gaf_dataset(), np.linspace(20, 250, 30), density=RHO_S, mach=0.6)
    write_flutter(tmp_path, [sweep, other], [{"mach": 0.3, "density": RHO_S, "configuration": "a"},
                                             {"mach": 0.6, "density": RHO_S, "configuration": "a"}],
                  units="si")
    ds = read_dataset(tmp_path / "flutter.nc")
    for v in ("damping", "frequency", "k", "eigenvalue", "converged"):
        assert ds[v].dims == ("case", "velocity", "root"), v
    assert ds["eigenvector"].dims == ("case", "velocity", "root", "mode")
    assert ds.sizes["case"] == 2 and ds.sizes["velocity"] == 47
    np.testing.assert_allclose(ds.damping.isel(case=0).values, sweep.damping.values)
    assert np.isnan(ds.damping.isel(case=1, velocity=40)).all()
    assert np.iscomplexobj(ds.eigenvalue.values)
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert len(summary) == sweep.sizes["crossing"] + other.sizes["crossing"]
    first = summary[0]
    assert set(first) >= {"mach", "density", "velocity", "frequency", "root", "kind", "units"}
    assert first["velocity"] == pytest.approx(float(sweep.crossing_velocity[0]))
    assert first["units"] == {"system": "si", "velocity": "m/s", "density": "kg/m^3",
                              "frequency": "Hz"}
    assert ds.attrs["unit_system"] == "si"
    assert ds["velocity_value"].attrs["units"] == "m/s"
    assert ds["density_value"].attrs["units"] == "kg/m^3"
    assert ds["frequency"].attrs["units"] == "Hz"
    np.testing.assert_array_equal(ds.root_velocity.isel(case=0, root=0).values, sweep.velocity.values)
    text = (tmp_path / "flutter_summary.txt").read_text()
    assert text.count("FLUTTER  SUMMARY") == 2 * sweep.sizes["root"]
    assert "UNITS = si (VELOCITY m/s, DENSITY kg/m^3, FREQUENCY Hz)" in text
    assert (tmp_path / "vg_1.png").stat().st_size > 0 and (tmp_path / "vg_2.png").exists()


def test_bare_deck_labels_model_units(tmp_path, sweep):
    """Without a case the labels say "model units"; an unknown system is refused up front."""
    write_flutter(tmp_path, [sweep], [{"mach": 0.3, "density": RHO_S}])
    ds = read_dataset(tmp_path / "flutter.nc")
    assert ds["velocity_value"].attrs["units"] == "model units"
    assert ds.attrs["unit_system"] == "model units"
    entry = json.loads((tmp_path / "summary.json").read_text())[0]
    assert entry["units"]["velocity"] == "model units" and entry["units"]["frequency"] == "Hz"
    with pytest.raises(InputError, match="valid|use one of"):
        write_flutter(tmp_path, [sweep], [{"mach": 0.3}], units="imperial")


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_pt145_ke_writes_the_flutter_contract(tmp_path):
    """The K method (pt145, KE at M 0.45) goes into flutter.nc with the p-k contract: its points are
    the FLFACT k values, each root at its own V = omega b / k in root_velocity."""
    deck = DATA / "pt145" / "pt145.bdf"
    out = flutter_chain(deck, deck_modes(deck), units="english_in", out_dir=tmp_path)
    ds = read_dataset(tmp_path / "flutter.nc")
    for v in ("damping", "frequency", "k", "eigenvalue", "converged", "root_velocity"):
        assert ds[v].dims == ("case", "velocity", "root"), v
    assert ds["eigenvector"].dims == ("case", "velocity", "root", "mode")
    assert list(ds.method.values) == ["KE"] and not list(tmp_path.glob("flutter_k_*.nc"))
    bdf_k = [0.1, 1 / 9.00009, 0.125, 1 / 6.99986, 1 / 5.99988, 0.2, 0.25, 1 / 3.00003, 0.5]
    np.testing.assert_allclose(np.sort(ds.k.isel(case=0, root=0).values), bdf_k, rtol=1e-4)
    assert bool(ds.converged.all()) and np.isnan(ds.velocity_value).all()
    b = 0.5 * float(out["gaf"].attrs["refc"])
    omega = 2 * np.pi * ds.frequency.values
    np.testing.assert_allclose(ds.root_velocity.values, omega * b / ds.k.values, rtol=1e-12)
    np.testing.assert_allclose(ds.eigenvalue.values, omega * (ds.damping.values / 2 + 1j), rtol=1e-12)
    assert ds["root_velocity"].attrs["units"] == "in/s"
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert [(c["kind"], c["method"], c["units"]["velocity"]) for c in summary] == [
        ("flutter", "KE", "in/s")]
    assert summary[0]["velocity"] == pytest.approx(6004.0, rel=0.02)  # DESIGN.md: Nastran ~6004
    assert (tmp_path / "vg_1.png").exists() and (tmp_path / "flutter_summary.txt").exists()
    assert read_dataset(tmp_path / "modes.nc").attrs["units"] == "english_in"
    assert "(english_in)" in read_dataset(tmp_path / "gaf.nc").attrs["units"]


def test_us76_reference_values():
    """US76 tables: 11 km 216.774 K, 0.36480 kg/m^3; 20 km 0.088910; sea level 1.2250, 340.29 m/s."""
    atm = atmosphere([0.0, 11000.0, 20000.0])
    np.testing.assert_allclose(atm["density"], [1.2250, 0.36480, 0.088910], rtol=2e-4)
    np.testing.assert_allclose(atm["temperature"][1], 216.774, rtol=1e-5)
    np.testing.assert_allclose(atm["speed_of_sound"][0], 340.294, rtol=1e-5)
    assert altitude_from_density(0.36480) == pytest.approx(11000.0, abs=5.0)
    lab = flight_labels([100.0], [RHO0])
    assert lab["keas"][0] == pytest.approx(lab["ktas"][0]) == pytest.approx(194.384, rel=1e-4)
    with pytest.raises(InputError, match="outside the US76 range"):
        atmosphere([90000.0])
    ips = Units.named("english_in")
    assert ips.density * 1.1468e-7 == pytest.approx(1.2256, rel=1e-3)  # sea-level rho in slinch/in^3


def test_matched_flutter_is_consistent():
    res = matched_flutter(section(), gaf_dataset(), np.linspace(20, 300, 57), altitude_m=3000.0,
                          mach0=0.0)
    a = float(atmosphere(3000.0)["speed_of_sound"])
    assert res["mach"] == pytest.approx(res["velocity"] / a, abs=1e-4)
    again = velocity_sweep_at_altitude(section(), gaf_dataset(), np.linspace(20, 300, 57),
                                       altitude_m=3000.0, mach=res["mach"])
    assert float(again.crossing_velocity[0]) == pytest.approx(res["velocity"], rel=1e-3)
    assert float(again.crossing_altitude[0]) == pytest.approx(3000.0, abs=2.0)


def test_mach_line_density_sweep():
    ds = mach_line(section(), gaf_dataset(), np.linspace(15000, 0, 31), mach=0.6)
    assert ds.attrs["method"] == "PKNL"
    fl = ds.crossing_kind.values == "flutter"
    assert fl.any()
    i = int(np.flatnonzero(fl)[0])
    assert float(ds.crossing_matched_mach[i]) == pytest.approx(0.6, abs=2e-3)
    with pytest.raises(InputError, match="altitudes must decrease"):
        mach_line(section(), gaf_dataset(), [0.0, 1000.0], mach=0.6)
