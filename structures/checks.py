"""Model checks to run before an analysis: coincident grids, free shell edges, unconnected grids.

These are the pre-processor checks a practitioner runs on a deck (an equivalence check, a free-edge
plot, a search for loose grids) before trusting its modes; with the grid point singularity table of
:mod:`structures.singularity` they explain most mechanisms. All functions are pure and vectorised.

* Coincident grids: pairs closer than ``rel_tol`` times the model size (the diagonal of the bounding
  box of all grids), found with a k-d tree; both ids are named (an un-equivalenced mesh seam shows
  as a line of such pairs).
* Free edges: edges of CQUAD4/CTRIA3 used by exactly one shell element (a seam that is not joined
  shows as free edges inside a surface).
* Unconnected grids: grids no element (stiffness, mass or rigid) refers to.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from structures.model import FEModel, Grids
from structures.singularity import SingularityTable

#: Default coincidence tolerance, relative to the model size.
COINCIDENT_REL_TOL = 1.0e-5
_SHELLS = ("CQUAD4", "CTRIA3")


@dataclass(frozen=True)
class ModelChecks:
    """Results of :func:`model_checks`.

    Attributes
    ----------
    coincident : (npair, 2) int grid ids of coincident pairs (smaller id first).
    coincident_distance : (npair,) float distance of each pair.
    tolerance : float, absolute coincidence tolerance used.
    free_edges : (nedge, 2) int grid ids of each free shell edge (smaller id first).
    free_edge_elements : (nedge,) int id of the one shell element using each free edge.
    unconnected : (nu,) int ids of grids no element refers to.
    singularities : SingularityTable or None.
    """

    coincident: np.ndarray
    coincident_distance: np.ndarray
    tolerance: float
    free_edges: np.ndarray
    free_edge_elements: np.ndarray
    unconnected: np.ndarray
    singularities: SingularityTable | None = None

    def format(self, max_rows: int = 20) -> str:
        """A plain-text report (first ``max_rows`` entries of each list and the counts)."""
        def more(n):
            return [f"  ... {n - max_rows} more"] if n > max_rows else []
        lines = [f"coincident grids (closer than {self.tolerance:.3g}): {len(self.coincident)} "
                 "pairs"]
        lines += [f"  {a} - {b}  distance {d:.3g}" for (a, b), d in
                  zip(self.coincident[:max_rows], self.coincident_distance[:max_rows])]
        lines += more(len(self.coincident))
        lines.append(f"free shell edges: {len(self.free_edges)}")
        lines += [f"  grids {a} - {b}  (element {e})" for (a, b), e in
                  zip(self.free_edges[:max_rows], self.free_edge_elements[:max_rows])]
        lines += more(len(self.free_edges))
        lines.append(f"grids not connected to any element: {len(self.unconnected)}")
        if len(self.unconnected):
            lines.append("  " + " ".join(map(str, self.unconnected[:max_rows])))
            lines += more(len(self.unconnected))
        if self.singularities is not None:
            lines.append(self.singularities.format(max_rows))
        return "\n".join(lines)


def coincident_grids(grids: Grids, rel_tol: float = COINCIDENT_REL_TOL):
    """Pairs of grids closer than ``rel_tol`` times the model size.

    Parameters
    ----------
    grids : Grids
    rel_tol : float, tolerance relative to the bounding-box diagonal of all grids.

    Returns
    -------
    pairs : (npair, 2) int grid ids, sorted.
    distance : (npair,) float.
    tol : float, absolute tolerance.
    """
    xyz = np.asarray(grids.xyz, float)
    size = float(np.linalg.norm(np.ptp(xyz, axis=0))) if len(xyz) else 0.0
    tol = rel_tol * size
    if len(xyz) < 2:
        return np.zeros((0, 2), np.int64), np.zeros(0), tol
    idx = cKDTree(xyz).query_pairs(tol, output_type="ndarray")
    ids = np.sort(grids.ids[idx], axis=1).reshape(-1, 2)
    dist = np.linalg.norm(xyz[idx[:, 0]] - xyz[idx[:, 1]], axis=1) if len(idx) else np.zeros(0)
    order = np.lexsort((ids[:, 1], ids[:, 0]))
    return ids[order], dist[order], tol


def free_edges(model: FEModel):
    """Edges of CQUAD4/CTRIA3 used by one shell element only.

    Returns
    -------
    edges : (nedge, 2) int grid ids (smaller first), sorted.
    elements : (nedge,) int the element using each edge.
    """
    edges, owners = [], []
    for kind in _SHELLS:
        es = model.elements.get(kind)
        if es is None:
            continue
        nodes = np.asarray(es.nodes)
        nn = nodes.shape[1]
        pairs = np.stack([nodes, np.roll(nodes, -1, axis=1)], axis=2).reshape(-1, 2)
        edges.append(np.sort(pairs, axis=1))
        owners.append(np.repeat(es.eids, nn))
    if not edges:
        return np.zeros((0, 2), np.int64), np.zeros(0, np.int64)
    edges, owners = np.concatenate(edges), np.concatenate(owners)
    unique, first, counts = np.unique(edges, axis=0, return_index=True, return_counts=True)
    single = counts == 1
    return unique[single], owners[first[single]]


def unconnected_grids(model: FEModel) -> np.ndarray:
    """Ids of grids that no element, CONM2 or rigid element refers to, sorted. Shape (nu,)."""
    used = [np.asarray(es.nodes).ravel() for es in model.elements.values()]
    used.append(np.asarray(model.masses.grid))
    for elem in model.rigid:
        used.append(np.array([g for g, _ in (*elem.independent, *elem.dependent)], np.int64))
    used = np.concatenate(used) if used else np.zeros(0, np.int64)
    return np.setdiff1d(model.grids.ids, used)


def model_checks(model: FEModel, singularities: SingularityTable | None = None,
                 rel_tol: float = COINCIDENT_REL_TOL) -> ModelChecks:
    """All pre-analysis checks of a model.

    Parameters
    ----------
    model : FEModel
    singularities : SingularityTable, optional, from :func:`structures.assembly.assemble`.
    rel_tol : float, coincidence tolerance relative to the model size.

    Returns
    -------
    ModelChecks
    """
    pairs, dist, tol = coincident_grids(model.grids, rel_tol)
    edges, owners = free_edges(model)
    return ModelChecks(coincident=pairs, coincident_distance=dist, tolerance=tol,
                       free_edges=edges, free_edge_elements=owners,
                       unconnected=unconnected_grids(model), singularities=singularities)
