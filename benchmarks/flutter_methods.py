"""Benchmark: the three flutter methods (p-k, g-method, p-method on a rational fit) on the same data.

Two cases:

* Nastran's bah_plane (tests/data/bah_plane: its own QHH and generalized mass and stiffness),
  FLUTTER 502, 30 velocities, 10 modes;
* with ``--run DIR`` (a finished ``pipeline run`` of data/x56_like/case.toml), the X-56A-class
  EFEW configuration's stage-0 modes and GAFs (34 modes) on the case's four matched-point lines of
  43 points each.

For each method: wall and CPU seconds of the solve (the machine is shared: take the minimum over
``--repeat`` runs), and the first crossing of every sweep (speed, frequency, kind), so the methods
can be compared at g = 0 where all three are exact. Output: one ``key: value`` per line.

Run: ``PYTHONPATH=. python benchmarks/flutter_methods.py [--run runs/x56_like] [--repeat 3]``
"""
from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tests" / "flutter"))

from aero.rfa import fit_rfa  # noqa: E402
from flutter.solve import FlutterRequest, solve_flutter, solve_request  # noqa: E402
from flutter.system import ModalSystem  # noqa: E402
from flutter_nastran import bah_flutter_502  # noqa: E402

SOLVERS = ("pk", "g", "p")


def timed(run, repeat: int):
    """(minimum wall seconds, its CPU seconds, the last result) of ``repeat`` calls of ``run``."""
    best = (np.inf, np.inf, None)
    for _ in range(repeat):
        w0, c0 = time.perf_counter(), time.process_time()
        out = run()
        wall, cpu = time.perf_counter() - w0, time.process_time() - c0
        if wall < best[0]:
            best = (wall, cpu, out)
    return best


def report(case: str, solver: str, wall: float, cpu: float, results) -> None:
    print(f"{case}_{solver}_wall_s: {wall:.3f}")
    print(f"{case}_{solver}_cpu_s: {cpu:.3f}")
    for lab, ds in results:
        if ds.sizes.get("crossing", 0):
            i = int(np.argmin(ds["crossing_velocity"].values))
            print(f"{case}_{solver}_first_crossing[{lab['configuration']}, M {lab['mach']:.3f}]: "
                  f"V {float(ds.crossing_velocity[i]):.2f}, f {float(ds.crossing_frequency[i]):.3f} "
                  f"Hz, {ds.crossing_kind.values[i]}")


def bah(repeat: int) -> None:
    c = bah_flutter_502()
    system = ModalSystem(np.diag(c["gm"]), np.diag(c["gk"]))
    for solver in SOLVERS:
        req = FlutterRequest(sid=502, method="PK", density=(c["rho"],), mach=(c["mach"],),
                             values=tuple(c["V"]), solver=solver)
        wall, cpu, out = timed(lambda: solve_request(system, c["gaf"], req, fit_rfa), repeat)
        report("bah_plane", solver, wall, cpu, out)


def x56(run_dir: Path, repeat: int) -> None:
    from pipeline.case import read_case
    from pipeline.chain import _requests
    from structures.common.files import read_dataset
    from structures.common.nastran import read_pynastran

    case = read_case(REPO / "data" / "x56_like" / "case.toml")
    config = next(c for c in case.configurations if c.name == "efew")
    folder = Path(run_dir) / "stage0" / "efew" / "flutter"
    modes, gaf = read_dataset(folder / "modes.nc"), read_dataset(folder / "gaf.nc")
    s = case.flutter
    for solver in SOLVERS:
        reqs = _requests(read_pynastran(config.deck), str(config.deck), None, s.structural_damping,
                         s.matched, case.units, solver)
        wall, cpu, out = timed(lambda: solve_flutter(modes, gaf, reqs, case.units,
                                                     rational_fit=fit_rfa), repeat)
        report("x56_efew", solver, wall, cpu, out)
    print(f"x56_efew_modes: {modes.sizes['mode']}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--run", type=Path, default=None,
                        help="a finished pipeline run of data/x56_like/case.toml")
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # roots beyond the k table at low speed
        bah(args.repeat)
        if args.run is not None:
            x56(args.run, args.repeat)


if __name__ == "__main__":
    main()
