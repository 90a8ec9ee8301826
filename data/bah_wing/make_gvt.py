"""Write the example's synthetic GVTs (``gvt.unv``, ``gvt_fuel.unv``) and print their measured mass.

The "aircraft" that was tested is a truth model richer than the analysis deck: the BAH wing with
its third and fourth bar segments 10 % stiffer in bending (PBAR 203/204 I1), the fourth 8 % softer
in torsion (PBAR 204 J) and the mid-wing masses 5 % heavier (CONM2 2 and 7). It was tested in two
configurations, the decks of ``case.toml``: ``baseline`` (``bah_plane.bdf``) and ``fuel``
(``bah_plane_fuel.bdf``: the same structure plus the 2,700 kg of ``fuel_bah.inc``, loaded as gauged,
so the truth fuel equals the deck's). In each, the truth model's elastic modes 3-8 are "measured" in
T1, T2, T3 at every grid (60 DOFs) with 1 % frequency noise and 3 % shape noise (of each mode's
largest entry, white, independent per DOF), damping 1.5 %. The noise has its own seed per
configuration: 56 for ``baseline`` (the draws of the original single-configuration script, so
``gvt.unv`` is unchanged byte for byte) and 57 for ``fuel``. The fuel brings the truth model's
W1FA (8.44 Hz) and W2B (8.54 Hz) within 1.2 % of each other but keeps their order, while the
analysis deck with fuel swaps them (W2B 8.36 Hz, W1FA 8.49 Hz): a test-analysis mode interchange
that the tuning's mode tracking has to follow. The truth model's weight and CG of each configuration are printed as the ``measured_mass`` lines of
``case.toml``. Run from the repository root: ``python data/bah_wing/make_gvt.py``.
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
SHARED = ("aero_bah.inc", "interface_bah.inc", "fuel_bah.inc")
# configuration -> (deck, GVT file, noise seed, names of the truth model's modes 3-8)
CONFIGURATIONS = {
    "baseline": ("bah_plane.bdf", "gvt.unv", 56, ["W1B", "W1T", "W1FA", "W2B", "W2T", "W3B"]),
    "fuel": ("bah_plane_fuel.bdf", "gvt_fuel.unv", 57, ["W1B", "W1T", "W1FA", "W2B", "W2T", "W3B"]),
}


def _scale_field(text: str, card: str, eid: int, field: int, factor: float) -> str:
    """Multiply free-field ``field`` (1-based after the card name) of card ``eid`` by ``factor``."""
    pattern = re.compile(rf"^({card},\s*{eid},.*)$", re.MULTILINE)
    line = pattern.search(text).group(1)
    parts = line.split(",")
    parts[field] = repr(float(parts[field]) * factor)
    return text.replace(line, ",".join(parts))


def truth_deck(folder: Path, deck: str) -> Path:
    """Copy the example deck ``deck`` into ``folder`` with the truth model's property changes."""
    for name in (deck, *SHARED):
        shutil.copy(HERE / name, folder / name)
    text = (HERE / "structure_bah.inc").read_text()
    text = _scale_field(text, "PBAR", 203, 4, 1.10)
    text = _scale_field(text, "PBAR", 204, 4, 1.10)
    text = _scale_field(text, "PBAR", 204, 6, 0.92)
    text = _scale_field(text, "CONM2", 2, 4, 1.05)
    text = _scale_field(text, "CONM2", 7, 4, 1.05)
    (folder / "structure_bah.inc").write_text(text)
    return folder / deck


def write_gvt(configuration: str) -> str:
    """Write the GVT file of ``configuration`` and return its ``measured_mass`` line."""
    deck, gvt_file, seed, names = CONFIGURATIONS[configuration]
    rng = np.random.default_rng(seed)
    with tempfile.TemporaryDirectory() as tmp:
        model = read_model(truth_deck(Path(tmp), deck))
        modes = compute_modes(model, 8).sel(mode=[3, 4, 5, 6, 7, 8])
        props = mass_properties(model)
    keep = np.flatnonzero(modes["component"].values <= 3)
    shape = modes["shape"].values[:, keep]
    shape = shape + 0.03 * rng.standard_normal(shape.shape) * np.abs(shape).max(axis=1, keepdims=True)
    freq = modes["frequency"].values * (1.0 + 0.01 * rng.standard_normal(len(modes["mode"])))
    gvt = make_gvt_dataset(freq, shape, modes["grid"].values[keep], modes["component"].values[keep],
                           damping=np.full(len(freq), 0.015), name=names,
                           xyz=np.column_stack([modes[c].values[keep] for c in ("x", "y", "z")]),
                           source="synthetic GVT of the BAH truth model (data/bah_wing/make_gvt.py)",
                           units="si")
    write_uff(gvt, HERE / gvt_file)
    return (f"measured_mass = {{ weight = {props.weight:.6g}, x_cg = {props.cg[0]:.6g}, "
            f"y_cg = {props.cg[1]:.6g} }}")


def main() -> None:
    for configuration in CONFIGURATIONS:
        print(f"{configuration}: {write_gvt(configuration)}")


if __name__ == "__main__":
    main()
