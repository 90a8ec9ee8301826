"""Speed and memory of the doublet-lattice AIC (aero.dlm.dlm_aic).

A 15-degree swept wing (leading-edge sweep), aspect ratio 6, taper 0.5, both halves modelled
(the left half defined right-to-left) without symmetry, M = 0.5, quartic kernel. Each case runs
in a fresh subprocess; ``peak_rss_mb`` is that process's ru_maxrss (the whole Python process,
numpy and the result included), ``seconds`` the wall time of the dlm_aic call alone,
``cpu_seconds`` its CPU time summed over threads (time.process_time) and ``thread_cpu_seconds``
the CPU time of each thread that ran during the call (sampled every 20 ms from
/proc/self/task on Linux, so the worker threads' share is visible; the machine is shared:
compare wall and CPU, and the load average printed with each case).

Run from the repository root:  PYTHONPATH=. python benchmarks/dlm.py
Prints ``key: value`` lines, with the 1-minute load average before and after: on a shared
machine the wall times scale with it, the CPU times much less.
"""
from __future__ import annotations

import json
import os
import resource
import subprocess
import sys
import time

import numpy as np

CASES = [(500, 1), (1000, 1), (2000, 1), (4000, 1), (2000, 8)]
NCHORD = {500: 10, 1000: 10, 2000: 20, 4000: 20}


def swept_wing(n: int):
    """Full-span wing of n boxes: AR 6, taper 0.5, LE sweep 15 deg, mean chord 1."""
    from aero.panels import caero1_boxes, concat
    nc = NCHORD[n]
    ns = n // (2 * nc)
    semi, root = 3.0, 4.0 / 3.0
    tip = 0.5 * root
    dx = semi * np.tan(np.radians(15.0))
    fs, fc = np.linspace(0.0, 1.0, ns + 1), np.linspace(0.0, 1.0, nc + 1)
    right = caero1_boxes(1000, [0, 0, 0], root, [dx, semi, 0], tip, fs, fc)
    left = caero1_boxes(5000, [0, 0, 0], root, [dx, -semi, 0], tip, fs, fc)
    return concat([right, left])


def _thread_cpu() -> dict:
    """CPU seconds (user + system) of each live thread of this process, by thread id."""
    tick = os.sysconf("SC_CLK_TCK")
    out = {}
    for tid in os.listdir("/proc/self/task"):
        try:
            with open(f"/proc/self/task/{tid}/stat") as fh:
                fields = fh.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        out[int(tid)] = (int(fields[11]) + int(fields[12])) / tick
    return out


def child(n: int, nk: int) -> None:
    import threading

    from aero.dlm import dlm_aic
    mesh = swept_wing(n)
    ks = np.linspace(0.1, 1.5, nk) if nk > 1 else np.array([0.5])
    seen, stop = {}, threading.Event()
    me = threading.get_native_id()

    def sample():
        while not stop.wait(0.02):
            seen.update(_thread_cpu() if os.path.isdir("/proc/self/task") else {})

    start = _thread_cpu() if os.path.isdir("/proc/self/task") else {}
    monitor = threading.Thread(target=sample, daemon=True)
    monitor.start()
    t0, c0 = time.perf_counter(), time.process_time()
    d = dlm_aic(mesh, 0.5, ks, refc=1.0, method="quartic")
    dt, dc = time.perf_counter() - t0, time.process_time() - c0
    stop.set()
    monitor.join()
    seen.update(_thread_cpu() if os.path.isdir("/proc/self/task") else {})
    per_thread = {("main" if tid == me else "pool/blas" if tid in start else "worker") + f"-{tid}":
                  round(cpu - start.get(tid, 0.0), 2) for tid, cpu in seen.items()
                  if tid != monitor.native_id and cpu - start.get(tid, 0.0) > 0.0}
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"n": mesh.n, "nk": nk, "seconds": dt, "cpu_seconds": dc,
                      "thread_cpu_seconds": per_thread,
                      "peak_rss_mb": rss, "result_mb": d.nbytes / 2 ** 20,
                      "finite": bool(np.isfinite(d).all())}))


def main() -> None:
    env = dict(os.environ)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    env["PYTHONPATH"] = root + os.pathsep + env.get("PYTHONPATH", "")
    print(f"machine_cpus: {os.cpu_count()}")
    print(f"load_average_1min_at_start: {os.getloadavg()[0]:.2f}")
    print("case: swept wing AR 6, taper 0.5, sweep 15 deg, M 0.5, quartic, symxz 0")
    for n, nk in CASES:
        load = os.getloadavg()[0]
        res = subprocess.run([sys.executable, __file__, "--child", str(n), str(nk)], env=env,
                             capture_output=True, text=True, check=True)
        r = json.loads(res.stdout.strip().splitlines()[-1])
        tag = f"n{r['n']}_nk{r['nk']}"
        print(f"{tag}_seconds: {r['seconds']:.3f}")
        print(f"{tag}_cpu_seconds: {r['cpu_seconds']:.3f}")
        print(f"{tag}_thread_cpu_seconds: {r['thread_cpu_seconds']}")
        print(f"{tag}_load_average_1min_before: {load:.2f}")
        print(f"{tag}_peak_rss_mb: {r['peak_rss_mb']:.1f}")
        print(f"{tag}_result_mb: {r['result_mb']:.1f}")
        print(f"{tag}_finite: {r['finite']}")
    print(f"load_average_1min_at_end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    if len(sys.argv) == 4 and sys.argv[1] == "--child":
        child(int(sys.argv[2]), int(sys.argv[3]))
    else:
        main()
