"""Speed and memory of the Q_hh pipeline on the BAH wing (aero.gaf.generalized_aero_forces).

tests/data/bah_plane/bah_plane_qhh.bdf: 228 boxes (wing 200 + tail 28, SYMXZ half model), two
SPLINE2 beam splines, 8 modes from structures.modal, all 2 Mach x 15 k of its MKAERO1 cards.
Steps timed separately: reading the aero model, the splines (G_kg), and Q for each kernel.
Each kernel runs in a fresh subprocess whose ru_maxrss is reported as ``peak_rss_mb`` (the
whole Python process). The machine is shared: wall and CPU seconds are both printed.

Run from the repository root:  PYTHONPATH=. python benchmarks/aero_gaf.py
Prints ``key: value`` lines.
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time
import warnings
from pathlib import Path

DECK = Path(__file__).resolve().parents[1] / "tests" / "data" / "bah_plane" / "bah_plane_qhh.bdf"


def run_case(method: str) -> dict:
    """Time one kernel in this process and return the figures."""
    from aero.gaf import generalized_aero_forces, spline_matrices
    from aero.model import read_aero_model
    from structures.bdf import read_model
    from structures.modal import compute_modes

    out = {}
    t0 = time.perf_counter()
    am = read_aero_model(DECK)
    out["read_aero_model_seconds"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    spline_matrices(am)
    out["spline_matrices_seconds"] = time.perf_counter() - t0
    modes = compute_modes(read_model(DECK), 8)
    t0, c0 = time.perf_counter(), time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        generalized_aero_forces(am, modes, am.machs, am.ks, method=method)
    out["gaf_seconds"] = time.perf_counter() - t0
    out["gaf_cpu_seconds"] = time.process_time() - c0
    out["n_mach_k"] = int(am.machs.size * am.ks.size)
    out["n_boxes"] = int(am.mesh.n)
    out["peak_rss_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    return out


def main() -> None:
    if len(sys.argv) == 3 and sys.argv[1] == "--case":
        print(json.dumps(run_case(sys.argv[2])))
        return
    print(f"load_average_before: {os.getloadavg()[0]:.2f}")
    for method in ("quartic", "parabolic"):
        res = subprocess.run([sys.executable, __file__, "--case", method], capture_output=True,
                             text=True, check=True, env={**os.environ})
        figures = json.loads(res.stdout.strip().splitlines()[-1])
        for key, value in figures.items():
            print(f"{method}_{key}: {value:.3f}" if isinstance(value, float) else
                  f"{method}_{key}: {value}")
    print(f"load_average_after: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
