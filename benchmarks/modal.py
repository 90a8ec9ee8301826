"""Modal benchmark: a ~60,000-DOF stiffened plate solved by our solver and (if installed) MYSTRAN.

The deck: a 2 m x 1 m aluminium CQUAD4 plate (MAT1 E = 70 GPa, nu = 0.33, rho = 2700 kg/m^3,
PSHELL T = 3 mm with MID3 for transverse shear), ``--nx`` x ``--ny`` elements, CBAR edge stiffeners
(30 mm x 10 mm rectangular bars) along both long edges, clamped (123456) along the short edge x = 0,
EIGRL for ``--modes`` modes. SI units.

Each solver runs in its own subprocess, so that its wall time and peak resident memory (``ru_maxrss``
from ``os.wait4``) are its own. Our solver reports the wall seconds of each phase (read, assemble,
solve, write). Output: one ``key: value`` per line.

Usage: ``PYTHONPATH=. python benchmarks/modal.py [--nx 100 --ny 100 --modes 40 --no-mystran]``
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from structures.bulk_text import real8
from structures.mystran import mystran_executable

E, NU, RHO, T = 7.0e10, 0.33, 2700.0, 0.003
BAR_W, BAR_H = 0.03, 0.01


def write_deck(path: Path, nx: int, ny: int, nmodes: int, a: float = 2.0, b: float = 1.0) -> int:
    """Write the stiffened-plate deck (free-field cards); return the number of grids."""
    x = np.linspace(0.0, a, nx + 1)
    y = np.linspace(0.0, b, ny + 1)
    gid = np.arange(1, (nx + 1) * (ny + 1) + 1).reshape(nx + 1, ny + 1)
    area = BAR_W * BAR_H
    i1 = BAR_W * BAR_H ** 3 / 12                       # bending out of the plate (about the 1-axis)
    i2 = BAR_H * BAR_W ** 3 / 12
    j = BAR_W * BAR_H ** 3 / 3 * (1 - 0.63 * BAR_H / BAR_W)   # thin rectangle (Roark, table 10.7)
    lines = ["SOL 103", "CEND", "TITLE = MODAL BENCHMARK STIFFENED PLATE", "METHOD = 1", "SPC = 1",
             "DISP(PLOT) = ALL", "BEGIN BULK", f"EIGRL,1,,,{nmodes}",
             f"MAT1,1,{real8(E)},,{real8(NU)},{real8(RHO)}", f"PSHELL,1,1,{real8(T)},1,,1",
             f"PBAR,2,1,{real8(area)},{real8(i1)},{real8(i2)},{real8(j)}"]
    for i in range(nx + 1):
        for k in range(ny + 1):
            lines.append(f"GRID,{gid[i, k]},,{real8(x[i])},{real8(y[k])},0.")
    eid = 1
    for i in range(nx):
        for k in range(ny):
            lines.append(f"CQUAD4,{eid},1,{gid[i, k]},{gid[i + 1, k]},{gid[i + 1, k + 1]},{gid[i, k + 1]}")
            eid += 1
    for k in (0, ny):
        for i in range(nx):
            lines.append(f"CBAR,{eid},2,{gid[i, k]},{gid[i + 1, k]},0.,0.,1.")
            eid += 1
    root = gid[0]
    for start in range(0, len(root), 8):
        lines.append("SPC1,1,123456," + ",".join(str(g) for g in root[start:start + 8]))
    lines.append("ENDDATA")
    path.write_text("\n".join(lines) + "\n")
    return gid.size


def worker(deck: Path, out: Path, nmodes: int) -> None:
    """Our solver, phase by phase; prints a JSON line with the timings and frequencies."""
    from structures.assembly import assemble
    from structures.bdf import read_model
    from structures.modal import compute_modes
    from structures.modes import write_modes

    times = {}
    t0 = time.perf_counter()
    model = read_model(deck)
    times["read"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    system = assemble(model)
    times["assemble"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    ds = compute_modes(model, nmodes, system=system)
    times["solve"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    write_modes(ds, out)
    times["write"] = time.perf_counter() - t0
    print(json.dumps({"times": times, "frequencies": [float(f) for f in ds["frequency"].values],
                      "a_set_dof": int(system.K.shape[0])}))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--nx", type=int, default=100)
    parser.add_argument("--ny", type=int, default=100)
    parser.add_argument("--modes", type=int, default=40)
    parser.add_argument("--no-mystran", action="store_true")
    parser.add_argument("--worker", nargs=3, metavar=("DECK", "OUT", "NMODES"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(Path(args.worker[0]), Path(args.worker[1]), int(args.worker[2]))
        return
    with tempfile.TemporaryDirectory(prefix="modal_bench_") as tmp:
        folder = Path(tmp)
        deck = folder / "plate.bdf"
        ngrid = write_deck(deck, args.nx, args.ny, args.modes)
        print(f"grids: {ngrid}")
        print(f"dof_g_set: {6 * ngrid}")
        print(f"elements_cquad4: {args.nx * args.ny}")
        print(f"elements_cbar: {2 * args.nx}")
        print(f"modes: {args.modes}")
        print(f"cpu_count: {os.cpu_count()}")
        print(f"load_average_1min_before: {os.getloadavg()[0]:.2f}")
        env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
        wall, cpu, peak, out = run_measured([sys.executable, str(Path(__file__).resolve()), "--worker",
                                        str(deck), str(folder / "modes.nc"), str(args.modes)],
                                       folder, env)
        ours = json.loads(out.strip().splitlines()[-1])
        for phase, seconds in ours["times"].items():
            print(f"ours_{phase}_s: {seconds:.3f}")
        print(f"ours_a_set_dof: {ours['a_set_dof']}")
        print(f"ours_total_wall_s: {wall:.3f}")
        print(f"ours_total_cpu_s: {cpu:.3f}")
        print(f"ours_peak_rss_mb: {peak:.0f}")
        print("ours_first5_hz: " + " ".join(f"{f:.5g}" for f in ours["frequencies"][:5]))
        exe = None if args.no_mystran else mystran_executable()
        if exe is None:
            print("mystran: not run")
            return
        wall_m, cpu_m, peak_m, _ = run_measured([exe, deck.name], folder, dict(os.environ))
        theirs = mystran_frequencies(deck)
        print(f"mystran_total_wall_s: {wall_m:.3f}")
        print(f"mystran_total_cpu_s: {cpu_m:.3f}")
        print(f"mystran_peak_rss_mb: {peak_m:.0f}")
        print("mystran_first5_hz: " + " ".join(f"{f:.5g}" for f in theirs[:5]))
        n = min(len(theirs), len(ours["frequencies"]))
        diff = np.max(np.abs(np.array(ours["frequencies"][:n]) / theirs[:n] - 1.0))
        print(f"max_relative_frequency_difference_{n}_modes: {diff:.4f}")
        print(f"speedup_mystran_over_ours_wall: {wall_m / wall:.2f}")
        print(f"speedup_mystran_over_ours_cpu: {cpu_m / cpu:.2f}")
        print(f"load_average_1min_after: {os.getloadavg()[0]:.2f}")


def run_measured(cmd: list[str], cwd: Path, env: dict) -> tuple[float, float, float, str]:
    """Run ``cmd`` in ``cwd``; return (wall s, CPU s, peak RSS MB) of that child alone and its output.

    CPU seconds (user + system) are less sensitive than wall time to other load on a shared machine.
    """
    log = cwd / (Path(cmd[-1]).stem + f"_{len(list(cwd.glob('*.log')))}.log")
    t0 = time.perf_counter()
    with open(log, "w") as out:
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=out, stderr=subprocess.STDOUT)
        _, status, usage = os.wait4(proc.pid, 0)      # rusage of this child only
    wall = time.perf_counter() - t0
    proc.returncode = os.waitstatus_to_exitcode(status)
    text = log.read_text(errors="replace")
    if proc.returncode != 0:
        raise SystemExit(f"{cmd[0]} failed with exit code {proc.returncode}:\n{text[-3000:]}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss / 1024.0, text


def mystran_frequencies(deck: Path) -> np.ndarray:
    """Frequencies [Hz] from MYSTRAN's OP2 (eigns = omega^2)."""
    from pyNastran.op2.op2 import read_op2

    op2 = deck.with_suffix(".OP2")
    if not op2.exists():
        raise SystemExit(f"MYSTRAN wrote no OP2; see {deck.with_suffix('.F06')}")
    vectors = read_op2(str(op2), debug=None).eigenvectors
    eigns = np.asarray(vectors[min(vectors)].eigns, dtype=float)
    return np.sqrt(np.clip(eigns, 0.0, None)) / (2 * np.pi)


if __name__ == "__main__":
    main()
