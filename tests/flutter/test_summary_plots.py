"""Flutter summary (type, 15% margin), plots, and the ``pipeline flutter`` command."""
from __future__ import annotations

import argparse
import json
import warnings

import numpy as np
import pytest
import xarray as xr

from aero.strip import section_gaf
from flutter.plots import plot_flutter_boundary, plot_mode_snapshot, plot_vg
from flutter.pk import pk_solve
from flutter.summary import BFF_SHARE, Envelope, flutter_summary
from flutter.system import ModalSystem
from flutter_nastran import DATA
from structures.common.errors import InputError
from structures.common.files import read_dataset

A, E, MU, R2, SIGMA = -0.2, -0.1, 20.0, 0.24, 0.4


def section():
    m = MU * np.pi
    M = np.array([[m, m * (E - A)], [m * (E - A), m * R2]])
    return ModalSystem(M, np.diag([m * SIGMA ** 2, m * R2]))


@pytest.fixture(scope="module")
def sweep():
    return pk_solve(section(), lambda mach, k: section_gaf(k, A, 1.0), np.linspace(0.1, 3.2, 40),
                    density=1.0, mach=0.0, refc=2.0)


def test_summary_type_and_margin(sweep):
    sys_ = section()
    omega, _ = sys_.in_vacuo()
    env = Envelope(mach=(0.0, 0.5), velocity=(1.8, 1.8))
    out = flutter_summary(sweep, sys_.mass, omega, env, names={1: "SW1B", 2: "SW1T"})
    assert [e["kind"] for e in out] == ["flutter", "divergence"]
    fl = out[0]
    assert fl["type"].endswith("(bending-torsion)")
    assert fl["margin"] == pytest.approx(fl["velocity"] / (1.15 * 1.8) - 1)
    assert fl["margin"] > 0  # 2.18 > 1.15 x 1.8
    assert out[1]["type"] == "divergence"


def test_body_freedom_type(sweep):
    """Declaring mode 1 rigid: its share of the flutter mode (>= BFF_SHARE) makes the crossing
    body-freedom flutter, its type naming the rigid and the flexible mode."""
    from flutter.participation import crossing_participation

    sys_ = section()
    omega = np.array([0.0, 1.0])  # mode 1 declared rigid
    share = float(crossing_participation(sweep, sys_.mass, omega).rigid_total[0])
    assert share >= BFF_SHARE
    out = flutter_summary(sweep, sys_.mass, omega)
    assert out[0]["kind"] == "body_freedom_flutter"
    assert out[0]["type"] == "body-freedom: rigid mode 1-mode 2"
    assert out[1]["kind"] == out[1]["type"] == "divergence"


def test_envelope_validation():
    with pytest.raises(InputError, match="increasing Mach"):
        Envelope(mach=(0.5, 0.3), velocity=(1.0, 1.0))


def test_plots(tmp_path, sweep):
    fig = plot_vg(sweep)
    assert len(fig.axes) == 2 and len(fig.axes[0].lines) >= 2
    fig.savefig(tmp_path / "vg.png")
    sys_ = section()
    omega, _ = sys_.in_vacuo()
    pts = flutter_summary(sweep, sys_.mass, omega)
    fig = plot_flutter_boundary(pts, Envelope(mach=(0.0, 0.5), velocity=(1.8, 1.9)))
    assert any(line.get_label() == "1.15 x envelope" for line in fig.axes[0].lines)
    fig.savefig(tmp_path / "boundary.png")
    n = 4
    modes = xr.Dataset({"shape": (("mode", "dof"), np.array([[1.0] * n, [0.0, 0.5, 1.0, 1.5]]))},
                       coords={"mode": [1, 2], "component": ("dof", [3] * n),
                               "x": ("dof", [0.0, 1.0, 0.0, 1.0]), "y": ("dof", [0.0, 0.0, 1.0, 1.0])})
    fig = plot_mode_snapshot(modes, sweep.crossing_eigenvector.values[0])
    assert len(fig.axes) == 3
    fig.savefig(tmp_path / "mode.png")


def test_pipeline_flutter_command(tmp_path):
    import pipeline.cmd_flutter as cmd

    parser = argparse.ArgumentParser()
    cmd.add_parser(parser.add_subparsers(dest="command"))
    args = parser.parse_args(["flutter", str(DATA / "bah_plane" / "bah_plane.bdf"), "--out",
                              str(tmp_path), "--flutter-id", "502"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        assert args.func(args) == 0
    ds = read_dataset(tmp_path / "flutter.nc")
    assert ds["damping"].dims == ("case", "velocity", "root")
    summary = json.loads((tmp_path / "summary.json").read_text())
    # the elastic flutter first; above it the short period's real branch crosses zero, a static
    # pitch instability: Nastran's F06 (point 2) has its real root change sign between 435.5 and 450
    assert [c["kind"] for c in summary] == ["flutter", "divergence"]
    assert 435.5 <= summary[1]["velocity"] <= 450.0
    assert summary[0]["velocity"] == pytest.approx(394.0, rel=0.02)
