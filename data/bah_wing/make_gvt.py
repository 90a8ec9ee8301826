"""Write the example's synthetic GVT (``gvt.unv``) and print its measured mass properties.

The "aircraft" that was tested is a truth model richer than the analysis deck: the BAH wing with
its third and fourth bar segments 10 % stiffer in bending (PBAR 203/204 I1), the fourth 8 % softer
in torsion (PBAR 204 J) and the mid-wing masses 5 % heavier (CONM2 2 and 7). Its elastic modes 3-8
are "measured" in T1, T2, T3 at every grid (60 DOFs) with 1 % frequency and 3 % shape noise
(seed 56), damping 1.5 %. The truth model's weight and CG are printed as the ``measured_mass``
line of ``case.toml``. Run from the repository root: ``python data/bah_wing/make_gvt.py``.
"""
from __future__ import annotations

import re
import shutil
import tempfile
from pathlib import Path

import numpy as np

from structures.bdf import read_model
from structures.gvt import make_gvt_dataset, write_uff
from structures.massprops import mass_properties
from structures.modal import compute_modes

HERE = Path(__file__).resolve().parent
NAMES = ["W1B", "W1T", "W1FA", "W2B", "W2T", "W3B"]


def _scale_field(text: str, card: str, eid: int, field: int, factor: float) -> str:
    """Multiply free-field ``field`` (1-based after the card name) of card ``eid`` by ``factor``."""
    pattern = re.compile(rf"^({card},\s*{eid},.*)$", re.MULTILINE)
    line = pattern.search(text).group(1)
    parts = line.split(",")
    parts[field] = repr(float(parts[field]) * factor)
    return text.replace(line, ",".join(parts))


def truth_deck(folder: Path) -> Path:
    """Copy the example deck into ``folder`` with the truth model's property changes."""
    for name in ("bah_plane.bdf", "aero_bah.inc", "interface_bah.inc"):
        shutil.copy(HERE / name, folder / name)
    text = (HERE / "structure_bah.inc").read_text()
    text = _scale_field(text, "PBAR", 203, 4, 1.10)
    text = _scale_field(text, "PBAR", 204, 4, 1.10)
    text = _scale_field(text, "PBAR", 204, 6, 0.92)
    text = _scale_field(text, "CONM2", 2, 4, 1.05)
    text = _scale_field(text, "CONM2", 7, 4, 1.05)
    (folder / "structure_bah.inc").write_text(text)
    return folder / "bah_plane.bdf"


def main() -> None:
    rng = np.random.default_rng(56)
    with tempfile.TemporaryDirectory() as tmp:
        model = read_model(truth_deck(Path(tmp)))
        modes = compute_modes(model, 8).sel(mode=[3, 4, 5, 6, 7, 8])
        props = mass_properties(model)
    keep = np.flatnonzero(modes["component"].values <= 3)
    shape = modes["shape"].values[:, keep]
    shape = shape + 0.03 * rng.standard_normal(shape.shape) * np.abs(shape).max(axis=1, keepdims=True)
    freq = modes["frequency"].values * (1.0 + 0.01 * rng.standard_normal(len(modes["mode"])))
    gvt = make_gvt_dataset(freq, shape, modes["grid"].values[keep], modes["component"].values[keep],
                           damping=np.full(len(freq), 0.015), name=NAMES,
                           xyz=np.column_stack([modes[c].values[keep] for c in ("x", "y", "z")]),
                           source="synthetic GVT of the BAH truth model (data/bah_wing/make_gvt.py)",
                           units="si")
    write_uff(gvt, HERE / "gvt.unv")
    print(f"measured_mass = {{ weight = {props.weight:.6g}, x_cg = {props.cg[0]:.6g}, "
          f"y_cg = {props.cg[1]:.6g} }}")


if __name__ == "__main__":
    main()
