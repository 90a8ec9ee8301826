"""Picture of the X-56A-class model: beams, rigid elements and masses over the aero boxes.

``python data/x56_like/plot_model.py [DECK] [PNG]`` (defaults: ``x56_fffw.bdf``, ``model.png``
beside this script). Plan view (x aft, y starboard) and a view from behind (y, z).
"""
from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parents[1]))

from structures.common.nastran import read_pynastran  # noqa: E402


def plot_model(deck) -> plt.Figure:
    """Figure of the deck's CAERO1 boxes, CBARs, RBE2s and CONM2s (marker area ~ weight).

    Parameters
    ----------
    deck : path of a Nastran deck with CAERO1, CBAR, RBE2 and CONM2 cards.

    Returns
    -------
    matplotlib.figure.Figure with two axes: plan view (x, y) and rear view (y, z).
    """
    bdf = read_pynastran(deck)
    xyz = {gid: node.get_position() for gid, node in bdf.nodes.items()}
    fig, (plan, rear) = plt.subplots(2, 1, figsize=(10, 9), height_ratios=[3, 1])
    for caero in bdf.caeros.values():
        points, elements = caero.panel_points_elements()
        for quad in elements:
            p = points[np.r_[quad, quad[0]]]
            plan.plot(p[:, 1], p[:, 0], color="0.8", lw=0.3)
            rear.plot(p[:, 1], p[:, 2], color="0.8", lw=0.3)
    for elem in bdf.elements.values():
        if elem.type == "CBAR":
            a, b = (xyz[g] for g in elem.node_ids)
            for ax, (i, j) in ((plan, (1, 0)), (rear, (1, 2))):
                ax.plot([a[i], b[i]], [a[j], b[j]], color="tab:blue", lw=1.5)
    for rigid in bdf.rigid_elements.values():
        a = xyz[rigid.gn]
        for g in rigid.Gmi:
            b = xyz[g]
            for ax, (i, j) in ((plan, (1, 0)), (rear, (1, 2))):
                ax.plot([a[i], b[i]], [a[j], b[j]], color="tab:red", lw=0.8)
    masses = [m for m in bdf.masses.values() if m.type == "CONM2"]
    pos = np.array([xyz[m.nid] + np.asarray(m.X, dtype=float) for m in masses])
    size = np.array([m.mass for m in masses]) * 6.0
    plan.scatter(pos[:, 1], pos[:, 0], s=size, color="tab:orange", zorder=3, label="CONM2 (area ~ lb)")
    rear.scatter(pos[:, 1], pos[:, 2], s=size, color="tab:orange", zorder=3)
    plan.invert_yaxis()
    plan.set(xlabel="y [in]", ylabel="x [in] (aft)", aspect="equal",
             title=f"{Path(deck).name}: {sum(len(c.panel_points_elements()[1]) for c in bdf.caeros.values())} DLM boxes, "
                   "beams (blue), RBE2 (red), CONM2 (orange)")
    rear.set(xlabel="y [in]", ylabel="z [in]", aspect="equal")
    plan.legend(loc="lower right")
    fig.tight_layout()
    return fig


if __name__ == "__main__":
    args = sys.argv[1:]
    deck = Path(args[0]) if args else HERE / "x56_fffw.bdf"
    out = Path(args[1]) if len(args) > 1 else HERE / "model.png"
    plot_model(deck).savefig(out, dpi=110, metadata={"Software": None})
    print(f"wrote {out}")
