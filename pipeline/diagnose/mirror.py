"""Mirror-image pairs of candidate effects (DESIGN.md section 5, issue 14 step 4).

An aircraft is built, and modelled, symmetric about its plane of symmetry, and what a model lacks
usually is too: both landing-gear legs are tapered and bowed alike, both engines hang on the same
mounts, a sensor cable runs along each wing (the reference paper's gear finding, Pak & Truong,
sec. V, is of both legs). One side's candidate then explains half the change and needs a second
round, or is beaten by a compensating effect. So every candidate whose site has a mirror image
on the model gets a *pair*: the same kind, the same parameters, acting on the site and on its
mirror image at once; it competes with the one-sided candidates on the same terms (the same
parameter count), so the data decide between one side and both.

Mirror image: the reflection y -> -y of the basic frame (:data:`REFLECTION`), the convention of
aircraft models whose plane of symmetry is the basic XZ plane. A grid's image is the one grid at
the reflected position (within :data:`TOLERANCE` of the model's size; grids that coincide with
another, as at a hinge, have none, and images are mutual); a grid on the plane is its own image
and has no pair. The image of each kind's site:

- ``lumped_mass``: the image grid (a spread mass: the image grids); both get the same mass
  (parameter ``mass`` per site). Two spreads that share a grid on the plane have no pair (the
  shared grid would carry both shares; the spread around that grid is a candidate of its own).
- ``boundary_stiffness``: the image grid, the same direction letter (a spring's stiffness has no
  sign); only grids displaced in basic axes (CD = 0) on both sides.
- ``joint_flexibility``: the rigid element whose grids are the images of the joint's grids; whole
  joints only (a one-sided variant is paired through its whole joint).
- ``member_taper``: the member whose grids are the images; ``taper`` changes sign when the image
  member's chain runs the other way (the taper grows along the chain).
- ``member_curvature``: the image member; each bow takes the sign that makes its arc the
  reflection of the site's: the sign of (R y_e) . y_e' for ``bow_1`` and (R z_e) . z_e' for
  ``bow_2``, y_e, z_e the axes of a site element and y_e', z_e' those of its image element, R
  the reflection (a member whose image's axes are not the reflected axes within
  :data:`AXIS_TOLERANCE`, or whose elements want different signs, has no pair).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from structures.assembly import line_offsets
from structures.elements.beam import beam_axes
from structures.model import FEModel

#: The reflection of the basic frame onto the image side (plane of symmetry XZ).
REFLECTION = np.diag([1.0, -1.0, 1.0])
#: Largest distance of an image grid from the reflected position, relative to the model's size.
TOLERANCE = 1e-6
#: |cos| of the angle between a reflected element axis and its image's below which the image
#: member is not a mirror image (a member oriented differently on the two sides).
AXIS_TOLERANCE = 0.999


def mirror_grids(model: FEModel) -> dict:
    """Grid id -> id of its mirror image, for the grids that have one (a grid on the plane maps
    to itself).

    Parameters
    ----------
    model : FEModel

    Returns
    -------
    dict of int -> int
    """
    from scipy.spatial import cKDTree

    xyz = np.asarray(model.grids.xyz, float)
    if not len(xyz):
        return {}
    size = max(float(np.ptp(xyz, axis=0).max()), 1.0)
    tree = cKDTree(xyz)
    near = tree.query_ball_point(xyz @ REFLECTION, TOLERANCE * size)
    ids = np.asarray(model.grids.ids)
    image = {}
    for i, rows in enumerate(near):
        if abs(xyz[i, 1]) <= TOLERANCE * size:
            image[int(ids[i])] = int(ids[i])               # on the plane: its own image
        elif len(rows) == 1:                               # one grid there: coincident ones
            image[int(ids[i])] = int(ids[rows[0]])          # (hinges) have no certain image
    return {g: h for g, h in image.items() if image.get(h) == g}


def sites(candidate) -> tuple:
    """The one-sided candidates a candidate acts through: its two sites for a pair, else itself."""
    pair = candidate.get("sites")
    return tuple(pair) if pair is not None else (candidate,)


def site_values(candidate, values) -> list:
    """(site, values) of each site of a candidate at its parameter values (the image's signs
    applied)."""
    x = np.asarray(values, float)
    signs = candidate.get("signs")
    if signs is None:
        return [(candidate, x)]
    return [(site, x * np.asarray(s, float)) for site, s in zip(candidate.get("sites"), signs)]


def mirror_pairs(model: FEModel, candidates) -> tuple:
    """A pair candidate for every candidate whose site has a mirror image among the candidates
    (module docstring), each pair once.

    Parameters
    ----------
    model : FEModel, the model the candidates were built on.
    candidates : sequence of Candidate (one-sided).

    Returns
    -------
    tuple of Candidate, the pairs (kind of their sites, location the union of both, detail
    ``sites`` (site, image) and ``signs`` (per site, per parameter)).
    """
    image = mirror_grids(model)
    if not image:
        return ()
    one_sided = [c for c in candidates
                 if c.get("sites") is None and c.get("dependent") is None]
    by_site = {_key(c, None): c for c in one_sided}
    out = []
    for cand in one_sided:
        twin = by_site.get(_key(cand, image))
        if twin is None or twin.location.grids <= cand.location.grids:
            continue                                # no image, its own image, or the other side
        if cand.kind == "lumped_mass" and set(cand.location.grids) & set(twin.location.grids):
            continue                                # spreads meeting on the plane: see above
        signs = _signs(model, image, cand, twin)
        if signs is not None:
            out.append(_pair(cand, twin, signs))
    return tuple(out)


def _key(cand, image):
    """(kind, grids, direction) of the candidate's site, or of its mirror image with ``image``
    (None when a grid has no image). The four bow quadrants of a member share its key."""
    grids = cand.location.grids
    if image is not None:
        if any(g not in image for g in grids):
            return None
        grids = [image[g] for g in grids]
    return cand.kind, frozenset(grids), cand.get("direction")


def _signs(model: FEModel, image: dict, cand, twin):
    """(site signs, image signs) per parameter, or None when the image is not a mirror image."""
    ones = (1.0,) * len(cand.parameters)
    if cand.kind == "boundary_stiffness":
        cd = model.grids.cd[model.grids.index([cand.location.grids[0], twin.location.grids[0]])]
        return (ones, ones) if not np.any(cd) else None
    if cand.kind == "member_taper":
        forward = image[cand.get("member").grids[0]] == twin.get("member").grids[0]
        return ones, (1.0, 1.0 if forward else -1.0)
    if cand.kind == "member_curvature":
        return _bow_signs(model, image, cand.get("member"), twin.get("member"))
    return ones, ones


def _element_axes(model: FEModel, member, eid: int) -> np.ndarray:
    """(3, 3) axes (rows x, y, z in basic) of the member's element ``eid``."""
    es = model.elements[member.card]
    row = int(np.flatnonzero(np.asarray(es.eids) == eid)[0])
    sub = replace(es, eids=es.eids[[row]], pids=es.pids[[row]], nodes=es.nodes[[row]],
                  data={k: np.asarray(v)[[row]] for k, v in es.data.items()})
    gi = model.grids.index(sub.nodes, card=es.card, filename=model.filename)
    v, wa, wb = line_offsets(model, sub, gi, model.filename)
    xyz = model.grids.xyz
    return beam_axes(xyz[gi[:, 0]] + wa, xyz[gi[:, 1]] + wb, v)[0][0]


def _bow_signs(model: FEModel, image: dict, member, twin):
    """Signs of (bow_1, bow_2) on the image member that reflect the site's arc, or None."""
    es = model.elements[member.card]
    ends = {int(e): set(np.asarray(es.nodes)[np.asarray(es.eids) == e][0].tolist())
            for e in (*member.eids, *twin.eids)}
    signs = set()
    for eid in member.eids:                      # every element bows along its own axes
        match = [e for e in twin.eids if ends[e] == {image.get(g) for g in ends[eid]}]
        if not match:
            return None
        a, b = _element_axes(model, member, eid), _element_axes(model, twin, match[0])
        cos = np.array([(REFLECTION @ a[k]) @ b[k] for k in (1, 2)])
        if np.any(np.abs(cos) < AXIS_TOLERANCE):
            return None
        signs.add(tuple(float(v) for v in np.sign(cos)))
    return ((1.0, 1.0), signs.pop()) if len(signs) == 1 else None


def _pair(cand, twin, signs):
    """The pair candidate of a site and its image."""
    from pipeline.diagnose.effects import Location

    loc = Location(grids=cand.location.grids + twin.location.grids,
                   elements=cand.location.elements + twin.location.elements,
                   properties=cand.location.properties + twin.location.properties)
    image = twin.label                      # a bow's image is set by the signs, not its quadrant
    if cand.kind == "member_curvature":
        image = image[:image.rindex(" bow ")]
    label = f"{cand.label} and its mirror image {image}"
    return replace(cand, location=loc, label=label,
                   detail=cand.detail + (("sites", (cand, twin)), ("signs", signs)))
