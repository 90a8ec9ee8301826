"""Suspension (rigid-body) modes among the test modes of a GVT.

A free-free aircraft is tested on a soft suspension (bungees, air springs), and many GVT reports
and files list its six suspension modes, numbered 1-6, before the elastic ones (the reference
paper counts them so). They are rigid-body motions of the structure on the suspension: a free-free
model has them at 0 Hz and no elastic mode that matches them, so a pairing that takes them for
elastic modes pairs every mode wrongly. This module finds them so that a workflow can set them
aside and say so.

Only a structure that can move as a rigid body has them: a caller asks only when its model has
rigid-body modes (a clamped structure's first bending mode, measured in one direction, can lie
90 % in the span below; the cantilever plate of ``plate_decks``, 20 x 12, z sensors: it did).

With shapes, a test mode is a suspension mode when its shape at the sensors lies almost wholly
in the span of the model's rigid-body motions at the sensors, share rho_j >= ``RIGID_SHARE``,
below the lowest elastic analysis frequency f_1 and below every test mode that does not
(suspension modes come first):

    rho_j = || P_R t_j ||^2 / || t_j ||^2,   P_R the orthogonal projector onto span(R),

R = R_6 C: R_6 (n_dof, 6) the readings of the unit rigid-body motions u = t + theta x (x - x_0)
at each sensor DOF (position x, component c in the basic frame; a translation reads e_c . u, a
rotation e_c . theta), x_0 the sensors' centroid (span(R) does not depend on it), and C (6, n_r)
the model's rigid-body modes as such motions (:func:`model_motions`, fitted to their shapes at
the model's grids). A free model has all six (C spans R^6); a constrained one fewer: a half
model on its plane of symmetry moves only in plunge and pitch, and its first symmetric bending
mode, seen at sensors on one half-span, is nearly a roll (0.94 of the share of the six on the
BAH wing, ``tests/data/bah_plane``, against 0.43 of plunge and pitch). White shape noise of
s (relative RMS per DOF) lowers a rigid mode's share to about 1 / (1 + s^2) (0.9975 at 5 %), and
an elastic mode of a free structure keeps a large part of its shape outside span(R) (the
X-56-class example's elastic modes: 0.58 at most, its suspension modes 0.995-0.998). The rank of
R is that of the sensor layout (all sensors on a line in one direction see fewer than six
motions); with fewer than ``MIN_DOFS`` DOFs per motion seen, no mode is judged by its shape.

Without shapes, a test mode below ``FREQUENCY_RATIO`` f_1 is taken as a suspension mode: no model
near enough to be tuned is that far off its first elastic mode, and a suspension is kept below it
by design (a third or less, by the usual rule).
"""
from __future__ import annotations

import numpy as np
import xarray as xr

from structures.common.errors import InputError
from structures.frames import rigid_offset
from structures.modes import elastic_index, rigid_index

#: Share of a test shape in the rigid-body span at or above which it is a suspension mode.
RIGID_SHARE = 0.9
#: Sensor DOFs needed per rigid-body motion the layout sees before any mode is judged by shape.
MIN_DOFS = 2
#: Largest relative misfit of a rigid-body mode's shape by a rigid motion of its grids (the
#: solver's rigid-body modes are exact to about 1e-12).
MOTION_TOLERANCE = 1e-6
#: Frequency-only: a test mode below this share of the lowest elastic analysis frequency.
FREQUENCY_RATIO = 0.5


def rigid_body_readings(position, component, reference=None) -> np.ndarray:
    """R: the sensor readings of the six unit rigid-body motions (module docstring).

    Parameters
    ----------
    position : (n_dof, 3) sensor positions, basic frame.
    component : (n_dof,) int, 1-3 translations, 4-6 rotations, basic axes.
    reference : (3,), optional, the point the rotations turn about; default the sensors'
        centroid.

    Returns
    -------
    (n_dof, 6) readings of the translations x, y, z and the rotations about x, y, z through the
    reference point.
    """
    x = np.asarray(position, float)
    comp = np.asarray(component, int)
    if x.ndim != 2 or x.shape != (comp.size, 3) or np.any((comp < 1) | (comp > 6)):
        raise InputError(f"sensor layout: positions {x.shape} and components {comp.shape} must be "
                         "(n_dof, 3) and (n_dof,) with components 1-6.")
    x0 = x.mean(axis=0) if reference is None else np.asarray(reference, float)
    rows = rigid_offset(x - x0)                                           # (n_dof, 6, 6)
    return rows[np.arange(comp.size), comp - 1]                          # u = t + theta x r


def model_motions(fe_modes: xr.Dataset, reference) -> np.ndarray | None:
    """C: the model's rigid-body modes as rigid-body motions about ``reference`` (module
    docstring), least squares on their shapes at every grid DOF that moves in some mode (a DOF
    zero in all of them is held: an SPC, or a rotation AUTOSPC holds at a grid only rods reach).

    Parameters
    ----------
    fe_modes : xarray.Dataset of analysis modes (:func:`structures.modal.compute_modes`: shapes in
        the basic frame, coordinates ``x``, ``y``, ``z``, ``component`` per DOF).
    reference : (3,) the point x_0 the motions turn about [length].

    Returns
    -------
    (6, n_r) translation and rotation of each rigid-body mode, or None when the modes carry no
    positions or a rigid-body mode is no rigid motion of its grids to ``MOTION_TOLERANCE``
    (shapes in local frames): the caller then takes all six motions.
    """
    rigid = rigid_index(fe_modes)
    if not rigid.size or not all(k in fe_modes.coords for k in ("x", "y", "z", "component")):
        return None
    free = np.any(fe_modes["shape"].values != 0.0, axis=0)
    position = np.stack([fe_modes[k].values[free] for k in ("x", "y", "z")], axis=1)
    rows = rigid_body_readings(position, fe_modes["component"].values[free], reference)
    shapes = fe_modes["shape"].values[rigid][:, free].T                  # (n_free, n_r)
    motions = np.linalg.lstsq(rows, shapes, rcond=None)[0]
    miss = np.linalg.norm(rows @ motions - shapes, axis=0) / np.linalg.norm(shapes, axis=0)
    return motions if np.all(miss <= MOTION_TOLERANCE) else None


def rigid_body_share(shape, position, component, motions=None) -> np.ndarray:
    """rho_j: the share of each test shape's squared norm in the rigid-body span (module
    docstring).

    Parameters
    ----------
    shape : (n_mode, n_dof) test shapes.
    position, component : the sensor layout (:func:`rigid_body_readings`).
    motions : (6, n_r), optional, C: the rigid-body motions the model has, about the sensors'
        centroid (:func:`model_motions`); default all six.

    Returns
    -------
    (n_mode,) shares in [0, 1]; NaN for every mode when the layout has fewer than ``MIN_DOFS``
    DOFs per rigid-body motion it sees.
    """
    t = np.asarray(shape, float)
    readings = rigid_body_readings(position, component)
    if motions is not None:
        readings = readings @ np.asarray(motions, float)                 # R = R_6 C
    u, sv, _ = np.linalg.svd(readings, full_matrices=False)
    rank = int(np.sum(sv > 1e-9 * sv[0])) if sv.size and sv[0] > 0 else 0
    if rank == 0 or t.shape[1] < MIN_DOFS * rank:
        return np.full(t.shape[0], np.nan)
    q = t @ u[:, :rank]
    norm = np.sum(t ** 2, axis=1)
    return np.divide(np.sum(q ** 2, axis=1), norm, out=np.zeros_like(norm), where=norm > 0)


def suspension_modes(gvt: xr.Dataset, first_elastic: float, *, position=None,
                     fe_modes: xr.Dataset | None = None) -> np.ndarray:
    """Which test modes are suspension modes (module docstring); ask only for a model with
    rigid-body modes.

    Parameters
    ----------
    gvt : xarray.Dataset in the :mod:`structures.gvt` layout.
    first_elastic : float, the lowest elastic analysis frequency f_1 [Hz].
    position : (n_dof, 3), optional, the sensor positions; default the Dataset's ``x``, ``y``,
        ``z`` coordinates (UFF 15); without either, shapes cannot be judged and no mode is one.
    fe_modes : xarray.Dataset, optional, the analysis modes: their rigid-body motions span the
        suspension modes (:func:`model_motions`); default all six motions.

    Returns
    -------
    (n_mode,) bool, in the Dataset's mode order.
    """
    f = np.asarray(gvt["frequency"].values, float)
    if "shape" not in gvt:
        return f < FREQUENCY_RATIO * float(first_elastic)
    if position is None:
        if not all(k in gvt.coords for k in ("x", "y", "z")):
            return np.zeros(f.size, bool)
        position = np.stack([gvt[k].values for k in ("x", "y", "z")], axis=1)
    position = np.asarray(position, float)
    motions = None if fe_modes is None else model_motions(fe_modes, position.mean(axis=0))
    share = rigid_body_share(gvt["shape"].values, position, gvt["component"].values, motions)
    rigid = (share >= RIGID_SHARE) & (f < float(first_elastic))          # NaN: False
    if not rigid.any():
        return rigid
    elastic = f[~rigid]
    return rigid & (f < (elastic.min() if elastic.size else np.inf))


def without_suspension(fe_modes: xr.Dataset, gvt: xr.Dataset, *, position=None
                       ) -> tuple[xr.Dataset, np.ndarray]:
    """The test modes without the suspension modes, for a model with rigid-body modes.

    Parameters
    ----------
    fe_modes : xarray.Dataset of analysis modes, rigid-body ones marked by ``rigid_motion``
        (:func:`structures.modes.rigid_index`); without any, every test mode is kept.
    gvt : xarray.Dataset in the :mod:`structures.gvt` layout.
    position : (n_dof, 3), optional, as :func:`suspension_modes`.

    Returns
    -------
    kept : xarray.Dataset, ``gvt`` without its suspension modes.
    hung : xarray.Dataset, the suspension modes left out (``mode`` of size 0 when none).

    Raises
    ------
    InputError
        Every test mode is a suspension mode.
    """
    f_fe = fe_modes["frequency"].values[elastic_index(fe_modes)]
    if not rigid_index(fe_modes).size or not f_fe.size:
        return gvt, gvt.isel(mode=slice(0, 0))
    rigid = suspension_modes(gvt, float(f_fe.min()), position=position, fe_modes=fe_modes)
    if rigid.all():
        raise InputError(f"GVT file {gvt.attrs.get('source') or '(arrays)'}: every test mode is "
                         "a suspension mode (a rigid-body motion at the sensors, or below "
                         f"{FREQUENCY_RATIO:g} x the lowest elastic analysis frequency "
                         f"{f_fe.min():.3g} Hz without shapes). Fix: give the elastic modes of "
                         "the test.")
    return gvt.isel(mode=~rigid), gvt.isel(mode=rigid)
