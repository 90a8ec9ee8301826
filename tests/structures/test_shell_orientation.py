"""Shell material orientation: THETA and an equivalent MCID give the same orthotropic plate."""
from __future__ import annotations

import numpy as np
import pytest

from structures.bdf import read_model
from structures.common.errors import MissingReferenceError
from structures.modal import compute_modes


def _plate(path, orientation: str, n: int = 8):
    lines = ["MAT8,1,1.4e11,1.0e10,0.3,5.0e9,5.0e9,3.0e9,1600.", "PSHELL,1,1,0.004,1,,1",
             "CORD2R,5,,0.,0.,0.,0.,0.,1.\n,0.8660254037844387,0.5,0.",
             "SPC1,1,123456," + ",".join(str(j * (n + 1) + 1) for j in range(n + 1))]
    for j in range(n + 1):
        for i in range(n + 1):
            lines.append(f"GRID,{j * (n + 1) + i + 1},,{0.5 * i / n!r},{0.4 * j / n!r},0.")
    for j in range(n):
        for i in range(n):
            g1 = j * (n + 1) + i + 1
            lines.append(f"CQUAD4,{j * n + i + 1},1,{g1},{g1 + 1},{g1 + n + 2},{g1 + n + 1},"
                         f"{orientation}")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_mcid_equals_theta(tmp_path):
    """CORD2R 5 has its x axis at 30 degrees from basic x: MCID=5 is THETA=30 on this plate."""
    theta = compute_modes(read_model(_plate(tmp_path / "t.bdf", "30.")), 5)["frequency"].values
    mcid = compute_modes(read_model(_plate(tmp_path / "m.bdf", "5")), 5)["frequency"].values
    zero = compute_modes(read_model(_plate(tmp_path / "z.bdf", "0.")), 5)["frequency"].values
    np.testing.assert_allclose(mcid, theta, rtol=1e-10)
    assert np.max(np.abs(theta / zero - 1)) > 0.01  # the fibre angle matters on this plate


def test_undefined_mcid_raises(tmp_path):
    with pytest.raises(MissingReferenceError, match="MCID=7"):
        read_model(_plate(tmp_path / "bad.bdf", "7"))
