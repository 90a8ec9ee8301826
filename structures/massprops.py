"""Mass properties: total mass, centre of gravity and inertia tensor about the CG.

These are the quantities of the paper's performance indices J1..J10 (eqs. 1-10): weight W, CG
(x, y, z) and the inertias Ixx, Iyy, Izz, Ixy, Iyz, Izx at the CG. They are computed like Nastran's
grid point weight generator: the g-set mass matrix (basic axes, all grids, before constraints) is
projected on the six rigid-body motions about a reference point, M0 = D^T M_gg D, and the mass,
CG and inertia follow from M0. Inertias are reported as the positive tensor components
(Ixx = sum m (y^2 + z^2), Ixy = -sum m x y is the tensor entry; the paper's Ixy is the product
sum m x y, so ``product_of_inertia`` holds that sign convention too).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
import xarray as xr

from structures.assembly import assemble_g
from structures.common.errors import InputError, card_message
from structures.frames import rigid_offset, skew
from structures.model import FEModel


#: The ten measured quantities of the paper's J1..J10 (eqs. 1-10), by name.
MASS_QUANTITIES = ("weight", "x_cg", "y_cg", "z_cg", "Ixx", "Iyy", "Izz", "Ixy", "Iyz", "Izx")


@dataclass(frozen=True)
class MassProperties:
    """Rigid-body mass properties of a model (consistent mass units, after PARAM WTMASS).

    Attributes
    ----------
    mass : float
        Total mass (translational, x direction of the rigid-body mass matrix).
    cg : (3,) centre of gravity, basic frame.
    inertia : (3, 3) inertia tensor about the CG, basic axes (diagonal Ixx, Iyy, Izz; off-diagonal
        entries are minus the products of inertia).
    rigid_body_mass : (6, 6) rigid-body mass matrix about the reference point.
    reference_point : (3,)
    wtmass : float, the deck's PARAM WTMASS (weight = mass / wtmass in the deck's force units).
    """

    mass: float
    cg: np.ndarray
    inertia: np.ndarray
    rigid_body_mass: np.ndarray
    reference_point: np.ndarray
    wtmass: float = 1.0

    @property
    def weight(self) -> float:
        """Mass in the deck's weight units (mass / WTMASS), as Nastran's GPWG prints it."""
        return self.mass / self.wtmass

    @property
    def product_of_inertia(self) -> dict:
        """Products of inertia Ixy, Iyz, Izx = sum m x y, ... about the CG (paper eqs. 8-10)."""
        i = self.inertia
        return {"Ixy": -i[0, 1], "Iyz": -i[1, 2], "Izx": -i[2, 0]}

    def as_dict(self) -> dict:
        """The ten quantities of the paper's J1..J10 (``MASS_QUANTITIES``) plus ``mass``."""
        return {"mass": self.mass, "x_cg": self.cg[0], "y_cg": self.cg[1], "z_cg": self.cg[2],
                "Ixx": self.inertia[0, 0], "Iyy": self.inertia[1, 1], "Izz": self.inertia[2, 2],
                **self.product_of_inertia, "weight": self.weight}

    def to_dataset(self) -> xr.Dataset:
        """The mass properties as a Dataset (dims ``axis``, ``axis_2``, ``rigid_dof``,
        ``rigid_dof_2``); :meth:`from_dataset` reads it back."""
        axes = ["x", "y", "z"]
        dofs = np.arange(1, 7)
        return xr.Dataset({"mass": ((), self.mass), "cg": ("axis", self.cg),
                           "inertia": (("axis", "axis_2"), self.inertia),
                           "rigid_body_mass": (("rigid_dof", "rigid_dof_2"), self.rigid_body_mass),
                           "reference_point": ("axis", self.reference_point)},
                          coords={"axis": axes, "axis_2": axes, "rigid_dof": dofs,
                                  "rigid_dof_2": dofs},
                          attrs={"wtmass": self.wtmass, "inertia_convention":
                                 "tensor about the CG; off-diagonals are minus the products"})

    @classmethod
    def from_dataset(cls, ds: xr.Dataset) -> "MassProperties":
        """The mass properties of a :meth:`to_dataset` Dataset."""
        return cls(mass=float(ds["mass"]), cg=np.asarray(ds["cg"].values, float),
                   inertia=np.asarray(ds["inertia"].values, float),
                   rigid_body_mass=np.asarray(ds["rigid_body_mass"].values, float),
                   reference_point=np.asarray(ds["reference_point"].values, float),
                   wtmass=float(ds.attrs.get("wtmass", 1.0)))


def rigid_body_mass(m_basic, grid_xyz, reference=(0.0, 0.0, 0.0)) -> np.ndarray:
    """M0 = D^T M D about ``reference`` for a basic-frame g-set mass matrix.

    Parameters
    ----------
    m_basic : sparse or dense (6 ng, 6 ng)
    grid_xyz : (ng, 3)
    reference : (3,)

    Returns
    -------
    (6, 6)
    """
    d = rigid_offset(np.asarray(grid_xyz, float) - np.asarray(reference, float)).reshape(-1, 6)
    return d.T @ (m_basic @ d)


def properties_from_rigid_body_mass(m0, reference=(0.0, 0.0, 0.0), wtmass=1.0,
                                    filename: str = "") -> MassProperties:
    """Mass, CG and CG inertia from a 6x6 rigid-body mass matrix about ``reference``."""
    m0 = np.asarray(m0, float)
    mass = m0[0, 0]
    if not mass > 0:
        raise InputError(card_message("the model has no translational mass.", filename=filename,
                                      fix="add CONM2/CMASS2 or material densities."))
    # M0[:3, 3:] = -m skew(r_cg)  ->  r_cg from its skew entries (Nastran GPWG, per direction x).
    s = -m0[:3, 3:] / mass
    cg = np.array([s[2, 1], s[0, 2], s[1, 0]])
    inertia_ref = m0[3:, 3:]
    inertia_cg = inertia_ref - mass * (skew(cg).T @ skew(cg))
    return MassProperties(mass=float(mass), cg=cg, inertia=inertia_cg, rigid_body_mass=m0,
                          reference_point=np.asarray(reference, float), wtmass=wtmass)


def mass_properties(model: FEModel, *, mass: str = "deck", reference=(0.0, 0.0, 0.0),
                    m_basic=None) -> MassProperties:
    """Mass properties of a model.

    Parameters
    ----------
    model : FEModel
    mass : {'deck', 'consistent', 'lumped'}; the rigid-body properties do not depend on it.
    reference : (3,) reference point for the rigid-body mass matrix (basic).
    m_basic : optional pre-assembled g-set basic-frame mass (e.g. ``AssembledSystem.m_basic``).

    Returns
    -------
    MassProperties
    """
    if m_basic is None:
        _, m_basic = assemble_g(model, mass)
    m0 = rigid_body_mass(m_basic, model.grids.xyz, reference)
    return properties_from_rigid_body_mass(m0, reference, model.wtmass, model.filename)


def read_measured_mass(path) -> dict:
    """Measured mass properties from a JSON file, as :data:`MASS_QUANTITIES` values.

    The file holds ``{"weight": W, "cg": [x, y, z], "inertia_cg": [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]}``
    (any of the three keys may be left out): the moments and the products of inertia
    (Ixy = sum m x y, as :attr:`MassProperties.product_of_inertia`) about the CG, basic axes, in
    the deck's units (weight = mass / WTMASS).

    Raises
    ------
    InputError
        Naming the file, the key and the fix for a missing file, bad JSON, a list or an empty
        object, unknown keys, values that are not finite numbers of the right count, a weight
        that is not positive or an inertia no body has (:func:`check_measured_mass`).
    """
    import json
    from pathlib import Path

    path = Path(path)
    form = ('{"weight": 480.0, "cg": [x, y, z], "inertia_cg": [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]}')
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise InputError(f"file {path}: no such measured-mass file. Fix: check the path "
                         "(relative to the case file).") from None
    except (ValueError, UnicodeDecodeError) as exc:
        raise InputError(f"file {path}: not valid JSON ({exc}). Fix: write {form}.") from None
    lengths = {"weight": None, "cg": 3, "inertia_cg": 6}
    if not isinstance(data, dict):
        raise InputError(f"file {path}: holds a JSON {type(data).__name__}, not an object of "
                         f"named quantities. Fix: write {form}.")
    if set(data) - set(lengths):
        raise InputError(f"file {path}: unknown keys {sorted(set(data) - set(lengths))}; valid: "
                         f"{sorted(lengths)}. Fix: write {form}.")
    if not data:
        raise InputError(f"file {path}: names no quantity. Fix: write {form}, or leave "
                         "measured_mass out of the case.")
    out = {}
    for key, n in lengths.items():
        if key not in data:
            continue
        value = data[key]
        values = [value] if n is None else value
        if not (isinstance(values, list) and len(values) == (n or 1) and all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and np.isfinite(v)
                for v in values)):
            raise InputError(f"file {path}: {key} = {value!r} is not "
                             f"{'a finite number' if n is None else f'a list of {n} finite numbers'}"
                             f". Fix: write {form}.")
        names = {"weight": ("weight",), "cg": ("x_cg", "y_cg", "z_cg"),
                 "inertia_cg": ("Ixx", "Iyy", "Izz", "Ixy", "Izx", "Iyz")}[key]
        out.update({name: float(v) for name, v in zip(names, values)})
    return check_measured_mass(out, f"file {path}")


def check_measured_mass(measured: Mapping, where: str = "measured mass properties") -> dict:
    """Validate measured mass properties: names from :data:`MASS_QUANTITIES`, finite numbers, a
    positive weight and moments and products of inertia that a body can have
    (:func:`_check_inertia`)."""
    unknown = sorted(set(measured) - set(MASS_QUANTITIES))
    if unknown:
        raise InputError(f"{where}: unknown quantities {unknown}; valid: {list(MASS_QUANTITIES)}.")
    out = {}
    for name, value in measured.items():
        if not isinstance(value, (int, float)) or not np.isfinite(value):
            raise InputError(f"{where}: {name} = {value!r} is not a finite number.")
        out[name] = float(value)
    if "weight" in out and not out["weight"] > 0:
        raise InputError(f"{where}: weight = {out['weight']} must be positive. Fix: give the "
                         "measured weight in the deck's units (mass / PARAM WTMASS).")
    _check_inertia(out, where)
    return out


#: How far below zero a second moment of mass implied by measured moments and products of
#: inertia may fall, as a fraction of the largest moment: swing tests measure moments to a few
#: per cent (2 % is what the diagnosis assumes), so a flat body's near-zero second moment can
#: come out slightly negative; 5 % is 2.5 such standard deviations.
INERTIA_CONSISTENCY = 0.05


def _check_inertia(measured: Mapping, where: str) -> None:
    """Refuse moments and products of inertia that no body has.

    About any axes, S = sum m r r^T = (tr J / 2) 1 - J (J the inertia tensor, products
    Ixy = sum m x y entering it as -Ixy) is a second moment of mass, positive semi-definite:
    every moment is non-negative (zero about the line of masses on a line) and no moment
    exceeds the sum of the other two (S_zz = (Ixx + Iyy - Izz) / 2 >= 0). Checked when the
    three moments are given; with the products too on all of S, else on its diagonal.
    """
    moments = ("Ixx", "Iyy", "Izz")
    if not all(k in measured for k in moments):
        return
    diag = np.array([measured[k] for k in moments])
    if np.any(diag < 0.0) or not diag.max() > 0.0:
        bad = [k for k, v in zip(moments, diag) if v < 0.0] or list(moments)
        raise InputError(f"{where}: moments of inertia {bad} must not be negative, nor all zero "
                         "(a point mass's). Fix: give the moments about the CG in the deck's mass "
                         "and length units.")
    products = ("Ixy", "Iyz", "Izx")
    full = all(k in measured for k in products)
    s = np.diag(0.5 * diag.sum() - diag)
    if full:
        for (i, j), name in zip(((0, 1), (1, 2), (2, 0)), products):
            s[i, j] = s[j, i] = measured[name]
    lowest = float(np.linalg.eigvalsh(s)[0] if full else s.diagonal().min())
    if lowest < -INERTIA_CONSISTENCY * diag.max():
        what = ("with the products, a second moment of mass" if full else
                "a second moment of mass (half the sum of two moments less the third)")
        raise InputError(
            f"{where}: the moments {diag.tolist()}"
            + (f" and products [Ixy, Iyz, Izx] = {[measured[k] for k in products]}" if full else "")
            + f" are not a body's inertia: {what} comes to {lowest:.6g}, below zero by "
            f"{-100 * lowest / diag.max():.1f} % of the largest moment (at most "
            f"{100 * INERTIA_CONSISTENCY:.0f} % is measurement error). Fix: check that no moment "
            "exceeds the sum of the other two, the products' size and sign (Ixy = sum m x y) and "
            "the units.")


#: How far outside the extent of a model's grids and CONM2 centres a measured CG may lie, as a
#: fraction of the extent's largest side: a CG lies inside the body, so a CG beyond it is in
#: other units or axes; 5 % leaves room for a weighing's error and for mass (rods' and shells'
#: own) between grids nearer the edge.
CG_EXTENT_MARGIN = 0.05


def check_cg_inside(measured: Mapping, model: FEModel, where: str) -> None:
    """Refuse a measured CG that lies outside the model's extent (the box of its grids and
    CONM2 centres of mass, basic axes, widened by :data:`CG_EXTENT_MARGIN` of its largest
    side): a body's CG lies within it, so the CG is in other units or axes.

    Parameters
    ----------
    measured : mapping with any of ``x_cg``, ``y_cg``, ``z_cg`` (:data:`MASS_QUANTITIES`).
    model : FEModel
    where : str, the file or configuration (the message's start).

    Raises
    ------
    InputError
        Naming the coordinates, the extent and the fix.
    """
    axes = [(i, k) for i, k in enumerate(("x_cg", "y_cg", "z_cg")) if k in measured]
    if not axes or not len(model.grids.ids):
        return
    points = model.grids.xyz
    if len(model.masses.eids):
        points = np.vstack([points, model.grids.xyz[model.grids.index(model.masses.grid)]
                            + model.masses.offset])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = CG_EXTENT_MARGIN * float(np.max(high - low))
    outside = [f"{k} = {measured[k]:g} (the model spans {low[i]:g} .. {high[i]:g})" for i, k in axes
               if not low[i] - margin <= measured[k] <= high[i] + margin]
    if outside:
        raise InputError(f"{where}: the measured CG lies outside the model: "
                         f"{'; '.join(outside)}, more than {100 * CG_EXTENT_MARGIN:.0f} % of the "
                         "model's size beyond its grids and masses, where no body's CG can be. "
                         "Fix: give the CG in the deck's length unit and basic axes.")


def compare_mass_properties(props: MassProperties, measured: Mapping) -> xr.Dataset:
    """Model against measured mass properties, per quantity (the data of the paper's J1..J10).

    Parameters
    ----------
    props : MassProperties of the model.
    measured : {quantity: value} for some of :data:`MASS_QUANTITIES` (weight in the deck's weight
        units, i.e. mass / WTMASS).

    Returns
    -------
    xarray.Dataset on dim ``quantity``: ``model``, ``measured``, ``error`` (model - measured) and
    ``relative_error`` in % (eqs. 1-10 before squaring; NaN where the measured value is 0).
    """
    measured = check_measured_mass(measured)
    names = [q for q in MASS_QUANTITIES if q in measured]
    model = np.array([props.as_dict()[q] for q in names])
    test = np.array([measured[q] for q in names])
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(test != 0.0, 100.0 * (model - test) / test, np.nan)
    return xr.Dataset({"model": ("quantity", model), "measured": ("quantity", test),
                       "error": ("quantity", model - test),
                       "relative_error": ("quantity", rel, {"units": "%"})},
                      coords={"quantity": names})
