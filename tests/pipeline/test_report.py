"""The run's HTML report and the flutter-change table (paper Table 5) on a synthetic run folder
whose expected entries are worked out by hand (tests/pipeline/run_fixture.py)."""
from __future__ import annotations

import base64
import re
import shutil
from dataclasses import replace
from html.parser import HTMLParser

import numpy as np
import pytest
import xarray as xr

from pipeline.case import Case, Configuration, LoopSettings
from pipeline.flutter_change import flutter_change
from pipeline.report import mechanisms, write_report
from pipeline.report_figures import figure_data_uri, vg_overlay
from structures.common.errors import InputError
from structures.common.files import read_dataset, write_dataset
from tests.pipeline.run_fixture import (CONFIGS, CROSSINGS, DESIGN, EXPECTED_CHANGE, STOP_REASON,
                                        make_run)

DASH = "\u2013"
#: headers that name things (identifiers, text), not numbers: they carry no unit
NAME_HEADERS = {"configuration", "deck", "GVT", "stage", "standard", "stop reason", "test mode",
                "FE mode", "name", "check", "unit", "kind", "root", "flutter mode",
                "design variable", "acceptance check", "limits", "configuration:test mode",
                "FE mode before", "FE mode after", "selection role", "mechanism",
                "stage 0 mechanism", "stage 1 mechanism", "method"}


class Tables(HTMLParser):
    """Every <table> of a page: its id, header cells and body rows (cell texts)."""

    def __init__(self, text: str):
        super().__init__()
        self.tables, self._cell, self._row = [], None, None
        self.feed(text)

    def handle_starttag(self, tag, attrs):
        if tag == "table":
            self.tables.append({"id": dict(attrs).get("id"), "header": [], "rows": []})
        elif tag == "tr":
            self._row = []
        elif tag in ("td", "th"):
            self._cell = []

    def handle_data(self, data):
        if self._cell is not None:
            self._cell.append(data)

    def handle_endtag(self, tag):
        if tag in ("td", "th"):
            self._row.append(("th" if tag == "th" else "td", "".join(self._cell).strip()))
            self._cell = None
        elif tag == "tr":
            table = self.tables[-1]
            if all(kind == "th" for kind, _ in self._row):
                table["header"] = [text for _, text in self._row]
            else:
                table["rows"].append([text for _, text in self._row])


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    case, run_dir = make_run(tmp_path_factory.mktemp("report"))
    page = write_report(case, run_dir)
    return case, run_dir, page.read_text()


def _table5(text: str) -> dict:
    table = next(t for t in Tables(text).tables if t["id"] == "flutter-change")
    assert table["header"][:4] == ["configuration", "Mach [-]", "density [kg/m^3]", "flutter mode"]
    col = {h: i for i, h in enumerate(table["header"])}
    return {(r[0], float(r[1]), int(r[3][0])): {h: r[i] for h, i in col.items()}
            for r in table["rows"]}


def test_table5_entries_and_signs_by_hand(run):
    rows = _table5(run[2])
    assert set(rows) == set(EXPECTED_CHANGE)                  # FFFW at Mach 0.6: no crossing, no row
    for (config, mach, mode), (dv, df) in EXPECTED_CHANGE.items():
        row = rows[(config, mach, mode)]
        case = [0.2, 0.6].index(mach)
        assert row["stage 1 speed change [%]"] == (DASH if dv is None else f"{dv:+.2f}")
        assert row["stage 1 frequency change [%]"] == (DASH if df is None else f"{df:+.2f}")
        v1, f1 = CROSSINGS[1][config][case][mode - 1]
        assert float(row["stage 1 speed [m/s]"]) == pytest.approx(v1, rel=1e-12)
        assert float(row["stage 1 frequency [Hz]"]) == pytest.approx(f1, rel=1e-12)
        if dv is None:
            assert row["stage 0 speed [m/s]"] == DASH
        else:
            v0, f0 = CROSSINGS[0][config][case][mode - 1]
            assert float(row["stage 0 speed [m/s]"]) == pytest.approx(v0, rel=1e-12)
            assert float(row["stage 0 frequency [Hz]"]) == pytest.approx(f0, rel=1e-12)
    assert rows[("FFFW", 0.2, 1)]["stage 1 speed change [%]"].startswith("-")   # slower: negative


#: by hand from run_fixture.PARTICIPATION (modes 1 rigid, 2..4 flexible; test modes SW1B, SW1T,
#: SW2B paired with FE modes 2, 3, 4): 1st crossings rigid 20 % < 50 %, top flexible modes 2 (55 %)
#: and 3 (20 %); 2nd crossings rigid 10 %, modes 3 (70 %) and 2 (15 %)
FIRST, SECOND = "SW1B-SW1T (bending-torsion)", "SW1T-SW1B (bending-torsion)"


def test_flutter_mechanisms_named_in_table5_and_crossing_tables(run):
    rows = _table5(run[2])
    for (config, mach, mode) in EXPECTED_CHANGE:
        name = FIRST if mode == 1 else SECOND
        assert rows[(config, mach, mode)]["stage 1 mechanism"] == name
        assert rows[(config, mach, mode)]["stage 0 mechanism"] == (
            DASH if (config, mach, mode) == ("EFEW", 0.6, 2) else name)   # absent at stage 0
    crossing = [t for t in Tables(run[2]).tables if "mechanism" in t["header"]]
    assert len(crossing) == 4                              # 2 stages x 2 configurations
    at = crossing[0]["header"].index("mechanism")
    efew0 = {(r[2], r[4]): r[at] for r in crossing[0]["rows"]}
    assert efew0 == {("0.2", "200"): FIRST, ("0.2", "250"): SECOND, ("0.6", "180"): FIRST}
    # every crossing names the method that found it (the fixture's sweeps are p-k, PK)
    assert all(r[-1] == "p-k (PK)" for t in crossing for r in t["rows"])


def test_mechanism_body_freedom_and_unpaired_modes(run, tmp_path):
    _, run_dir, _ = run
    folder = tmp_path / "stage0"
    shutil.copytree(run_dir / "stage0" / "EFEW", folder / "EFEW")
    part = read_dataset(folder / "EFEW" / "flutter" / "participation.nc")
    part["participation"][:] = [[50.0, 30.0, 15.0, 5.0], [49.0, 5.0, 16.0, 30.0],
                                [0.0, 10.0, 45.0, 45.5]]
    write_dataset(part, folder / "EFEW" / "flutter" / "participation.nc")
    corr = read_dataset(folder / "EFEW" / "correlation.nc")
    corr["paired_fe_mode"][:] = [2, 3, 2]                  # FE mode 4 unpaired
    write_dataset(corr, folder / "EFEW" / "correlation.nc")
    names = [m[-1] for m in mechanisms(folder, "EFEW")]
    assert names == ["body-freedom: rigid mode 1-SW2B", "mode 4-SW1T", "mode 4-SW1T"]
    assert mechanisms(folder, "FFFW") == []               # no participation.nc: nothing to name


def _points(rows, mach=(0.2, 0.6), units="si"):
    """A participation.nc with points (case, flutter_mode, velocity, frequency)."""
    rows = list(rows)
    col = list(zip(*rows)) if rows else [(), (), (), ()]
    p = "flutter_point"
    return xr.Dataset(
        {"participation": ((p, "mode"), np.full((len(rows), 2), 50.0))},
        coords={"case": (p, np.array(col[0], int)), "flutter_mode": (p, np.array(col[1], int)),
                "mach": (p, np.array([mach[c] for c in col[0]], float)),
                "density": (p, np.full(len(rows), 1.225)),
                "velocity": (p, np.array(col[2], float)), "frequency": (p, np.array(col[3], float)),
                "root": (p, np.array(col[1], int)), "mode": [1, 2]},
        attrs={"units": units})


def test_flutter_change_matches_nth_crossing_and_signs():
    stage0 = {"A": _points([(0, 1, 200.0, 5.0), (0, 2, 250.0, 8.0), (1, 1, 100.0, 4.0)])}
    stage1 = {"A": _points([(0, 1, 150.0, 6.0), (0, 2, 275.0, 6.0), (1, 1, 125.0, 3.0)])}
    fc = flutter_change([stage0, stage1])
    at = fc.sel(stage=1, configuration="A")
    # hand: 100 (150 - 200) / 200 = -25; 100 (275 - 250) / 250 = +10; 100 (125 - 100) / 100 = +25
    np.testing.assert_allclose(at["velocity_change"].values, [[-25.0, 10.0], [25.0, np.nan]],
                               rtol=1e-12)
    np.testing.assert_allclose(at["frequency_change"].values, [[20.0, -25.0], [-25.0, np.nan]],
                               rtol=1e-12)
    np.testing.assert_array_equal(fc["velocity_change"].sel(stage=0).values[0],
                                  [[0.0, 0.0], [0.0, np.nan]])
    assert fc["mach"].values.tolist() == [0.2, 0.6]
    assert fc["velocity"].attrs["units"] == "m/s" and fc.attrs["units"] == "si"
    assert fc["velocity_change"].attrs["units"] == "%"


def test_flutter_change_keas_of_matched_points_by_hand(tmp_path):
    # a matched line in the stratosphere: same true airspeed (M a, a constant), the stage-1
    # crossing lower (denser air): KEAS 65 -> 64 kn is -1.538 % while the speed change is 0
    stage0 = {"A": _points([(0, 1, 3299.2, 1.33)]).assign_coords(
        keas=("flutter_point", [65.0]))}
    stage1 = {"A": _points([(0, 1, 3299.2, 1.27)]).assign_coords(
        keas=("flutter_point", [64.0]))}
    fc = flutter_change([stage0, stage1])
    at = fc.sel(stage=1, configuration="A", case=0, flutter_mode=1)
    assert float(at["velocity_change"]) == 0.0
    assert float(at["keas_change"]) == pytest.approx(100.0 * (64.0 - 65.0) / 65.0, rel=1e-12)
    assert fc["keas"].attrs["units"] == "kn" and fc["keas_change"].attrs["units"] == "%"
    plain = flutter_change([{"A": _points([(0, 1, 200.0, 5.0)])}])
    assert np.isnan(plain["keas"].values).all()        # not matched-point: no KEAS
    case, run_dir = make_run(tmp_path)
    write_dataset(fc.assign_coords(configuration=["EFEW"], mach=("case", [0.2])),
                  run_dir / "flutter_change.nc")
    rows = _table5(write_report(case, run_dir).read_text())
    assert rows[("EFEW", 0.2, 1)]["stage 0 KEAS [kn]"] == "65"
    assert rows[("EFEW", 0.2, 1)]["stage 1 KEAS change [%]"] == "-1.54"


def test_flutter_change_mismatched_crossing_counts_are_nan():
    stage0 = {"A": _points([(0, 1, 200.0, 5.0), (0, 2, 250.0, 8.0)]), "B": _points([(0, 1, 90.0, 2.0)])}
    fewer = {"A": _points([(0, 1, 220.0, 5.0)])}                           # no B, one crossing of A
    more = {"A": _points([(0, 1, 180.0, 5.0), (0, 2, 240.0, 8.0), (0, 3, 260.0, 9.0)]),
            "B": _points([])}
    fc = flutter_change([stage0, fewer, more])
    dv = fc["velocity_change"].sel(configuration="A", case=0)
    assert dv.sel(stage=1, flutter_mode=1) == pytest.approx(10.0, rel=1e-12)
    assert np.isnan(dv.sel(stage=1, flutter_mode=2))                       # crossing lost
    assert dv.sel(stage=2, flutter_mode=2) == pytest.approx(-4.0, rel=1e-12)
    assert np.isnan(dv.sel(stage=2, flutter_mode=3))                       # new crossing
    assert np.isnan(fc["velocity"].sel(stage=0, configuration="A", case=0, flutter_mode=3))
    assert np.isnan(fc["velocity_change"].sel(configuration="B", stage=[1, 2])).all()


def test_flutter_change_rejects_bad_input():
    with pytest.raises(InputError, match="no stage"):
        flutter_change([])
    with pytest.raises(InputError, match="share a case and flutter_mode"):
        flutter_change([{"A": _points([(0, 1, 200.0, 5.0), (0, 1, 210.0, 5.0)])}])
    with pytest.raises(InputError, match="same FLUTTER cards"):
        flutter_change([{"A": _points([(0, 1, 200.0, 5.0)])},
                        {"A": _points([(0, 1, 200.0, 5.0)], mach=(0.3, 0.6))}])
    empty = flutter_change([{"A": _points([])}, {"A": _points([])}])
    assert empty.sizes["case"] == 0 and empty.sizes["flutter_mode"] == 0


def test_page_is_self_contained(run):
    text = run[2]
    sources = re.findall(r"""src\s*=\s*['"]([^'"]*)['"]""", text)
    assert len(sources) == 1 + 2 * 2 + 2 * 2 * 4          # boundary, V-g per config x Mach, maps
    assert all(s.startswith("data:image/png;base64,") for s in sources)
    bare = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", text)
    for banned in ("http:", "https:", "//", "<link", "<script", "url(", "@import", "file:"):
        assert banned not in bare, banned


def test_every_table_header_has_a_unit(run):
    tables = Tables(run[2]).tables
    assert len(tables) > 20
    for table in tables:
        for header in table["header"]:
            assert header in NAME_HEADERS or re.search(r"\[[^\]]+\]", header), header


def test_sections_name_stage_and_configuration(run):
    case, _, text = run
    for stage in (0, 1):
        for config in CONFIGS:
            assert f"Stage {stage}, configuration {config}: test-analysis correlation" in text
            assert f"Stage {stage}, configuration {config}: mass properties" in text
        assert f"Stage {stage}: modal participation and mode selection (paper Table 6)" in text
    assert STOP_REASON in text
    corr = next(t for t in Tables(text).tables if t["header"][:2] == ["test mode", "name"])
    role = corr["header"].index("selection role")
    assert [r[role] for r in corr["rows"]] == ["primary", "primary", "secondary"]  # FE modes 2, 3, 4
    assert "Envelope and 1.15 x envelope" in text
    table24 = next(t for t in Tables(text).tables if t["header"][0] == "design variable")
    rows = {r[0]: r for r in table24["rows"]}
    # hand: 100 (1.1 - 1.0) / 1.0 = +10 %, 100 (1.6 - 2.0) / 2.0 = -20 % (on the lower bound 1.6)
    assert rows["PBAR 11 I1"][2:] == ["1.1", "+10.00", "+10.00"]
    assert rows["CONM2 5 mass"][2:] == ["1.6 (at bound)", "-20.00", "-20.00"]
    assert set(rows) == set(DESIGN)


def test_missing_pieces_are_left_out_with_a_reason(run, tmp_path):
    case, run_dir = run[0], shutil.copytree(run[1], tmp_path / "run")
    (run_dir / "flutter_change.nc").unlink()
    (run_dir / "stage0" / "FFFW" / "correlation.nc").unlink()
    no_gvt = Configuration(name="FFFW", deck=case.configurations[1].deck)
    baseline = Case(name="fixture", configurations=(case.configurations[0], no_gvt), units="si",
                    flutter=replace(case.flutter, envelope=None))
    text = write_report(baseline, run_dir).read_text()
    assert "No tuning stage was run" in text and "Stage 1" not in text
    assert "No envelope in the case's [flutter]" in text
    assert "No flutter_change.nc in the run folder" in text
    assert "Stage 0, configuration FFFW: no GVT for this configuration" in text
    assert "Stage 0, configuration FFFW: FE modes" in text


def test_stages_stop_where_the_loop_stopped(run, tmp_path):
    case, run_dir = run[0], shutil.copytree(run[1], tmp_path / "run")
    shutil.copytree(run_dir / "stage1", run_dir / "stage2")          # left by an earlier run
    longer = replace(case, loop=LoopSettings(stages=2))
    text = write_report(longer, run_dir, out=tmp_path / "page.html").read_text()
    assert "Stage 2" not in text and "stage 2" not in text
    shutil.rmtree(run_dir / "stage0")
    with pytest.raises(InputError, match="no stage0"):
        write_report(case, run_dir)


def test_vg_overlay_keeps_root_colours_and_tells_stages_by_line_style(run):
    _, run_dir, _ = run
    flutter = [read_dataset(run_dir / f"stage{k}" / "EFEW" / "flutter" / "flutter.nc")
               for k in (0, 1)]
    fig = vg_overlay(flutter, 0, ["stage 0", "stage 1"])
    lines = [ln for ln in fig.axes[0].get_lines() if ln.get_xydata().shape[0] > 2]
    assert len(lines) == 2 * 3                                    # 2 stages x 3 roots
    stage0, stage1 = lines[:3], lines[3:]
    assert [ln.get_color() for ln in stage0] == [ln.get_color() for ln in stage1]
    assert len({ln.get_color() for ln in stage0}) == 3
    assert {ln.get_linestyle() for ln in stage0} == {"-"}
    assert {ln.get_linestyle() for ln in stage1} == {"--"}
    # root 1 of stage 1 crosses g = 0 at 210 m/s (fixture: g = 0.002 (V - 210))
    x, g = stage1[0].get_xydata().T
    assert np.interp(0.0, g, x) == pytest.approx(210.0, rel=1e-12)
    uri = figure_data_uri(fig)
    assert base64.b64decode(uri.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
