"""The library of candidate effects: small parametrised changes a model may be missing.

Each candidate is one kind of effect at one location with a few parameters, each defined so that
0 means "no effect" (all-zero values give a model with the same K and M) and relative to a stated
scale of the model (so that bounds do not depend on units):

``lumped_mass`` at a grid, parameters ``mass`` and ``inertia``
    A CONM2 (no offset) of m = ``mass`` times the model's total mass (deck mass units, before
    PARAM WTMASS) with the moment of inertia m ``inertia`` L^2 about each basic axis, L the
    model's size (the largest side of its grids' bounding box): ``inertia`` = (r / L)^2, r the
    radius of gyration, so that a mass spread around the grid (a cable bundle, an equipment
    rack) carries its rotary inertia (linear in the inertia, so that the refit's gradient does
    not vanish at a point mass, as it would in r). Bounds mass [0, 0.10], inertia [0, 0.01]
    (r up to L / 10). One candidate per grid that carries structure (referenced by an element,
    a rigid element or a CONM2) and whose translations are not all constrained. The screening
    samples the mass at inertia 0 (a point mass) and the refit frees the inertia.
    *Spread* (:func:`spread_sites`): the same mass spread in equal shares over a grid and the
    free grids one element layer around it (rigid elements included; label ``grid g spread
    over a, b, ...``), each share a CONM2 with its share of the inertia: a mass distributed
    along a member or over an attachment (a cable run, an engine on its pylon) that no one grid
    represents, where the rotary inertia of a point mass is its second moment only. One such
    candidate per distinct set of grids; a grid without a free neighbour has none.
    Once named, a mass may be added with one mass per grid of its neighbourhood
    (:func:`distributed`, :mod:`pipeline.diagnose.detail`): parameters ``mass_<g>`` per grid,
    then ``inertia``, the shares free (a mass that sits mostly on one grid of a spread, or on
    two grids unequally).
``joint_flexibility`` of a rigid element, parameters ``compliance`` and ``rotation``
    An RBE2, or an RBAR with all six independent components on one grid, stays rigid but is
    moved onto a new grid (id: the largest + 1) at its independent grid, which hangs on a
    zero-length CBUSH (basic axes, CID = 0, all six components) to the independent grid: the
    hung part moves as one body on a flexible attachment where the rigid element meets the
    structure (an engine on its mounts, a store or a control surface on its fittings; the usual
    idealisation of a joint, a zero-length spring between coincident grids). Its translational
    stiffness is k_ref,t / c_t and its rotational stiffness k_ref,r / c_r, with
    c_t = compliance 10^(-rotation / 2) and c_r = compliance 10^(rotation / 2): ``compliance``
    is the joint's geometric-mean compliance and ``rotation`` the decades by which its rotations
    are softer than its translations against the reference ratio (a joint's translational and
    rotational stiffness are separate properties of its fittings, a flange stiff in shear and
    soft in rocking or the reverse). k_ref is the median over the CBAR/CBEAM elements
    touching the element's grids (all beams of the model when none touch them) of
    k_ref,t = 12 E I / L^3 (the transverse stiffness term of the beam element),
    I = (I1 + I2) / 2; k_ref,r = k_ref,t I_h / m_h for the CONM2s on the hung grids (m_h their
    mass, I_h their largest moment of inertia about the independent grid: at rotation 0 one
    compliance puts the hung part's local translation and rotation modes at one frequency);
    without hung mass,
    k_ref,r = E I / L (the beam's bending stiffness per radian over its length) + k_ref,t d^2, d
    the largest distance of a hung grid from the independent one. At compliance 1 the joint is
    about as flexible as one adjacent element. Bounds [0, 1e5]: a joint whose hung mass has its
    local mode a few times the first elastic frequency is 10^0.5 - 10^4.5 times softer than an
    adjacent element (k_ref is the beam's, not the joint's);
    compliance 0 keeps the rigid element (whatever the rotation). Bounds of ``rotation``
    [-2, 2]. An RBE2 with several dependent grids also gives one candidate per dependent grid
    (detail ``dependent``): that grid alone leaves the RBE2 (written again without it) and hangs
    on a CBUSH to the independent grid (at mid-length, on its dependent components), the others
    stay rigid (a joint that is flexible on one side only, e.g. one control surface on its
    hinge line). The response is far from linear in the compliance, so the screening samples it
    on a ladder of sizes at rotation 0 (:data:`pipeline.diagnose.screen.LADDER`) and the refit
    frees the rotation. Once named, a joint may be added in its *directional* form
    (:func:`directional`, :mod:`pipeline.diagnose.detail`): parameters ``compliance_x``,
    ``compliance_y``, ``compliance_z``, ``compliance_rx``, ``compliance_ry``, ``compliance_rz``,
    one per CBUSH component (stiffness K_p = k_ref,t / c_p for the translations, k_ref,r / c_p for
    the rotations), bounds [0, 1e6] (the range of c_t and c_r above), all zero the rigid joint,
    every one > 0 otherwise. Skipped: rigid elements whose partial dependent
    components are not in basic axes. Very small compliances make K ill-conditioned: at 1e-6 on
    the X-56 wing ribs the rigid-body eigenvalues carry round-off of 2e-6 of the first elastic
    one (:data:`structures.modal.RIGID_ZERO` accepts up to 1e-4).
``member_taper`` of a member (:mod:`pipeline.diagnose.members`), parameters ``scale``, ``taper``
    Each element's section scaled in size by s = (1 + scale) (1 + taper (xi - 1/2)) at its
    mid-length xi, as a solid section is: A times s^2 and I1, I2, I12, J times s^4. ``scale``
    is the member's mean size against the uniform section it was idealised with (the section
    of one end or station, typically), ``taper`` its linear variation. Bounds scale
    [-0.3, 0.3] (I times 0.24 .. 2.9), taper [-0.8, 0.8].
    A member of fewer than :data:`~pipeline.diagnose.members.MIN_SEGMENTS` elements is first
    split in that many straight pieces (:func:`pipeline.diagnose.members.remesh`, new grids on
    its line), so that a member one element long has a taper too. An element keeps its PID when
    it is the PID's only element; otherwise it gets a new PID (a scaled copy of its property,
    numbered from the model's largest PID + 1). Applied again, to a member split or not, the
    factors multiply (each element's or piece's current property is scaled at its mid-length);
    a split member keeps its pieces, and a later ``member_curvature`` moves their grids onto
    its arc (bows add).
``member_curvature`` of a member, parameters ``bow_1``, ``bow_2``
    A parabolic bow: the member's middle rises by bow_1 L along each element's y axis (plane 1)
    and bow_2 L along its z axis (plane 2), L the member's length, the arc
    w(xi) = 4 bow L xi (1 - xi) (:func:`pipeline.diagnose.members.remesh`): the member's
    interior grids move onto it with what they carry (masses, rigid elements' independent
    grids, sensors), its end grids stay, and a member of fewer than
    :data:`~pipeline.diagnose.members.MIN_SEGMENTS` elements is split in that many straight
    pieces joined at new grids on the arc (one straight element cannot bow: its axial load
    path stays straight). Bending then couples with axial and torsion, and the member's
    axial stiffness falls with the square of the bow. Bounds [-0.15, 0.15], as four candidates
    per member, one per quadrant: bow_1 >= 0 or <= 0 with bow_2 >= 0 or <= 0 (labels
    ``bow +y +z``, ``bow +y -z``, ``bow -y +z``, ``bow -y -z``).
    The member's stiffness changes to second order in the bow (the axial softening ~ bow^2 of
    :mod:`pipeline.diagnose.members`) and only its couplings to first order, so the response
    is nearly even in the bow: a linear signature through 0 would predict the opposite change
    for the opposite bow, and within one quadrant a secant at one size is wrong at every other
    (the screening's second-order model, :mod:`pipeline.diagnose.quadratic`). Opposite bows
    are not the same bow turned over: their couplings change sign, and the grids and what they
    carry move to opposite sides (on the WINDY blind study's spar, its rib masses on its grids,
    the five of ten bows with a downward component were ``unexplained`` or named a mass when
    only the quadrants bow_1 >= 0 were offered, and named right with all four).
``boundary_stiffness`` at a grid in direction x, y or z, parameter ``k_<direction>``
    A grounded CELAS2 of stiffness k times m_total (2 pi f_1)^2, f_1 the model's lowest elastic
    frequency and m_total its total mass (consistent units): at k = 1 the spring alone would carry
    the whole mass at f_1. Bounds [0, 1]. A suspension identified from the test's suspension
    modes (:mod:`pipeline.diagnose.suspension`) is this kind at a grid with parameters ``k_x``,
    ``k_y``, ``k_z`` (direction ``xyz``): one CELAS2 per nonzero stiffness. x, y, z are the
    grid's displacement-frame axes 1, 2, 3
    (basic axes when CD = 0; a grounded CELAS2 rather than a CBUSH, which MYSTRAN cannot ground).
    One candidate per grid of ``lumped_mass`` and unconstrained direction.

The screening step of each parameter (:attr:`Candidate.reference`, :data:`PARAMETER_RANGES`) is
a plausible, clearly visible size: mass 0.02, inertia 4e-4 (r = L / 50), compliance 100,
rotation 0.5, scale 0.1, taper 0.3, bow 0.05, k 0.1.
New elements take ids from the model's largest element, CONM2 or rigid-element id + 1; new
properties from its largest PID + 1. This module is the library (the candidates, their bounds and
their other parametrisations); :mod:`pipeline.diagnose.apply` adds an effect to a model, to its
matrices or to a deck.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pipeline.diagnose.joints import joint_sites
from pipeline.diagnose.members import connectivity, find_members, fixed_masks, grow
from pipeline.diagnose.mirror import mirror_pairs
from structures.common.errors import InputError, card_message
from structures.massprops import mass_properties
from structures.model import FEModel
from structures.modes import elastic_index

KINDS = ("lumped_mass", "joint_flexibility", "member_taper", "member_curvature",
         "boundary_stiffness")
DIRECTIONS = ("x", "y", "z")

#: (lower, upper, reference) of each parameter, by kind and parameter name.
PARAMETER_RANGES = {
    "lumped_mass": {"mass": (0.0, 0.10, 0.02), "inertia": (0.0, 0.01, 4.0e-4)},
    "joint_flexibility": {"compliance": (0.0, 1.0e5, 100.0), "rotation": (-2.0, 2.0, 0.5)},
    "member_taper": {"scale": (-0.3, 0.3, 0.1), "taper": (-0.8, 0.8, 0.3)},
    "member_curvature": {"bow_1": (-0.15, 0.15, 0.05), "bow_2": (-0.15, 0.15, 0.05)},
    "boundary_stiffness": {f"k_{d}": (0.0, 1.0, 0.1) for d in DIRECTIONS},
}
#: Parameters of a joint with one compliance per CBUSH component (:func:`directional`), and
#: their (lower, upper, reference): the range of c_t and c_r over the bounds of compliance and
#: rotation.
JOINT_DIRECTIONS = tuple(f"compliance_{c}" for c in ("x", "y", "z", "rx", "ry", "rz"))
DIRECTIONAL_RANGE = (0.0, 1.0e6, 100.0)
#: Exponent n of the section fields scaled by s^n in ``member_taper``.
TAPER_EXPONENTS = {"A": 2, "I1": 4, "I2": 4, "I12": 4, "J": 4}


def _check_kinds(kinds) -> tuple:
    kinds = (kinds,) if isinstance(kinds, str) else tuple(kinds)
    bad = [k for k in kinds if k not in KINDS]
    if bad:
        raise InputError(f"unknown effect kind(s) {bad}. Fix: use some of {', '.join(KINDS)}.")
    return kinds


@dataclass(frozen=True)
class Location:
    """Where an effect acts: grid, element (or rigid element) and property ids, sorted."""

    grids: tuple = ()
    elements: tuple = ()
    properties: tuple = ()

    def __post_init__(self):
        for name in ("grids", "elements", "properties"):
            object.__setattr__(self, name, tuple(sorted({int(i) for i in getattr(self, name)})))

    def as_dict(self) -> dict:
        """``{"grids": [...], "elements": [...], "properties": [...]}``."""
        return {"grids": list(self.grids), "elements": list(self.elements),
                "properties": list(self.properties)}


@dataclass(frozen=True)
class Candidate:
    """One candidate effect: a kind at a location, with bounded parameters.

    Attributes
    ----------
    kind : str, one of :data:`KINDS`.
    location : Location
    label : str, human text (``"RBE2 7501 (5011-5021)"``, ``"grid 3005 z"``).
    parameters : tuple of str, parameter names.
    lower, upper : tuple of float, bounds of each parameter (0 inside).
    reference : tuple of float, a plausible, clearly visible size (the screening step), not 0.
    detail : tuple of (key, value) pairs the kind needs (scales, direction, member geometry).
    """

    kind: str
    location: Location
    label: str
    parameters: tuple
    lower: tuple
    upper: tuple
    reference: tuple
    detail: tuple = ()

    def __post_init__(self):
        _check_kinds(self.kind)
        for name in ("parameters", "lower", "upper", "reference"):
            object.__setattr__(self, name, tuple(getattr(self, name)))
        n = len(self.parameters)
        if not n or not len(self.lower) == len(self.upper) == len(self.reference) == n:
            raise InputError(f"candidate {self.label!r}: {n} parameters but {len(self.lower)} "
                             f"lower, {len(self.upper)} upper and {len(self.reference)} reference "
                             "values. Fix: give one of each per parameter.")
        if not all(lo <= 0.0 <= hi and lo <= ref <= hi and lo < hi
                   for lo, hi, ref in zip(self.lower, self.upper, self.reference)):
            raise InputError(f"candidate {self.label!r}: bounds {self.lower}..{self.upper} must "
                             f"contain 0 and the reference {self.reference}. Fix: widen them.")
        zero = [p for p, ref in zip(self.parameters, self.reference) if ref == 0.0]
        if zero:
            raise InputError(f"candidate {self.label!r}: reference 0 for {zero}: the screening "
                             "step and the refit's parameter scale (pipeline.diagnose.screen) "
                             "would be 0. Fix: give every parameter a nonzero reference "
                             "inside its bounds.")

    def get(self, key: str, default=None):
        """The value of ``key`` in :attr:`detail`."""
        return dict(self.detail).get(key, default)


def _candidate(kind, location, label, names, detail=()) -> Candidate:
    ranges = [PARAMETER_RANGES[kind][n] for n in names]
    return Candidate(kind, location, label, tuple(names), tuple(r[0] for r in ranges),
                     tuple(r[1] for r in ranges), tuple(r[2] for r in ranges), tuple(detail))


def spring(grid: int, directions: str, k_ref: float) -> Candidate:
    """A ``boundary_stiffness`` candidate at ``grid`` with one stiffness ``k_<d>`` per direction
    d of ``directions`` (some of ``"xyz"``, in that order), each over ``k_ref``."""
    return _candidate("boundary_stiffness", Location(grids=(grid,)), f"grid {grid} {directions}",
                      tuple(f"k_{d}" for d in directions),
                      (("direction", directions), ("k_ref", k_ref)))


# ----------------------------------------------------------------------------------- model scans
def _element_grids(model: FEModel) -> np.ndarray:
    """Grid ids referenced by elements, rigid elements and CONM2s."""
    parts = [nodes.ravel() for _, nodes, _ in connectivity(model)]
    ids = np.unique(np.concatenate(parts + [np.asarray(model.masses.grid, np.int64)]))
    return ids[ids > 0]


def _grids_and_masks(model: FEModel) -> tuple:
    """(grids, fixed, free): the grids that carry structure (:func:`_element_grids`), their
    constrained-component bit masks (:func:`pipeline.diagnose.members.fixed_masks`) and those of
    them whose translations are not all constrained."""
    grids = _element_grids(model)
    fixed = fixed_masks(model)[model.grids.index(grids)] if grids.size else np.zeros(0, int)
    return grids, fixed, grids[(fixed & 7) != 7]


def _lowest_elastic_frequency(model: FEModel) -> float:
    from structures.assembly import assemble
    from structures.modal import compute_modes
    # a frequency scale only: the deck's singularity table is preflight's to report
    ds = compute_modes(model, 8, system=assemble(model, warn=False))
    f = ds["frequency"].values[elastic_index(ds)]
    elastic = f[f > 0]
    if not elastic.size:
        raise InputError(card_message("no elastic mode among the 8 lowest modes, so the boundary "
                                      "stiffness scale cannot be set.", filename=model.filename,
                                      fix="pass frequency= (Hz) to candidates()."))
    return float(elastic[0])


def candidates(model: FEModel, kinds=KINDS, *, frequency: float | None = None
               ) -> tuple[Candidate, ...]:
    """Every candidate effect of the given kinds on the model.

    Parameters
    ----------
    model : FEModel
    kinds : sequence of str, some of :data:`KINDS`.
    frequency : float, optional
        The model's lowest elastic frequency [Hz] for the ``boundary_stiffness`` scale; computed
        (8 lowest modes) when not given and that kind is asked for.

    Returns
    -------
    tuple of Candidate, grouped by kind in the order of ``kinds``, then the mirror-image pairs
    (:func:`pipeline.diagnose.mirror.mirror_pairs`).
    """
    kinds = _check_kinds(kinds)
    out = []
    grids, fixed, free_grids = _grids_and_masks(model)
    props = mass_properties(model) if {"lumped_mass", "boundary_stiffness"} & set(kinds) else None
    members = find_members(model) if {"member_taper", "member_curvature"} & set(kinds) else ()
    for kind in kinds:
        if kind == "lumped_mass":
            detail = (("total_mass", props.weight),
                      ("length", float(np.ptp(model.grids.xyz, axis=0).max())))
            out += [_candidate(kind, Location(grids=(g,)), f"grid {g}",
                               tuple(PARAMETER_RANGES[kind]), detail)
                    for g in free_grids.tolist()]
            out += [_candidate(kind, Location(grids=spread), f"grid {g} spread over "
                               + ", ".join(str(n) for n in spread if n != g),
                               tuple(PARAMETER_RANGES[kind]), detail)
                    for g, spread in spread_sites(model, free_grids)]
        elif kind == "boundary_stiffness":
            f1 = _lowest_elastic_frequency(model) if frequency is None else float(frequency)
            k_ref = props.mass * (2.0 * np.pi * f1) ** 2
            for g, mask in zip(grids.tolist(), fixed.tolist()):
                out += [spring(g, d, k_ref) for c, d in enumerate(DIRECTIONS)
                        if not mask >> c & 1]
        elif kind == "joint_flexibility":
            out += [_candidate(kind, Location(grids=grids_j, elements=(eid,)), label,
                               tuple(PARAMETER_RANGES[kind]), detail)
                    for grids_j, eid, label, detail in joint_sites(model)]
        else:
            for m in members:
                names = PARAMETER_RANGES[kind]
                label = (f"member PID {m.pid} ({m.card} {m.eids[0]}" +
                         (f"..{m.eids[-1]}, grids {m.grids[0]}-{m.grids[-1]})"
                          if len(m.eids) > 1 else f", grids {m.grids[0]}-{m.grids[-1]})"))
                location = Location(grids=m.grids, elements=m.eids, properties=(m.pid,))
                if kind == "member_taper":
                    out.append(_candidate(kind, location, label, tuple(names), (("member", m),)))
                    continue
                for s1, s2 in ((1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)):
                    cand = _candidate(kind, location,
                                      f"{label} bow {'+-'[s1 < 0]}y {'+-'[s2 < 0]}z",
                                      tuple(names), (("member", m),))
                    up = cand.upper
                    out.append(replace(cand, lower=(min(0.0, s1 * up[0]), min(0.0, s2 * up[1])),
                                       upper=(max(0.0, s1 * up[0]), max(0.0, s2 * up[1])),
                                       reference=(s1 * cand.reference[0],
                                                  s2 * cand.reference[1])))
    return tuple(out) + mirror_pairs(model, out)


def spread_sites(model: FEModel, free_grids) -> list:
    """(g, grids) of every spread mass (module docstring): grid g and the free grids one element
    layer around it (rigid elements included), sorted, each set of grids once (the first
    centre's), none for a grid without a free neighbour.

    Parameters
    ----------
    model : FEModel
    free_grids : (n,) ids of the grids a mass may sit on.

    Returns
    -------
    list of (int, tuple of int)
    """
    around = _around(model, free_grids)
    out, seen = [], set()
    for g in sorted(around):
        grids = tuple(sorted(around[g]))
        if len(grids) > 1 and grids not in seen:
            seen.add(grids)
            out.append((g, grids))
    return out


def _around(model: FEModel, free_grids) -> dict:
    """{g: set of g and the free grids one element layer around it (rigid elements included)}
    for every free grid g."""
    free = set(np.asarray(free_grids, np.int64).tolist())
    around = {g: {g} for g in free}
    for _, nodes, _ in connectivity(model):
        for row in np.asarray(nodes).tolist():
            on = [n for n in row if n in free]
            for n in on:
                around[n].update(on)
    return around


def neighbours(model: FEModel, location: Location) -> Location:
    """The location grown by one element layer.

    The location's grids are its own and those of its elements; the grown location adds every
    element (rigid elements included) touching one of them and every grid of those elements;
    properties are those of the location and of the added elements.

    Parameters
    ----------
    model : FEModel
    location : Location

    Returns
    -------
    Location
    """
    grids, elements, props = grow(model, location.grids, location.elements, location.properties)
    return Location(grids=tuple(grids), elements=tuple(elements), properties=tuple(props))


# --------------------------------------------------------------------------- values and other forms
def check_values(candidate: Candidate, values) -> np.ndarray:
    """(npar,) float values of the candidate's parameters, checked: finite, one per parameter,
    inside the bounds (InputError naming the parameter otherwise)."""
    x = np.atleast_1d(np.asarray(values, float))
    if x.shape != (len(candidate.parameters),) or not np.all(np.isfinite(x)):
        given = np.asarray(values).tolist()
        raise InputError(f"candidate {candidate.label!r}: values {given} must "
                         f"be {len(candidate.parameters)} finite numbers "
                         f"({', '.join(candidate.parameters)}). Fix: give one value per parameter.")
    lo, hi = np.array(candidate.lower), np.array(candidate.upper)
    tol = 1e-12 * (hi - lo)
    bad = np.flatnonzero((x < lo - tol) | (x > hi + tol))
    if bad.size:
        i = bad[0]
        raise InputError(f"candidate {candidate.label!r}: {candidate.parameters[i]} = {x[i]:.6g} "
                         f"is outside its bounds [{lo[i]:.6g}, {hi[i]:.6g}]. Fix: keep the "
                         "parameter inside its bounds.")
    return x


def component_compliances(x) -> np.ndarray:
    """(6,) compliance per CBUSH component of a joint at (compliance, rotation):
    c_t = c 10^(-rotation / 2) three times, then c_r = c 10^(rotation / 2) three times."""
    split = 10.0 ** (0.5 * x[1])
    return np.repeat([x[0] / split, x[0] * split], 3)


def directional(candidate: Candidate, values) -> tuple[Candidate, np.ndarray]:
    """A ``joint_flexibility`` candidate at (compliance, rotation) as the same joint with one
    compliance per CBUSH component (module docstring).

    Parameters
    ----------
    candidate : Candidate, ``joint_flexibility`` with parameters ``compliance``, ``rotation``.
    values : (2,) its values, compliance > 0.

    Returns
    -------
    Candidate with parameters :data:`JOINT_DIRECTIONS`, and its (6,) values, which give the
    same model as ``values`` give ``candidate``.
    """
    x = check_values(candidate, values)
    if candidate.kind != "joint_flexibility" or candidate.parameters != ("compliance", "rotation"):
        raise InputError(f"candidate {candidate.label!r} ({candidate.kind}, parameters "
                         f"{candidate.parameters}) has no directional form. Fix: pass a "
                         "joint_flexibility candidate with parameters compliance, rotation.")
    if x[0] <= 0.0:
        raise InputError(f"candidate {candidate.label!r}: compliance {x[0]:g} is the rigid "
                         "joint, which has no directional form. Fix: pass a compliance > 0.")
    c = component_compliances(x)
    lo, hi, ref = DIRECTIONAL_RANGE
    n = len(JOINT_DIRECTIONS)
    fields = {"parameters": JOINT_DIRECTIONS, "lower": (lo,) * n, "upper": (hi,) * n,
              "reference": (ref,) * n}
    detail = dict(candidate.detail)
    if "sites" in detail:                                  # a mirror pair: images alike
        detail["sites"] = tuple(replace(site, **fields) for site in detail["sites"])
        detail["signs"] = tuple(((1.0,) * n,) * len(detail["signs"]))
    return replace(candidate, detail=tuple(detail.items()), **fields), np.clip(c, lo, hi)


def distributed(model: FEModel, candidate: Candidate, values) -> tuple[Candidate, np.ndarray]:
    """A ``lumped_mass`` at one grid or spread in equal shares as the same mass with one share
    per grid of its neighbourhood: parameters ``mass_<g>`` (each grid's mass over the model's
    total mass, bounds and reference of ``mass``) for every grid g of the location, then
    ``inertia`` ((r / L)^2 of each share, as before). The neighbourhood of a mass at one grid is
    the grid and the free grids one element layer around it (the grids of its spread mass); a
    spread mass keeps its grids. Label ``grids a, b, c``; detail ``per_grid`` True.

    Parameters
    ----------
    model : FEModel, the model the candidate was made on.
    candidate : Candidate, ``lumped_mass`` with parameters ``mass``, ``inertia`` at one site.
    values : (2,) its values.

    Returns
    -------
    Candidate with parameters ``mass_<g>`` per grid and ``inertia``, and its (n_grids + 1,)
    values: the named mass in equal shares over the named grids, 0 at the others, and its
    inertia (the same model as ``values`` give ``candidate``).
    """
    x = check_values(candidate, values)
    if (candidate.kind != "lumped_mass" or candidate.parameters != ("mass", "inertia")
            or candidate.get("sites") is not None):
        raise InputError(f"candidate {candidate.label!r} ({candidate.kind}, parameters "
                         f"{candidate.parameters}) is not a mass at one site. Fix: pass a "
                         "lumped_mass candidate with parameters mass, inertia.")
    named = candidate.location.grids
    grids = named
    if len(named) == 1:
        grids = tuple(sorted(_around(model, _grids_and_masks(model)[2]).get(named[0], named)))
    if len(grids) < 2:
        raise InputError(f"candidate {candidate.label!r}: grid {named[0]} has no free "
                         "neighbour, so its mass has no other distribution. Fix: keep the "
                         "named form.")
    lo, hi, ref = PARAMETER_RANGES["lumped_mass"]["mass"]
    n = len(grids)
    out = replace(candidate, location=Location(grids=grids),
                  label="grids " + ", ".join(map(str, grids)),
                  parameters=tuple(f"mass_{g}" for g in grids) + ("inertia",),
                  lower=(lo,) * n + candidate.lower[1:], upper=(hi,) * n + candidate.upper[1:],
                  reference=(ref,) * n + candidate.reference[1:],
                  detail=candidate.detail + (("per_grid", True),))
    shares = np.where(np.isin(grids, named), x[0] / len(named), 0.0)
    return out, np.append(shares, x[1])


def every_direction(model: FEModel, candidate: Candidate, values) -> tuple[Candidate, np.ndarray]:
    """A ``boundary_stiffness`` candidate in one direction as the same grid's spring in every
    direction its supports leave free (x, y, z in that order, direction e.g. ``yz``).

    Parameters
    ----------
    model : FEModel, the model the candidate was made on (its SPCs and GRID PS).
    candidate : Candidate, ``boundary_stiffness`` at one grid with one parameter ``k_<d>``.
    values : (1,) its value.

    Returns
    -------
    Candidate with parameters ``k_<d>`` for every free direction d, and its values: the given
    one in its direction and 0 in the others (the same model as ``values`` give ``candidate``).
    """
    x = check_values(candidate, values)
    if (candidate.kind != "boundary_stiffness" or len(candidate.parameters) != 1
            or candidate.get("sites") is not None):
        raise InputError(f"candidate {candidate.label!r} ({candidate.kind}, parameters "
                         f"{candidate.parameters}) is not a spring in one direction at one grid. "
                         "Fix: pass a boundary_stiffness candidate with one parameter k_<d>.")
    grid = candidate.location.grids[0]
    mask = int(fixed_masks(model)[model.grids.index([grid])[0]])
    out = spring(grid, "".join(d for c, d in enumerate(DIRECTIONS) if not mask >> c & 1),
                 candidate.get("k_ref"))
    return out, np.where(np.array(out.parameters) == candidate.parameters[0], x[0], 0.0)


