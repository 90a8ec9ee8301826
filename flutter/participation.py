"""Modal participation factors of flutter roots (the reference paper's Table 6).

Definition (stated here once). For a flutter eigenvector u in modal coordinates (complex, shape (n,))
and generalized mass matrix M_hh, the participation of mode j is its share of the flutter motion's
kinetic-energy norm u^H M u:

    P_j = 100 * Re( conj(u_j) (M_hh u)_j ) / ( u^H M_hh u )   [%],

so sum_j P_j = 100 exactly. With a diagonal (mass-normalised) M_hh this is
P_j = 100 m_j |u_j|^2 / sum_k m_k |u_k|^2, non-negative; a coupled M_hh can give small negative
shares. Rigid-body modes (in-vacuo frequency below ``rigid_hz``) are included in the sum and shown,
as in Pak & Truong's Table 6 (x56a-model-tuning-paper, sec. IV.B), where the participation of the
primary modes is quoted "together with rigid body modes".
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from flutter.results import FLUTTER_KINDS
from structures.common.errors import InputError


def participation_factors(u: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """Kinetic-energy participation (%) of each mode in each eigenvector.

    Parameters
    ----------
    u : ndarray, shape (..., n) complex
        Eigenvectors in modal coordinates.
    mass : ndarray, shape (n, n)
        Generalized mass matrix M_hh.

    Returns
    -------
    ndarray, shape (..., n)
        P_j in percent; sums to 100 over the last axis.
    """
    u = np.asarray(u, dtype=complex)
    mass = np.asarray(mass, dtype=float)
    if u.shape[-1] != mass.shape[0]:
        raise InputError(f"participation: eigenvectors have {u.shape[-1]} modal coordinates but M_hh "
                         f"is {mass.shape}. Fix: use the eigenvectors of the same modal system.")
    Mu = np.einsum("ij,...j->...i", mass, u)
    parts = np.real(np.conj(u) * Mu)
    total = parts.sum(axis=-1, keepdims=True)
    if np.any(total <= 0):
        raise InputError("participation: an eigenvector has zero kinetic-energy norm. Fix: check "
                         "that the eigenvector is not all zeros.")
    return 100.0 * parts / total


def crossing_participation(ds: xr.Dataset, mass: np.ndarray, omega: np.ndarray,
                           rigid_hz: float = 0.05, kinds: tuple = FLUTTER_KINDS) -> xr.Dataset:
    """Participation of every mode in each flutter crossing of one sweep.

    Parameters
    ----------
    ds : xarray.Dataset
        A :func:`flutter.pk.pk_solve` result (with ``crossing_eigenvector``).
    mass : ndarray, shape (n, n)
        Generalized mass.
    omega : ndarray, shape (n,)
        In-vacuo circular frequency of each mode (to mark rigid-body modes).
    rigid_hz : float
        Modes below this frequency (Hz) are rigid-body modes.
    kinds : tuple of str
        Crossing kinds to include (default both flutter kinds, :data:`flutter.results.FLUTTER_KINDS`).

    Returns
    -------
    xarray.Dataset
        ``participation(flutter_mode, mode)`` [%] with flutter modes numbered 1, 2, ... in order of
        crossing speed; ``velocity``, ``frequency``, ``root`` per flutter mode; coordinate
        ``rigid(mode)``; ``rigid_total(flutter_mode)``.
    """
    if "crossing_eigenvector" not in ds:
        raise InputError("participation: the sweep has no crossing eigenvectors. Fix: pass the "
                         "Dataset returned by flutter.pk.pk_solve.")
    sel = [i for i in range(ds.sizes.get("crossing", 0)) if str(ds.crossing_kind.values[i]) in kinds]
    sel.sort(key=lambda i: float(ds.crossing_velocity[i]))
    u = ds.crossing_eigenvector.values[sel] if sel else np.zeros((0, ds.sizes["mode"]), complex)
    P = participation_factors(u, mass)
    rigid = np.asarray(omega) / (2 * np.pi) < rigid_hz
    out = xr.Dataset(
        {"participation": (("flutter_mode", "mode"), P, {"units": "%",
                           "definition": "100 Re(conj(u_j)(M u)_j) / (u^H M u)"}),
         "velocity": ("flutter_mode", ds.crossing_velocity.values[sel]),
         "frequency": ("flutter_mode", ds.crossing_frequency.values[sel], {"units": "Hz"}),
         "root": ("flutter_mode", ds.crossing_root.values[sel]),
         "rigid_total": ("flutter_mode", P[:, rigid].sum(axis=1), {"units": "%"})},
        coords={"flutter_mode": np.arange(1, len(sel) + 1), "mode": ds["mode"].values,
                "rigid": ("mode", rigid)},
    )
    return out


def participation_table(cases: list[tuple[dict, xr.Dataset]], primary: list[int] | None = None) -> str:
    """Text table of participation factors per case and flutter mode, like the paper's Table 6.

    Parameters
    ----------
    cases : list of (label, participation Dataset)
        ``label`` holds ``mach`` and ``configuration``; the Dataset comes from
        :func:`crossing_participation`.
    primary : list of int, optional
        Mode ids whose total (with the rigid-body modes) is printed as "Total".

    Returns
    -------
    str
    """
    cols = [(lab, ds, f) for lab, ds in cases for f in ds.flutter_mode.values]
    if not cols:
        return "no flutter crossing"
    modes = cases[0][1]["mode"].values
    ordinal = {1: "1st", 2: "2nd", 3: "3rd"}
    head1 = "mode  " + "".join(f"{str(lab.get('configuration', '')):>10s}" for lab, _, _ in cols)
    head2 = "      " + "".join(f"{'M=' + format(lab.get('mach', float('nan')), '.3f'):>10s}"
                              for lab, _, _ in cols)
    head3 = "      " + "".join(f"{ordinal.get(int(f), f'{int(f)}th'):>10s}" for _, _, f in cols)
    lines = [head1, head2, head3]
    for j, m in enumerate(modes):
        tag = " (rigid)" if bool(cases[0][1].rigid.values[j]) else ""
        vals = "".join(f"{float(ds.participation.sel(flutter_mode=f).values[j]):10.1f}"
                       for _, ds, f in cols)
        lines.append(f"{int(m):4d}  {vals}{tag}")
    if primary is not None:
        tot = []
        for _, ds, f in cols:
            P = ds.participation.sel(flutter_mode=f)
            keep = np.isin(ds["mode"].values, primary) | ds.rigid.values
            tot.append(float(P.values[keep].sum()))
        lines.append("Total " + "".join(f"{t:10.1f}" for t in tot))
    return "\n".join(lines)
