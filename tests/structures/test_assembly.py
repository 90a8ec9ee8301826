"""Sparse assembly (structures.assembly): the scattered K_gg, M_gg against a dense sum of the
element matrices, element by element (an independent, plain-loop reference)."""
from __future__ import annotations

import numpy as np
import pytest

from structures.assembly import assemble_g, element_matrices
from structures.bdf import read_model
from structures.bulk_text import card
from tests.structures.plate_decks import plate_deck

#: A rotation taking the plate out of the basic XY plane, so that no stiffness term vanishes by
#: symmetry of the orientation.
TILT = np.array([[0.8, 0.0, -0.6], [0.36, 0.8, 0.48], [0.48, -0.6, 0.64]])


def dense_sum(model, mass: str) -> tuple[np.ndarray, np.ndarray]:
    """K_gg, M_gg (basic axes) summed element by element into dense arrays."""
    n = 6 * len(model.grids)
    k_sum, m_sum = np.zeros((n, n)), np.zeros((n, n))
    for gi, k, m in element_matrices(model, mass):
        for e in range(len(gi)):
            dofs = (6 * gi[e][:, None] + np.arange(6)).ravel()
            if k is not None:
                k_sum[np.ix_(dofs, dofs)] += k[e]
            if m is not None:
                m_sum[np.ix_(dofs, dofs)] += m[e]
    return k_sum, m_sum * model.wtmass


def two_thickness_deck(path):
    """The tilted plate deck with every other CQUAD4 on a second, thicker PSHELL."""
    plate_deck(path, nx=4, ny=3, rotation=TILT)
    lines = path.read_text().splitlines()
    out = []
    for line in lines:
        if line.startswith("CQUAD4") and int(line[8:16]) % 2 == 0:
            line = line[:16] + f"{2:<8d}" + line[24:]
        out.append(line)
        if line.startswith("PSHELL"):
            out.append(card("PSHELL", 2, 1, 0.008, 1, None, 1))
    path.write_text("\n".join(out) + "\n")
    return path


@pytest.mark.parametrize("mass", ["lumped", "consistent"])
@pytest.mark.parametrize("deck", ["quad", "tria", "two_thicknesses"])
def test_scatter_equals_dense_element_sum(tmp_path, deck, mass):
    path = tmp_path / "plate.bdf"
    if deck == "two_thicknesses":
        two_thickness_deck(path)
    else:
        plate_deck(path, nx=4, ny=3, rotation=TILT, element="CQUAD4" if deck == "quad" else "CTRIA3")
    model = read_model(path)
    if deck == "two_thicknesses":
        assert set(model.elements["CQUAD4"].pids) == {1, 2}
    k_ref, m_ref = dense_sum(model, mass)
    k, m = assemble_g(model, mass)
    np.testing.assert_allclose(k.toarray(), k_ref, rtol=0, atol=1e-13 * np.abs(k_ref).max())
    np.testing.assert_allclose(m.toarray(), m_ref, rtol=0, atol=1e-13 * np.abs(m_ref).max())
    assert np.all(k.data != 0) and np.all(m.data != 0)      # no stored zeros
