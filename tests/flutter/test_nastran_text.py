"""The Nastran-style FLUTTER SUMMARY text (flutter.nastran_text) against Nastran's own F06 tables.

Both texts are read by the same F06 reader (tests/flutter/flutter_nastran.py), so the layout is
checked by the reader finding the same tables, and the header lines are compared verbatim.
- bah_plane, PK at M 0.2 (p-k on Nastran's own Q_hh, as tests/flutter/test_pk_bah.py): the elastic
  roots' rows agree with the F06 to the tolerance our p-k agrees with Nastran there (frequency,
  k 0.5%, g 0.005);
- pt145, KE at M 0.45 (our modes and doublet-lattice GAFs through pipeline.chain, as
  tests/flutter/test_end_to_end.py): same k column, velocity, frequency and Nastran's K-method eigenvalue within 1%, g within 0.015;
- round trip: the printed numbers read back equal the Dataset's to printed precision (PK, PKNL, K).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
from pyNastran.bdf.bdf import read_bdf

from flutter.kmethod import k_solve
from flutter.nastran_text import INV_K_ZERO, flutter_summary_text
from flutter.pk import pk_solve
from flutter.results import label_units
from flutter.system import ModalSystem
from flutter_nastran import DATA, bah_qhh_dataset, f06_flutter_summaries, f06_modes_used
from pipeline.chain import deck_modes, flutter_chain
from test_pk_typical_section import RHO, gaf, section

BAH_F06 = DATA / "bah_plane" / "bah_plane.f06"


def _tables(text: str, tmp_path, name: str) -> list[dict]:
    path = tmp_path / name
    path.write_text(text)
    return f06_flutter_summaries(path)


def _header_lines(text: str) -> list[str]:
    """The POINT and column-heading lines of every table, trailing blanks removed."""
    return [line.rstrip() for line in text.splitlines()
            if line.lstrip().startswith(("POINT =", "KFREQ"))]


@pytest.fixture(scope="module")
def bah():
    bdf = read_bdf(str(DATA / "bah_plane" / "bah_plane.bdf"), debug=None)
    fl = bdf.flutters[502]
    rho = bdf.flfacts[fl.density].factors[0] * bdf.aero.rho_ref
    mach = bdf.flfacts[fl.mach].factors[0]
    V = np.asarray(bdf.flfacts[fl.reduced_freq_velocity].factors, dtype=float)
    gm, gk, _ = f06_modes_used(BAH_F06)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # roots 9-10 start above the k table
        ds = pk_solve(ModalSystem(np.diag(gm), np.diag(gk)), bah_qhh_dataset(), V, density=rho,
                      mach=mach)
    ds.attrs["rhoref"] = float(bdf.aero.rho_ref)
    ds = label_units(ds, "si")
    f06 = BAH_F06.read_text(errors="replace")
    ref = [s for s in f06_flutter_summaries(BAH_F06) if np.isclose(s["mach"], mach)]
    return ds, ref, f06[f06.index("MACH NUMBER =  0.2000") - 30:]


def test_bah_pk_tables_match_f06_line_by_line(bah, tmp_path):
    ds, ref, f06_tail = bah
    text = flutter_summary_text(ds, title="bah_plane.bdf")
    assert _header_lines(text) == _header_lines(f06_tail)[:2 * len(ref)]
    ours = _tables(text, tmp_path, "flutter_summary.txt")
    assert [t["point"] for t in ours] == [t["point"] for t in ref] == list(range(1, 11))
    checked = 0
    for o, r in zip(ours, ref):
        a, b = o["rows"], r["rows"]
        assert a.shape == b.shape and o["columns"] == r["columns"]
        np.testing.assert_allclose(a[:, 2], b[:, 2], rtol=1e-7)  # the FLFACT velocities
        if np.any(b[:, 0] == 0) or b[0, 4] < 2.0 or b[0, 4] > 30.0:
            continue  # rigid / real roots, and roots above the k table at low speed
        checked += 1
        # measured: f, 1/k, Im p 0.38%, k 0.43% (with its 4-decimal rounding), g 0.0039,
        # Re p = g omega / 2 within 0.006 omega / 2
        np.testing.assert_allclose(a[:, 4], b[:, 4], rtol=5e-3)
        np.testing.assert_allclose(a[:, 0], b[:, 0], rtol=5e-3, atol=1e-4)
        np.testing.assert_allclose(a[:, 1], b[:, 1], rtol=5e-3)
        np.testing.assert_allclose(a[:, 3], b[:, 3], atol=5e-3)
        np.testing.assert_allclose(a[:, 6], b[:, 6], rtol=5e-3)
        assert np.all(np.abs(a[:, 5] - b[:, 5]) <= 0.5 * 8e-3 * np.abs(b[:, 6]))
    assert checked >= 4


def _assert_round_trip(ds, tables, columns):
    """Every printed row equals the Dataset's numbers to printed precision."""
    sweep = ds.attrs["sweep"]
    for t in tables:
        r = t["point"]
        one = ds.sel(root=r)
        p = one.eigenvalue.values
        real = np.abs(p.imag) <= 1e-9 * np.abs(p)
        k = one.k.values if sweep != "k" else ds.k.values
        V = np.broadcast_to(one.velocity.values, p.shape)
        if sweep == "k":
            order = np.argsort(k)
            p, real, k, V = p[order], real[order], k[order], V[order]
            one = one.isel(k=order)
            p = 1j * V / np.sqrt(1 + 1j * one.damping.values)
        rows = t["rows"]
        assert t["columns"] == columns and rows.shape[0] == p.size
        col = {name: rows[:, i] for i, name in enumerate(columns)}
        np.testing.assert_allclose(col["k"], np.where(real, 0.0, k), atol=5e-5)
        inv = np.where(real, INV_K_ZERO, 1 / np.where(real, 1.0, k))
        digits = 5e-8 if len(columns) == 7 else 5e-6   # 8 or 6 significant digits
        for name, want in (("inv_k", inv), ("velocity", V), ("damping", one.damping.values),
                           ("frequency", np.where(real, 0.0, one.frequency.values)),
                           ("re", p.real), ("im", np.where(real, 0.0, p.imag))):
            np.testing.assert_allclose(col[name], want, rtol=digits, atol=1e-300, err_msg=name)
        if "density" in col:
            np.testing.assert_allclose(col["density"], ds.density.values, rtol=digits)
            np.testing.assert_allclose(col["mach"], ds.mach.values, rtol=digits)


def test_round_trip_pk_pknl_k(bah, tmp_path):
    ds = bah[0]
    pk_cols = ("k", "inv_k", "velocity", "damping", "frequency", "re", "im")
    _assert_round_trip(ds, _tables(flutter_summary_text(ds), tmp_path, "pk.txt"), pk_cols)
    pknl = pk_solve(section(), gaf, np.full(25, 2.0), density=np.linspace(0.5, 1.5, 25), mach=0.0,
                    refc=2.0, sweep="density")
    tables = _tables(flutter_summary_text(pknl), tmp_path, "pknl.txt")
    assert [t["point"] for t in tables] == [1, 2]
    _assert_round_trip(pknl, tables, ("k", "inv_k", "density", "mach", "velocity", "damping",
                                      "frequency", "re", "im"))
    kd = k_solve(section(), gaf, np.linspace(0.05, 1.5, 30), density=RHO, mach=0.0, refc=2.0)
    _assert_round_trip(kd, _tables(flutter_summary_text(kd), tmp_path, "k.txt"), pk_cols)


@pytest.mark.filterwarnings("ignore::UserWarning")
def test_pt145_ke_tables_match_f06(tmp_path):
    out = tmp_path / "pt145"
    deck = DATA / "pt145" / "pt145.bdf"
    flutter_chain(deck, deck_modes(deck), units="english_in", out_dir=out)
    text = (out / "flutter_summary.txt").read_text()
    f06 = DATA / "pt145" / "pt145.f06"
    assert _header_lines(text) == _header_lines(f06.read_text(errors="replace"))
    assert "UNITS = english_in (VELOCITY in/s, DENSITY lbf s^2/in^4 (slinch/in^3)" in text
    ours, ref = f06_flutter_summaries(out / "flutter_summary.txt"), f06_flutter_summaries(f06)
    assert [t["point"] for t in ours] == [t["point"] for t in ref] == [1, 2, 3]
    for o, r in zip(ours, ref):
        a, b = o["rows"], r["rows"]
        assert a.shape == b.shape
        np.testing.assert_array_equal(a[:, :2], b[:, :2])  # KFREQ, 1./KFREQ: the FLFACT list
        # measured: V and f 0.47%, complex eigenvalue 0.48%, g 0.0075 (root 2, through g = 0)
        np.testing.assert_allclose(a[:, 2], b[:, 2], rtol=1e-2)
        np.testing.assert_allclose(a[:, 4], b[:, 4], rtol=1e-2)
        np.testing.assert_allclose(a[:, 3], b[:, 3], atol=0.015)
        eig_a, eig_b = a[:, 5] + 1j * a[:, 6], b[:, 5] + 1j * b[:, 6]
        assert np.all(np.abs(eig_a - eig_b) <= 1e-2 * np.abs(eig_b))
