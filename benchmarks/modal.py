"""Modal benchmark: stiffened plates of ~60,000 and ~240,000 DOF solved by our solver and MYSTRAN.

The deck: a 2 m x 1 m aluminium CQUAD4 plate (MAT1 E = 70 GPa, nu = 0.33, rho = 2700 kg/m^3,
PSHELL T = 3 mm with MID3 for transverse shear), n x n elements with n = round(sqrt(size / 6))
for each ``--sizes`` entry (100 x 100: 61,206 g-set DOF; 200 x 200: 242,406), CBAR edge stiffeners
(30 mm x 10 mm rectangular bars) along both long edges, clamped (123456) along the short edge
x = 0, EIGRL for ``--modes`` modes. SI units.

Each solver runs in its own subprocess, so that its wall time and peak resident memory (``ru_maxrss``
from ``os.wait4``) are its own; ours and MYSTRAN alternate ``--repeat`` times per size (the cores
are shared, so single runs are noisy) and the figures are the minimum and median over the runs.
Our solver reports the wall seconds of each phase (read, assemble, solve, write) and the sparse
factorisation backend (``--backend`` forces one, as ``FTP_SPARSE_BACKEND``) with its thread count
(:func:`structures.sparse_factor.free_cores`: fewer on a busy machine). Output: one
``key: value`` per line, keys prefixed by the size (``dof60000_...``).

Usage: ``PYTHONPATH=. python benchmarks/modal.py [--sizes 60000,240000 --modes 40 --repeat 2
--backend pardiso --no-mystran]``
"""
from __future__ import annotations

import argparse
import json
import os
import statistics
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
    """Our solver, phase by phase; prints a JSON line with the timings and frequencies.

    ``imports`` is the import of the solver's modules and pyNastran (numpy is already loaded by
    this script); the interpreter's own start and exit are the run's wall time minus the phases
    (``startup`` in the output).
    """
    times = {}
    t0 = time.perf_counter()
    from structures.assembly import assemble
    from structures.bdf import read_model
    from structures.modal import compute_modes
    from structures.modes import write_modes
    from structures.sparse_factor import choose_backend, free_cores

    import pyNastran.bdf.bdf  # noqa: F401  (read_model's parser, imported before settling)
    from structures.common.process import settle_process

    settle_process()                   # as the ``pipeline`` command does
    times["imports"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    model = read_model(deck)
    times["read"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    system = assemble(model)
    times["assemble"] = time.perf_counter() - t0
    threads = free_cores()             # what the PARDISO factor, made next, will use
    t0 = time.perf_counter()
    ds = compute_modes(model, nmodes, system=system)
    times["solve"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    write_modes(ds, out)
    times["write"] = time.perf_counter() - t0
    print(json.dumps({"times": times, "frequencies": [float(f) for f in ds["frequency"].values],
                      "a_set_dof": int(system.K.shape[0]), "backend": choose_backend(),
                      "pardiso_threads": threads}))
    settle_process()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="60000,240000",
                        help="comma-separated target g-set DOF counts (default 60000,240000)")
    parser.add_argument("--modes", type=int, default=40)
    parser.add_argument("--repeat", type=int, default=2, help="runs of each solver per size")
    parser.add_argument("--backend", help="force the sparse factorisation backend")
    parser.add_argument("--no-mystran", action="store_true")
    parser.add_argument("--worker", nargs=3, metavar=("DECK", "OUT", "NMODES"), help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(Path(args.worker[0]), Path(args.worker[1]), int(args.worker[2]))
        return
    env = dict(os.environ, PYTHONPATH=str(Path(__file__).resolve().parents[1]))
    if args.backend:
        env["FTP_SPARSE_BACKEND"] = args.backend
    exe = None if args.no_mystran else mystran_executable()
    print(f"cpu_count: {os.cpu_count()}")
    print(f"modes: {args.modes}")
    print(f"repeat: {args.repeat}")
    for size in (int(text) for text in args.sizes.split(",")):
        with tempfile.TemporaryDirectory(prefix="modal_bench_") as tmp:
            compare(Path(tmp), size, args.modes, args.repeat, env, exe)


def compare(folder: Path, size: int, nmodes: int, repeat: int, env: dict, exe: str | None) -> None:
    """Alternate our solver and MYSTRAN ``repeat`` times on one deck; print the figures."""
    n = round(np.sqrt(size / 6))
    deck = folder / "plate.bdf"
    ngrid = write_deck(deck, n, n, nmodes)
    key = f"dof{size}"
    print(f"{key}_grids: {ngrid}")
    print(f"{key}_dof_g_set: {6 * ngrid}")
    print(f"{key}_elements_cquad4: {n * n}")
    print(f"{key}_elements_cbar: {2 * n}")
    print(f"{key}_load_average_1min_before: {os.getloadavg()[0]:.2f}")
    runs = {"ours": [], "mystran": []}
    for _ in range(repeat):
        wall, cpu, peak, out = run_measured([sys.executable, str(Path(__file__).resolve()),
                                             "--worker", str(deck), str(folder / "modes.nc"),
                                             str(nmodes)], folder, env)
        ours = json.loads(out.strip().splitlines()[-1])
        runs["ours"].append((wall, cpu, peak))
        if exe is not None:
            runs["mystran"].append(run_measured([exe, deck.name], folder, dict(os.environ))[:3])
    for phase, seconds in ours["times"].items():
        print(f"{key}_ours_{phase}_s_last: {seconds:.3f}")
    print(f"{key}_ours_startup_s_last: {runs['ours'][-1][0] - sum(ours['times'].values()):.3f}")
    print(f"{key}_ours_backend: {ours['backend']}")
    print(f"{key}_ours_pardiso_threads_last: {ours['pardiso_threads']}")
    print(f"{key}_ours_a_set_dof: {ours['a_set_dof']}")
    for name, figures in runs.items():
        for label, index, fmt in (("wall_s", 0, ".3f"), ("cpu_s", 1, ".3f"),
                                  ("peak_rss_mb", 2, ".0f")):
            values = [f[index] for f in figures]
            if values:
                print(f"{key}_{name}_{label}_runs: " + " ".join(f"{v:{fmt}}" for v in values))
                print(f"{key}_{name}_{label}_min: {min(values):{fmt}}")
                print(f"{key}_{name}_{label}_median: {statistics.median(values):{fmt}}")
    print(f"{key}_ours_first5_hz: " + " ".join(f"{f:.5g}" for f in ours["frequencies"][:5]))
    if exe is None:
        print(f"{key}_mystran: not run")
        return
    theirs = mystran_frequencies(deck)
    print(f"{key}_mystran_first5_hz: " + " ".join(f"{f:.5g}" for f in theirs[:5]))
    count = min(len(theirs), len(ours["frequencies"]))
    diff = np.max(np.abs(np.array(ours["frequencies"][:count]) / theirs[:count] - 1.0))
    print(f"{key}_max_relative_frequency_difference_{count}_modes: {diff:.2e}")
    for label, index in (("wall", 0), ("cpu", 1)):
        ours_t = [f[index] for f in runs["ours"]]
        theirs_t = [f[index] for f in runs["mystran"]]
        print(f"{key}_speedup_mystran_over_ours_{label}_median: "
              f"{statistics.median(theirs_t) / statistics.median(ours_t):.2f}")
        print(f"{key}_speedup_mystran_over_ours_{label}_min: {min(theirs_t) / min(ours_t):.2f}")
    print(f"{key}_load_average_1min_after: {os.getloadavg()[0]:.2f}")


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
