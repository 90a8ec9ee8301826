"""Benchmark: how ``pipeline.diagnose.diagnose`` scales with the model's size.

Cantilever CQUAD4 plates (``tests/structures/plate_decks.py``, 1 x 0.6 m, 5 mm aluminium, clamped
at x = 0) of growing mesh, each with a hidden CONM2 of 4 % of its mass at the grid nearest
(0.75, 0.45) m; the GVT: the truth's 12 lowest modes (our solver) at up to 120 z DOFs spread
over the free grids, 1 % frequency and 5 % shape noise; no weighing; one round
(``max_effects = 1``). Prints, per mesh, ``key=value`` lines: grids, wall time and CPU time of
the diagnosis, peak resident memory of the process so far, the verdict and whether the named grid
is the hidden mass's.

Run ``python benchmarks/diagnose.py [NX,NY ...]`` from the repository root (default 10,6 20,12
40,24); pin it to one core (``taskset -c 0``) for figures that compare.
"""
from __future__ import annotations

import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "structures"))

from plate_decks import plate_deck  # noqa: E402
from pipeline.diagnose import ConfigurationData, DiagnoseSettings, diagnose  # noqa: E402
from structures.bdf import read_model  # noqa: E402
from structures.gvt import make_gvt_dataset  # noqa: E402
from structures.massprops import mass_properties  # noqa: E402
from structures.modal import compute_modes  # noqa: E402

N_TEST, N_DOF, MASS_SHARE, SITE = 12, 120, 0.04, (0.75, 0.45)


def case(folder: Path, nx: int, ny: int):
    """(ConfigurationData of the plate against its hidden-mass truth's GVT, hidden grid)."""
    deck = plate_deck(folder / "plate.bdf", nx=nx, ny=ny, boundary="cantilever", nmodes=30)
    model = read_model(deck)
    xyz, ids = model.grids.xyz, model.grids.ids
    site = int(ids[np.argmin(np.hypot(xyz[:, 0] - SITE[0], xyz[:, 1] - SITE[1]))])
    mass = MASS_SHARE * mass_properties(model).mass
    truth = folder / "truth.bdf"
    truth.write_text(deck.read_text().replace(
        "ENDDATA", f"CONM2   99999   {site:<8d}        {mass:<8.4f}\nENDDATA"))
    modes = compute_modes(read_model(truth), N_TEST)
    free = ids[xyz[:, 0] > 1e-9]
    sensors = np.unique(free[np.linspace(0, free.size - 1, min(N_DOF, free.size)).round()
                             .astype(int)])
    key = {(int(g), int(c)): j for j, (g, c) in
           enumerate(zip(modes["grid"].values, modes["component"].values))}
    shape = modes["shape"].values[:N_TEST, [key[(int(g), 3)] for g in sensors]]
    rng = np.random.default_rng(0)
    f = modes["frequency"].values[:N_TEST] * (1.0 + 0.01 * rng.standard_normal(N_TEST))
    shape = shape + 0.05 * np.sqrt(np.mean(shape ** 2, axis=1, keepdims=True)) * \
        rng.standard_normal(shape.shape)
    gvt = make_gvt_dataset(f, shape, sensors, np.full(sensors.size, 3),
                           mode=np.arange(1, N_TEST + 1), source="plate truth", units="si")
    return ConfigurationData(name="plate", model=model, gvt=gvt, measured_mass=None,
                             deck=deck), site


def main(meshes) -> None:
    for nx, ny in meshes:
        with tempfile.TemporaryDirectory() as tmp:
            data, site = case(Path(tmp), nx, ny)
            wall, cpu = time.perf_counter(), time.process_time()
            result = diagnose([data], DiagnoseSettings(max_effects=1))
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        named = result.effects[0].candidate.location.grids if result.effects else ()
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        print(f"mesh={nx}x{ny} grids={len(data.model.grids.ids)} wall_s={wall:.1f} "
              f"cpu_s={cpu:.1f} peak_rss_mb={rss:.0f} verdict={result.verdict} "
              f"named_hidden_grid={site in named}", flush=True)


if __name__ == "__main__":
    args = sys.argv[1:] or ["10,6", "20,12", "40,24"]
    main([tuple(int(v) for v in a.split(",")) for a in args])
