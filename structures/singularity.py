"""Grid point singularity processing (Nastran's GPSP / AUTOSPC) on the n-set stiffness.

Nastran checks every grid's stiffness for singular directions before it removes the SPCs (MSC
Nastran Linear Static Analysis User's Guide, "Grid Point Singularity Processing"; Quick Reference
Guide, PARAM AUTOSPC, EPZERO, EPPRT):

* at each grid, the 3x3 diagonal block of the translations (T1-T3) and the one of the rotations
  (R1-R3) of K_nn (after rigid-element elimination, in the grid's displacement frame) are
  eigen-decomposed;
* the STIFFNESS RATIO of a principal direction is its eigenvalue divided by the largest eigenvalue of
  the same block (so a film skin whose out-of-plane stiffness is 1e-10 of its membrane stiffness is
  singular at its own grids, whatever the rest of the model);
* a direction whose ratio is below PARAM EPZERO (default 1e-8) is singular and is listed in the GRID
  POINT SINGULARITY TABLE, with the component it is closest to as the FAILED DIRECTION;
* with PARAM AUTOSPC YES (the default in current MSC Nastran for the linear solution sequences,
  SOL 103 included) the failed component is constrained by an automatic SPC; PARAM AUTOSPC NO
  leaves it in the analysis set;
* components already in the m-set (dependent in a rigid element) or the s-set (SPC, GRID PS) take
  no part in the check.

Choice of the failed component: the singular eigenvectors of a block are taken in increasing order
of ratio, and each picks the not yet chosen component with the largest share of it. A direction
whose largest share is at least :data:`ALIGNED` (a cosine) is aligned with that component; otherwise
it is oblique and the most aligned component is still the one constrained (flagged ``oblique`` in
the table, as the F06 prints the nearest component for it).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import xarray as xr

from structures.common.errors import InputError

#: Nastran's PARAM EPZERO default: stiffness ratios below it are singular.
EPZERO_DEFAULT = 1.0e-8
#: Cosine above which a singular direction counts as aligned with a component.
ALIGNED = 0.99
#: Rows of the table printed in the summary warning.
WARN_ROWS = 20


class SingularityWarning(UserWarning):
    """The model has singular grid point directions (listed like Nastran's F06 table)."""


@dataclass(frozen=True)
class SingularityTable:
    """The GRID POINT SINGULARITY TABLE: one row per singular direction.

    Attributes
    ----------
    grid : (ns,) int grid ids.
    component : (ns,) int failed component 1..6 (grid displacement frame).
    ratio : (ns,) float stiffness ratio (eigenvalue / largest eigenvalue of the 3x3 block).
    action : (ns,) str ``"autospc"`` (constrained) or ``"left"`` (kept, PARAM AUTOSPC NO).
    oblique : (ns,) bool, the singular direction is not aligned with the component.
    dof : (ns,) int g-set DOF numbers (grid index * 6 + component - 1).
    epzero : float, the threshold used.
    """

    grid: np.ndarray
    component: np.ndarray
    ratio: np.ndarray
    action: np.ndarray
    oblique: np.ndarray
    dof: np.ndarray
    epzero: float = EPZERO_DEFAULT

    def __post_init__(self):
        for name, dtype in (("grid", np.int64), ("component", np.int64), ("ratio", float),
                            ("action", "<U7"), ("oblique", bool), ("dof", np.int64)):
            arr = np.array(getattr(self, name), dtype=dtype).reshape(-1)
            arr.setflags(write=False)
            object.__setattr__(self, name, arr)
        if len({len(getattr(self, n)) for n in ("grid", "component", "ratio", "action", "oblique",
                                                  "dof")}) != 1:
            raise InputError("SingularityTable columns have different lengths. Fix: give one "
                             "entry per singular direction in every column.")

    def __len__(self) -> int:
        return len(self.grid)

    @property
    def constrained(self) -> np.ndarray:
        """g-set DOFs removed by AUTOSPC, sorted."""
        return np.sort(self.dof[self.action == "autospc"])

    def to_dataset(self) -> xr.Dataset:
        """The table as a Dataset on dimension ``singularity``."""
        return xr.Dataset(
            {"grid": ("singularity", self.grid), "component": ("singularity", self.component),
             "ratio": ("singularity", self.ratio), "action": ("singularity", self.action),
             "oblique": ("singularity", self.oblique)},
            attrs={"epzero": self.epzero, "ratio_units": "1 (eigenvalue / largest of the block)"})

    def format(self, max_rows: int | None = WARN_ROWS) -> str:
        """Text like the F06's GRID POINT SINGULARITY TABLE (first ``max_rows`` rows + count)."""
        lines = ["G R I D   P O I N T   S I N G U L A R I T Y   T A B L E",
                 f"{'POINT ID':>10} {'FAILED DIRECTION':>17} {'STIFFNESS RATIO':>16} {'ACTION':>8}"]
        shown = len(self) if max_rows is None else min(len(self), max_rows)
        for i in range(shown):
            mark = " (oblique)" if self.oblique[i] else ""
            lines.append(f"{self.grid[i]:>10d} {self.component[i]:>17d} {self.ratio[i]:>16.2E} "
                         f"{self.action[i]:>8}{mark}")
        if shown < len(self):
            lines.append(f"... {len(self) - shown} more rows")
        n_spc = int(np.sum(self.action == "autospc"))
        lines.append(f"{len(self)} singular directions at {len(np.unique(self.grid))} grids "
                     f"(EPZERO = {self.epzero:.1E}); {n_spc} constrained by AUTOSPC, "
                     f"{len(self) - n_spc} left.")
        return "\n".join(lines)


def _blocks(k_nn: sp.spmatrix, pos: np.ndarray) -> np.ndarray:
    """(ng, 3, 3) diagonal blocks of ``k_nn`` at positions ``pos`` (ng, 3); -1 gives zeros."""
    ng = len(pos)
    rows = np.broadcast_to(pos[:, :, None], (ng, 3, 3))
    cols = np.broadcast_to(pos[:, None, :], (ng, 3, 3))
    valid = (rows >= 0) & (cols >= 0)
    out = np.zeros((ng, 3, 3))
    if np.any(valid):
        out[valid] = np.asarray(k_nn.tocsr()[rows[valid], cols[valid]]).ravel()
    return out


def block_singularities(blocks: np.ndarray, active: np.ndarray, epzero: float = EPZERO_DEFAULT,
                        floor: float = 0.0):
    """Singular directions of 3x3 stiffness blocks, vectorised over grids.

    Parameters
    ----------
    blocks : (ng, 3, 3) symmetric stiffness blocks (translations or rotations of each grid).
    active : (ng, 3) bool, components taking part (not in the m-set or s-set).
    epzero : float, ratio threshold (PARAM EPZERO).
    floor : float, eigenvalues at or below it are zero stiffness (round-off of a model whose
        largest stiffness is ~1e12 times larger), so a block of round-off is wholly singular.

    Returns
    -------
    block : (ns,) int index of the block (grid) of each singular direction.
    component : (ns,) int failed component 0..2 within the block.
    ratio : (ns,) float stiffness ratio.
    oblique : (ns,) bool.
    """
    out = ([], [], [], [])
    for mask in np.unique(active, axis=0):
        free = np.flatnonzero(mask)
        sel = np.flatnonzero(np.all(active == mask, axis=1))
        if free.size == 0 or sel.size == 0:
            continue
        sub = blocks[sel][:, free][:, :, free]
        lam, vec = np.linalg.eigh(sub)                       # ascending eigenvalues per block
        lam = np.where(lam <= floor, 0.0, lam)
        top = lam[:, -1:]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(top > 0, np.clip(lam, 0.0, None) / top, 0.0)
        taken = np.zeros((len(sel), free.size), dtype=bool)
        for j in range(free.size):
            singular = ratio[:, j] < epzero
            share = np.where(taken, -1.0, np.abs(vec[:, :, j]))
            pick = np.argmax(share, axis=1)
            taken[np.arange(len(sel))[singular], pick[singular]] = True
            out[0].append(sel[singular])
            out[1].append(free[pick[singular]])
            out[2].append(ratio[singular, j])
            out[3].append(share[np.arange(len(sel)), pick][singular] < ALIGNED)
    if not out[0]:
        return (np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0), np.zeros(0, bool))
    return tuple(np.concatenate(part) for part in out)


def grid_point_singularities(k_nn: sp.spmatrix, n_dofs: np.ndarray, excluded: np.ndarray,
                             grid_ids: np.ndarray, *, epzero: float = EPZERO_DEFAULT,
                             autospc: bool = True, floor=(0.0, 0.0)) -> SingularityTable:
    """Nastran's grid point singularity processing of the n-set stiffness.

    Parameters
    ----------
    k_nn : sparse (nn, nn) stiffness after rigid-element elimination, displacement frames.
    n_dofs : (nn,) int g-set DOF numbers of the n-set rows.
    excluded : (nn,) bool, n-set DOFs already constrained (SPC, GRID PS): not checked.
    grid_ids : (ngrid,) int ids of the grids (g-set DOF d belongs to grid_ids[d // 6]).
    epzero : float, PARAM EPZERO.
    autospc : bool, PARAM AUTOSPC (True: constrain the singular components).
    floor : (2,) float, zero-stiffness floors of the translational and rotational blocks
        (see :func:`block_singularities`).

    Returns
    -------
    SingularityTable, sorted by grid then component.
    """
    n_grid = len(grid_ids)
    pos = np.full(6 * n_grid, -1, dtype=np.int64)
    pos[n_dofs] = np.arange(len(n_dofs))
    pos = pos.reshape(n_grid, 6)
    active = pos >= 0
    active[active] = ~np.asarray(excluded, bool)[pos[active]]
    grids, comps, ratios, oblique = [], [], [], []
    for first, zero in zip((0, 3), floor):
        cols = slice(first, first + 3)
        touched = np.flatnonzero(np.any(active[:, cols], axis=1))
        blocks = _blocks(k_nn, np.where(active[touched, cols], pos[touched, cols], -1))
        b, c, r, o = block_singularities(blocks, active[touched, cols], epzero, zero)
        grids.append(touched[b])
        comps.append(c + first)
        ratios.append(r)
        oblique.append(o)
    gidx, comp = np.concatenate(grids), np.concatenate(comps)
    order = np.lexsort((comp, grid_ids[gidx]))
    gidx, comp = gidx[order], comp[order]
    return SingularityTable(grid=grid_ids[gidx], component=comp + 1,
                            ratio=np.concatenate(ratios)[order],
                            action=np.full(len(gidx), "autospc" if autospc else "left"),
                            oblique=np.concatenate(oblique)[order], dof=6 * gidx + comp,
                            epzero=epzero)


def warn_singularities(table: SingularityTable, filename: str = "") -> None:
    """Issue one :class:`SingularityWarning` printing the table (first rows and the count)."""
    if len(table) == 0:
        return
    where = f"file {filename}: " if filename else ""
    warnings.warn(f"{where}grid point singularities (Nastran GPSP):\n{table.format()}\nFix: "
                  "nothing when these are film, drilling or unconnected directions; otherwise add "
                  "the missing stiffness (PARAM AUTOSPC NO keeps them in the analysis).",
                  SingularityWarning, stacklevel=3)
