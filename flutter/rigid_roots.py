"""Rigid-body roots of a flutter sweep named as flight mechanics names them, and body-freedom
flutter crossings classified.

Every flutter solver returns one root per mode, root r starting from in-vacuo mode r (rigid-body
modes first), so the rigid-body roots are those whose starting mode is rigid: in-vacuo frequency
below ``rigid_hz`` (0.05 Hz, the convention of
:func:`flutter.participation.crossing_participation`).
Each is judged at the lowest speed of the sweep where it is solved, by its eigenvalue and its
eigenvector's modal participation (:func:`flutter.participation.participation_factors`):

- ``"plunge"``: a real or near-zero root (``|p|`` below ``NEAR_ZERO * rigid_hz``) whose largest
  rigid-body share is the plunge: the altitude (heave) root, whose aerodynamic stiffness is zero
  (Etkin & Reid, *Dynamics of Flight*, 3rd ed., sec. 6.2: the plunge-pitch characteristic
  equation has a root at zero);
- ``"short period"``: an oscillatory root whose rigid-body share is mostly longitudinal (plunge
  and pitch together more than surge and than the lateral sway, roll and yaw): the short-period
  pair (Etkin & Reid sec. 6.2). Pitch alone is no test: in a short period the flight path turns
  little, but the plunge displacement h = V gamma / p is large at low speed, so its kinetic
  energy can dominate (data/bff_wing's 0.5 Hz short period at 10 m/s is 96 % plunge, 4 % pitch);
- ``"phugoid"``: an oscillatory root whose rigid-body share is mostly surge (needs a free surge);
- ``"rigid <n>"`` otherwise (n the starting mode's id, e.g. the Dutch roll or a pitch
  instability), ``""`` for elastic roots.

Each name goes to one root at most: of several candidates, the plunge to the one with the
largest plunge share, the short period to the one with the largest pitch share, the phugoid to
the one with the largest surge share.

The rigid motion of each mode comes from ``motions`` (mode id -> "plunge", "pitch", ... : the modes'
``rigid_motion`` coordinate, :func:`structures.modal.rigid_body_modes`). Without it (modes imported
from Nastran carry no names) a model with exactly two rigid-body modes is taken as the plunge-pitch
model: its oscillatory rigid root is the short period and its near-zero one the plunge.
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from flutter.participation import participation_factors
from flutter.summary import crossing_kinds

#: A rigid-body root below ``NEAR_ZERO * rigid_hz`` (Hz) at the lowest speed is near zero (the
#: plunge): a tenth of the rigid-mode threshold, 0.005 Hz by default, against 0.09 Hz for
#: bah_plane's short period at 30 m/s (Nastran PK point 2).
NEAR_ZERO = 0.1
#: ... and below this share of the largest rigid root's |p| at that speed (bah_plane at 30 m/s:
#: the plunge drift root 0.0003 rad/s against the short period's 0.86; X-56A-class EFEW: 0.0015
#: against 3.3).
NEAR_SHARE = 0.05
#: Rigid-body motions (structures.modal.RIGID_MOTIONS) grouped as flight mechanics separates them.
_GROUPS = {"longitudinal": ("plunge", "pitch"), "surge": ("surge",),
           "lateral": ("sway", "roll", "yaw"),
           "all": ("surge", "sway", "plunge", "roll", "pitch", "yaw")}


def _lowest_speed(ds: xr.Dataset) -> tuple[np.ndarray, np.ndarray]:
    """Per root, eigenvalue (nroot,) and eigenvector (nroot, nmode) at its lowest solved speed."""
    dim = ds.attrs.get("sweep", "velocity")
    p = ds["eigenvalue"].transpose(dim, "root").values
    u = ds["eigenvector"].transpose(dim, "root", "mode").values
    v = ds["velocity"]
    speed = (v.transpose(dim, "root").values if "root" in v.dims
             else np.repeat(np.asarray(v.values, float)[:, None], p.shape[1], axis=1))
    solved = np.isfinite(p) & np.isfinite(speed) & np.all(np.isfinite(u), axis=-1)
    first = np.argmin(np.where(solved, speed, np.inf), axis=0)
    roots = np.arange(p.shape[1])
    return p[first, roots], u[first, roots]


def root_labels(ds: xr.Dataset, omega: np.ndarray, rigid_hz: float = 0.05, *,
                mass: np.ndarray | None = None, motions: dict | None = None) -> list[str]:
    """Flight-mechanics name of every root of a sweep (module docstring).

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep of any flutter method (``eigenvalue`` and ``eigenvector`` on (sweep, root[, mode]),
        ``velocity`` per point or per root).
    omega : ndarray, shape (n,)
        In-vacuo circular frequency of each mode [rad/s] (rigid-body modes below ``rigid_hz``).
    rigid_hz : float
        Modes below this frequency [Hz] are rigid-body modes.
    mass : ndarray, shape (n, n), optional
        Generalized mass for the participation (default identity: mass-normalised modes).
    motions : dict, optional
        Mode id -> rigid motion ("plunge", "pitch", "surge", ...; "" or absent for elastic modes).

    Returns
    -------
    list of str, length nroot
    """
    omega = np.asarray(omega, dtype=float)
    n = omega.size
    rigid = omega / (2 * np.pi) < rigid_hz
    modes = [int(m) for m in ds["mode"].values]
    motion = np.array([str((motions or {}).get(m, "")) for m in modes])
    named = bool(motions) and bool(np.any(motion[rigid] != ""))
    p, u = _lowest_speed(ds)
    share = participation_factors(u, np.eye(n) if mass is None else mass)
    roots = [r for r in range(min(ds.sizes["root"], n)) if rigid[r]]
    # near zero: below NEAR_ZERO x rigid_hz and far below the largest rigid root at that speed
    # (a sweep that starts slowly has a slow short period too: p scales with V)
    largest = float(np.abs(p[roots]).max()) if roots else 0.0
    near_zero = (np.abs(p) / (2 * np.pi) < NEAR_ZERO * rigid_hz) & (np.abs(p) <= NEAR_SHARE * largest)
    near_zero |= p.imag <= 0
    # (label, candidate roots, score): each label goes to its best-scoring candidate.
    if named:
        of = {name: share[:, rigid & (motion == name)].sum(axis=1) for name in _GROUPS["all"]}
        group = {g: sum(of[name] for name in members) for g, members in _GROUPS.items()
                 if g != "all"}
        main = np.array([max(group, key=lambda g: group[g][r]) for r in range(len(p))])
        top = np.array([max(of, key=lambda name: of[name][r]) for r in range(len(p))])
        wanted = [("plunge", near_zero & (top == "plunge"), of["plunge"]),
                  ("short period", ~near_zero & (main == "longitudinal"), of["pitch"]),
                  ("phugoid", ~near_zero & (main == "surge"), of["surge"])]
    elif rigid.sum() == 2:
        wanted = [("plunge", near_zero, -np.abs(p)), ("short period", ~near_zero, np.abs(p))]
    else:
        wanted = []
    labels = ["" for _ in range(ds.sizes["root"])]
    for r in roots:
        labels[r] = f"rigid {modes[r]}"
    for label, ok, score in wanted:
        free = [r for r in roots if ok[r] and labels[r].startswith("rigid ")]
        if free:
            labels[max(free, key=lambda r: score[r])] = label
    return labels


def label_rigid_roots(ds: xr.Dataset, mass: np.ndarray, omega: np.ndarray, rigid_hz: float = 0.05,
                      motions: dict | None = None) -> xr.Dataset:
    """A sweep with its roots named and its body-freedom flutter crossings classified.

    Adds the coordinate ``root_label(root)`` (:func:`root_labels`) and sets ``crossing_kind`` to
    ``"body_freedom_flutter"`` for the flutter crossings whose rigid-body modes take at least
    :data:`flutter.summary.BFF_SHARE` of the participation (:func:`flutter.summary.crossing_kinds`).

    Parameters
    ----------
    ds : xarray.Dataset
        A sweep (any method).
    mass : ndarray, shape (n, n)
        Generalized mass.
    omega : ndarray, shape (n,)
        In-vacuo circular frequencies [rad/s].
    rigid_hz : float
    motions : dict, optional
        Mode id -> rigid motion (see :func:`root_labels`).

    Returns
    -------
    xarray.Dataset
    """
    labels = root_labels(ds, omega, rigid_hz, mass=mass, motions=motions)
    out = ds.assign_coords(root_label=("root", np.array(labels, dtype=str), {
        "long_name": "flight-mechanics name of rigid-body roots ('' elastic)"}))
    if "crossing_kind" in out:
        out["crossing_kind"] = ("crossing", crossing_kinds(ds, mass, omega, rigid_hz))
    return out


def label_results(results: list, modes: xr.Dataset, rigid_hz: float = 0.05) -> list:
    """:func:`label_rigid_roots` on every sweep of a flutter run.

    Parameters
    ----------
    results : list of (dict, xarray.Dataset)
        (label, sweep) pairs (:func:`flutter.solve.solve_flutter`).
    modes : xarray.Dataset
        The modes the sweeps were solved on (DESIGN.md section 6: ``frequency(mode)`` [Hz],
        ``generalized_mass(mode)``, optional ``rigid_motion(mode)``).
    rigid_hz : float

    Returns
    -------
    list of (dict, xarray.Dataset)
    """
    out = []
    for label, ds in results:
        used = modes.sel(mode=ds["mode"].values)
        mass = np.diag(np.asarray(used["generalized_mass"].values, dtype=float))
        omega = 2 * np.pi * np.maximum(np.asarray(used["frequency"].values, dtype=float), 0.0)
        motions = (dict(zip(used["mode"].values.tolist(), used["rigid_motion"].values.astype(str)))
                   if "rigid_motion" in used.coords else None)
        out.append((label, label_rigid_roots(ds, mass, omega, rigid_hz, motions)))
    return out
