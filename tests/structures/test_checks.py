"""Model checks: coincident grids, free shell edges, unconnected grids (hand-built decks)."""
from __future__ import annotations

from pathlib import Path

import numpy as np

from structures.assembly import assemble
from structures.bdf import read_model
from structures.checks import coincident_grids, free_edges, model_checks, unconnected_grids

WING = Path(__file__).resolve().parents[1] / "data" / "practitioner_wing" / "wing.bdf"

# Two CQUAD4 sharing the edge 2-5 (2 x 1 strip), a CTRIA3 on 3-6-7, grid 8 on top of grid 3
# (1e-9 away: an un-equivalenced seam), grid 9 used by nothing, grid 10 only by a CONM2.
DECK = """GRID,1,,0.,0.,0.
GRID,2,,1.,0.,0.
GRID,3,,2.,0.,0.
GRID,4,,0.,1.,0.
GRID,5,,1.,1.,0.
GRID,6,,2.,1.,0.
GRID,7,,3.,0.5,0.
GRID,8,,2.,0.,1.-9
GRID,9,,5.,5.,0.
GRID,10,,4.,0.,0.
MAT1,1,7.e10,,0.3,2700.
PSHELL,1,1,0.002,1
CQUAD4,11,1,1,2,5,4
CQUAD4,12,1,2,3,6,5
CTRIA3,13,1,8,7,6
CONM2,20,10,,1.
"""


def _model(tmp_path):
    path = tmp_path / "c.bdf"
    path.write_text(DECK)
    return read_model(path)


def test_coincident_pair_named_with_its_distance(tmp_path):
    model = _model(tmp_path)
    pairs, dist, tol = coincident_grids(model.grids)
    size = np.linalg.norm([5.0, 5.0, 1e-9])            # bounding-box diagonal
    assert tol == 1e-5 * size
    np.testing.assert_array_equal(pairs, [[3, 8]])
    np.testing.assert_allclose(dist, [1e-9], rtol=1e-6)
    assert len(coincident_grids(model.grids, rel_tol=1e-12)[0]) == 0


def test_free_edges_by_hand(tmp_path):
    # Quads 11, 12: 8 edges, 2-5 shared -> 6 free; the triangle 8-7-6 adds 3 (its 6-8 edge is not
    # the quad's 3-6 edge because 8 is a separate, coincident grid).
    edges, owners = free_edges(_model(tmp_path))
    expected = {(1, 2): 11, (1, 4): 11, (4, 5): 11, (2, 3): 12, (3, 6): 12, (5, 6): 12,
                (7, 8): 13, (6, 7): 13, (6, 8): 13}
    assert dict(zip(map(tuple, edges.tolist()), owners.tolist())) == expected


def test_unconnected_grids(tmp_path):
    np.testing.assert_array_equal(unconnected_grids(_model(tmp_path)), [9])


def test_model_checks_report(tmp_path):
    model = _model(tmp_path)
    system = assemble(model, warn=False)
    checks = model_checks(model, system.singularities)
    text = checks.format()
    assert "coincident grids" in text and "3 - 8" in text
    assert "free shell edges: 9" in text and "grids not connected to any element: 1" in text
    # grid 9 has no stiffness at all, grid 10 only a mass: all 6 directions of each are singular
    table = checks.singularities
    for gid in (9, 10):
        assert sorted(table.component[table.grid == gid]) == [1, 2, 3, 4, 5, 6]


def test_practitioner_wing_checks():
    """The wing box is closed (skin edges meet the spar and rib webs: no free edge); each rib's
    reference-axis grid sits on the rib's mid-height grid without being equivalenced."""
    model = read_model(WING)
    checks = model_checks(model)
    assert len(checks.free_edges) == 0 and len(checks.unconnected) == 0
    assert checks.coincident.tolist() == [[3000 + 20 * k + 2, 9000 + 2 * k] for k in range(11)]
