"""Rigid-body root labels (flutter.rigid_roots) and body-freedom flutter (flutter.summary.BFF_SHARE).

Synthetic sweeps with hand-chosen eigenvalues and eigenvectors: the participation of each mode is
then known by hand (P_j = 100 m_j |u_j|^2 / sum m_k |u_k|^2), so the labels and the kinds are
checked against hand values, the threshold on both sides of its boundary. The flutter outputs
(flutter.nc, summary.json, flutter_summary.txt, V-g legend) carry the labels and kinds.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from flutter.crossings import Crossing
from flutter.plots import plot_vg
from flutter.results import (FLUTTER_KINDS, attach_crossings, is_flutter, stack_cases,
                             vg_dataset, write_flutter)
from flutter.rigid_roots import NEAR_ZERO, label_rigid_roots, label_results, root_labels
from flutter.summary import BFF_SHARE, crossing_kinds, flutter_summary
from structures.common.files import read_dataset

V = np.array([30.0, 60.0, 90.0])
OMEGA = np.array([0.0, 0.0, 2 * np.pi * 3.0])        # two rigid-body modes, one elastic at 3 Hz


def _sweep(p0, u0, crossing_u=None, velocity=V):
    """A 3-mode sweep whose roots have eigenvalues ``p0`` (3,) and eigenvectors ``u0`` (3, 3)
    at every speed (the labels look at the lowest one); one flutter crossing of root 3 with
    eigenvector ``crossing_u`` and one divergence of root 1."""
    npt = len(velocity)
    p = np.broadcast_to(np.asarray(p0, complex), (npt, 3)).copy()
    u = np.broadcast_to(np.asarray(u0, complex), (npt, 3, 3)).copy()
    g = np.where(p.imag > 0, 2 * p.real / np.where(p.imag > 0, p.imag, 1), 0.0)
    ds = vg_dataset(p, u, g, np.ones((npt, 3), bool), velocity, np.full(npt, 1.225),
                    np.full(npt, 0.2), b=2.0, modes=(1, 2, 3))
    if crossing_u is None:
        return ds
    cross = [Crossing(root=3, index=1, t=0.5, velocity=75.0, density=1.225, mach=0.2,
                      frequency=2.5, kind="flutter", converged=True, refined=True),
             Crossing(root=1, index=0, t=0.5, velocity=45.0, density=1.225, mach=0.2,
                      frequency=0.0, kind="divergence", converged=True, refined=True)]
    return attach_crossings(ds, cross, np.array([crossing_u, [1.0, 0.0, 0.0]], complex))


# Root 1: real, plunge-dominated; root 2: oscillatory (0.09 Hz, g -2.3 as bah_plane's short
# period), pitch-dominated; root 3: elastic.
P_PLUNGE, P_SP = 0.0 + 0.0j, 2 * np.pi * 0.09 * (-1.15 + 1.0j)
U_PLUNGE, U_SP, U_EL = [1.0, 0.05, 0.01], [0.2, 1.0, 0.05], [0.01, 0.1, 1.0]


@pytest.mark.parametrize("motions", [{1: "plunge", 2: "pitch", 3: ""}, None])
def test_plunge_and_short_period_named_from_eigen_data(motions):
    """With the modes' rigid motions, and without them for a two-rigid-mode (plunge-pitch) model."""
    ds = _sweep([P_PLUNGE, P_SP, 2 * np.pi * 3j], [U_PLUNGE, U_SP, U_EL])
    assert root_labels(ds, OMEGA, motions=motions) == ["plunge", "short period", ""]


def test_labels_follow_the_roots_not_their_numbers():
    """Root 1 oscillating in pitch and root 2 at zero: root 1 is the short period."""
    ds = _sweep([P_SP, P_PLUNGE, 2 * np.pi * 3j], [[0.1, 1.0, 0.0], [1.0, 0.1, 0.0], U_EL])
    motions = {1: "plunge", 2: "pitch"}
    assert root_labels(ds, OMEGA, motions=motions) == ["short period", "plunge", ""]


def test_short_period_with_plunge_dominated_energy():
    """data/bff_wing's short period at 10 m/s: 96 % plunge, 4 % pitch (h = V gamma / p is large
    at low speed); still the short period, the real pure-plunge root the plunge."""
    ds = _sweep([P_PLUNGE, P_SP, 2 * np.pi * 3j],
                [[1.0, 0.0, 0.0], [np.sqrt(0.96), np.sqrt(0.04), 0.0], U_EL])
    assert root_labels(ds, OMEGA, motions={1: "plunge", 2: "pitch"}) == ["plunge", "short period",
                                                                         ""]


def test_lateral_oscillation_is_not_the_short_period():
    """Roll-dominated oscillation (a Dutch roll) beside a longitudinal one."""
    omega = np.zeros(3)
    ds = _sweep([P_SP, P_SP, P_PLUNGE], [[0.1, 0.3, 1.0], [0.3, 1.0, 0.1], [1.0, 0.0, 0.0]])
    motions = {1: "plunge", 2: "pitch", 3: "roll"}
    assert root_labels(ds, omega, motions=motions) == ["rigid 1", "short period", "plunge"]


def test_near_zero_threshold_and_lowest_speed():
    """A root below NEAR_ZERO * rigid_hz at the lowest speed is the plunge (points in any order)."""
    slow = 2 * np.pi * 0.9 * NEAR_ZERO * 0.05 * 1j
    fast = 2 * np.pi * 1.1 * NEAR_ZERO * 0.05 * 1j
    motions = {1: "plunge", 2: "pitch"}
    for p1, expect in ((slow, "plunge"), (fast, "rigid 1")):
        ds = _sweep([p1, P_SP, 2 * np.pi * 3j], [U_PLUNGE, U_SP, U_EL], velocity=V[::-1])
        ds["eigenvalue"][{"velocity": slice(0, 2)}] = P_SP     # faster points: oscillatory
        assert root_labels(ds, OMEGA, motions=motions)[0] == expect


def test_other_rigid_roots_and_phugoid():
    """A pitch-dominated real root is not a plunge; surge-dominated oscillation is the phugoid;
    without motion names and three rigid modes nothing is guessed."""
    omega = np.array([0.0, 0.0, 0.0])
    ds = _sweep([P_PLUNGE, P_SP, 2 * np.pi * 0.02 * (-0.1 + 1j)],
                [[0.1, 1.0, 0.0], [0.0, 1.0, 0.1], [0.1, 0.1, 1.0]])
    motions = {1: "plunge", 2: "pitch", 3: "surge"}
    assert root_labels(ds, omega, motions=motions) == ["rigid 1", "short period", "phugoid"]
    assert root_labels(ds, omega) == ["rigid 1", "rigid 2", "rigid 3"]


def _bff_sweep(rigid_mass):
    """Flutter eigenvector u = (1, 0, 1) with generalized masses (m_r, 0, 10 - m_r): the rigid
    share of the flutter mode is 10 m_r % exactly."""
    mass = np.diag([rigid_mass, 1.0, 10.0 - rigid_mass])
    ds = _sweep([P_PLUNGE, P_SP, 2 * np.pi * 3j], [U_PLUNGE, U_SP, U_EL], [1.0, 0.0, 1.0])
    return ds, mass


@pytest.mark.parametrize("rigid_mass, kind", [(9.0, "body_freedom_flutter"), (0.5, "flutter"),
                                              (BFF_SHARE / 10, "body_freedom_flutter"),
                                              (BFF_SHARE / 10 - 1e-3, "flutter")])
def test_body_freedom_flutter_threshold(rigid_mass, kind):
    """90 % and 5 % rigid share on either side; 50 % exactly is body-freedom, 49.99 % is not."""
    ds, mass = _bff_sweep(rigid_mass)
    assert list(crossing_kinds(ds, mass, OMEGA)) == [kind, "divergence"]
    summary = flutter_summary(ds, mass, OMEGA, names={3: "SW1B"})
    fl = next(e for e in summary if e["root"] == 3)
    assert fl["kind"] == kind
    assert fl["type"] == ("body-freedom: rigid mode 1-SW1B" if kind != "flutter" else "SW1B")


def test_flutter_kinds():
    assert is_flutter("flutter") and is_flutter("body_freedom_flutter")
    assert not is_flutter("divergence")
    assert set(FLUTTER_KINDS) == {"flutter", "body_freedom_flutter"}


def test_outputs_carry_labels_and_kinds(tmp_path):
    """flutter.nc root_label(root); summary.json kind and root_label; the FLUTTER SUMMARY text's
    ROOT line; the V-g legend."""
    ds, mass = _bff_sweep(9.0)
    modes = {1: "plunge", 2: "pitch", 3: ""}
    labelled = label_rigid_roots(ds, mass, OMEGA, motions=modes)
    assert list(labelled["root_label"].values) == ["plunge", "short period", ""]
    write_flutter(tmp_path, [labelled, labelled], [{"mach": 0.2, "density": 1.225}] * 2)
    nc = read_dataset(tmp_path / "flutter.nc")
    assert list(nc["root_label"].values) == ["plunge", "short period", ""]
    summary = json.loads((tmp_path / "summary.json").read_text())
    assert [(e["root"], e["kind"], e.get("root_label")) for e in summary[:2]] == [
        (3, "body_freedom_flutter", None), (1, "divergence", "plunge")]
    text = (tmp_path / "flutter_summary.txt").read_text()
    assert text.count("ROOT = SHORT PERIOD") == 2 and text.count("ROOT = PLUNGE") == 2
    legend = [t.get_text() for t in plot_vg(labelled).axes[0].get_legend().get_texts()]
    assert legend == ["root 1 (plunge)", "root 2 (short period)", "root 3"]


def test_stacked_labels_of_disagreeing_cases_are_joined():
    ds, mass = _bff_sweep(9.0)
    a = label_rigid_roots(ds, mass, OMEGA, motions={1: "plunge", 2: "pitch"})
    b = a.assign_coords(root_label=("root", ["plunge", "rigid 2", ""]))
    stacked = stack_cases([a, b], [{"mach": 0.2}, {"mach": 0.3}])
    assert list(stacked["root_label"].values) == ["plunge", "short period / rigid 2", ""]


def test_label_results_reads_the_modes_dataset():
    """Masses, frequencies and rigid motions taken from a modes Dataset (DESIGN.md section 6)."""
    import xarray as xr

    ds, _ = _bff_sweep(9.0)
    modes = xr.Dataset({"frequency": ("mode", [0.0, 0.0, 3.0]),
                        "generalized_mass": ("mode", [9.0, 1.0, 1.0])},
                       coords={"mode": [1, 2, 3], "rigid_motion": ("mode", ["plunge", "pitch", ""])})
    (_, out), = label_results([({"mach": 0.2}, ds)], modes)
    assert list(out["root_label"].values) == ["plunge", "short period", ""]
    assert list(out["crossing_kind"].values) == ["body_freedom_flutter", "divergence"]
