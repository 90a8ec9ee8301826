"""Tuning benchmark: 24 design variables, two configurations of a ~20,000-DOF model, 30 modes.

The model is the aircraft-like beam/shell deck of ``tests/structures/tuning_decks.py`` refined to
``--span`` stations per wing and ``--chord`` skin elements per station (defaults: ~3,300 grids,
~19,800 DOFs); the "full" configuration adds fuel CONM2s along the spars. GVT data: 14 elastic
modes of a perturbed truth at 120 DOFs. Objective: every frequency error and cross-orthogonality
off-diagonal of both configurations (2 x (14 + 182) indices), SLSQP.

Figures (``key: value`` lines): setup seconds, seconds per evaluation without gradients,
evaluations per second, seconds per evaluation with gradients (per shape method), seconds per
SLSQP iteration (with gradients; time and counts up to the last completed iteration, the start
design's gradient included), eigen solves and gradients per SLSQP iteration, peak resident memory
of each method's tuning (``[method] peak_rss_mb``: evaluator set-up to the end of ``tune``, the
previous method's evaluator released; Linux, from VmHWM reset through /proc/self/clear_refs) and
of the whole process (``peak_rss_mb``, which includes building the truth models and GVTs). Wall
seconds depend on what else runs on the machine: the CPU seconds of the process (all its
threads) and the 1-minute load average are printed beside them.

Usage: ``PYTHONPATH=. python benchmarks/tuning.py [--span 180 --chord 8 --iterations 3 --workers 2]``
"""
from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "structures"))
from tuning_decks import synthetic_gvt, write_aircraft_deck  # noqa: E402

from structures.bdf import read_model  # noqa: E402
from structures.design import DesignVariable  # noqa: E402
from structures.modal import compute_modes  # noqa: E402
from structures.tuning import Evaluator, TuningConfiguration, TuningProblem, tune  # noqa: E402


def variables(skin_e_only: bool = False):
    """24 design variables (39 fields), left/right linked.

    The skin modulus drives MAT1 2 E and G together: the deck gives E and NU with G blank, so the
    truth deck's G follows its E (Nastran completes G = E / 2(1 + NU)); the reader stores the
    completed G, and tuning E alone would hold G (20 % off the isotropic G = E / 2(1 + NU) at a
    bound). ``skin_e_only`` keeps the former E-only variable (38 fields): its skin matrices are
    then rational in E / G and are re-assembled at every design (structures.subassembly).
    """
    skin = [("MAT1", 2, "E")] if skin_e_only else [("MAT1", 2, "E"), ("MAT1", 2, "G")]
    both = lambda card, a, b, f: [(card, a, f), (card, b, f)]  # noqa: E731
    out = [DesignVariable(f"fus_{f}", [("PBAR", 1, f)]) for f in ("A", "I1", "I2", "J")]
    out += [DesignVariable(f"in_{f}", both("PBAR", 11, 12, f)) for f in ("I1", "I2", "J")]
    out += [DesignVariable(f"out_{f}", both("PBAR", 13, 14, f)) for f in ("I1", "I2", "J")]
    out += [DesignVariable(f"tail_{f}", [("PBAR", 31, f)]) for f in ("I1", "I2", "J")]
    out += [DesignVariable(f"fin_{f}", [("PBAR", 32, f)]) for f in ("I1", "I2")]
    out += [DesignVariable("skin_T", both("PSHELL", 21, 22, "T")),
            DesignVariable("skin_E", skin), DesignVariable("bar_E", [("MAT1", 1, "E")]),
            DesignVariable("engine_M", both("CONM2", 900, 901, "M")),
            DesignVariable("engine_I22", both("CONM2", 900, 901, "I22")),
            DesignVariable("pylon_K", [("PELAS", 41, "K")]),
            DesignVariable("pylon_rot", both("CELAS2", 805, 808, "K")),
            DesignVariable("payload", [("CONM2", 910, "M")]),
            DesignVariable("fuel", [("CONM2", 950, "M")])]
    return out


def reset_peak_rss() -> bool:
    """Reset the process's peak resident memory (Linux >= 4.0); False where that is impossible."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        return False
    return True


def peak_rss_mb() -> float:
    """Peak resident memory [MB] since the last reset (VmHWM), else since the process started."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--span", type=int, default=180)
    parser.add_argument("--chord", type=int, default=8)
    parser.add_argument("--iterations", type=int, default=3)
    parser.add_argument("--methods", default="modal,nelson")
    parser.add_argument("--workers", type=int, default=None,
                        help="threads evaluating the configurations (default: Evaluator's)")
    parser.add_argument("--skin-e-only", action="store_true",
                        help="tune the skin E alone (G held: re-assembled skin, see variables())")
    args = parser.parse_args(argv)
    print(f"blas_threads: {os.environ.get('OPENBLAS_NUM_THREADS', 'default')}")
    tmp = Path(tempfile.mkdtemp(prefix="tuning_bench_"))
    t0 = time.perf_counter()
    var = variables(args.skin_e_only)
    factors = {(r.card, r.card_id, r.field): 1.0 + 0.1 * np.sin(3.0 * i + 1.0)
               for i, v in enumerate(var) for r in v.fields}
    configs = []
    for name, fuel in (("empty", 0.0), ("full", 300.0)):
        info = write_aircraft_deck(tmp / f"{name}.bdf", n_span=args.span, n_chord=args.chord,
                                   n_fus=60, fuel=fuel)
        truth = read_model(write_aircraft_deck(tmp / f"{name}_truth.bdf", n_span=args.span,
                                               n_chord=args.chord, n_fus=60, fuel=fuel,
                                               changes=factors)["path"])
        gvt = synthetic_gvt(compute_modes(truth, 30), info["grids"], list(range(7, 21)))
        configs.append(TuningConfiguration(name, read_model(info["path"]), gvt, nmodes=30))
    print(f"grids: {info['n_grids']}")
    print(f"dofs: {6 * info['n_grids']}")
    print(f"design_variables: {len(var)}")
    print(f"truth_and_gvt_seconds: {time.perf_counter() - t0:.2f}")
    for method in args.methods.split(","):
        problem = TuningProblem(tuple(configs), tuple(var),
                                objective=(("*:frequency:*", 1.0), ("*:cross_orthogonality:*", 1.0)),
                                shape_method=method)
        reset = reset_peak_rss()
        t0 = time.perf_counter()
        ev = Evaluator(problem, workers=args.workers)
        print(f"[{method}] workers: {ev.workers}")
        print(f"[{method}] setup_seconds: {time.perf_counter() - t0:.2f}")
        print(f"[{method}] a_set_dofs: {[c.sub.system.K.shape[0] for c in ev.configs]}")
        t0, c0 = time.perf_counter(), time.process_time()
        n_eval = 3
        for k in range(n_eval):
            ev.evaluate(ev.space.x0 * (1.0 + 0.01 * (k + 1)))
        per_eval = (time.perf_counter() - t0) / n_eval
        print(f"[{method}] seconds_per_evaluation: {per_eval:.2f}")
        print(f"[{method}] cpu_seconds_per_evaluation: {(time.process_time() - c0) / n_eval:.2f}")
        print(f"[{method}] evaluations_per_second: {1.0 / per_eval:.3f}")
        t0, c0 = time.perf_counter(), time.process_time()
        ev.evaluate(ev.space.x0 * 1.005, True)
        print(f"[{method}] seconds_per_evaluation_with_gradients: {time.perf_counter() - t0:.2f}")
        print(f"[{method}] cpu_seconds_per_evaluation_with_gradients: {time.process_time() - c0:.2f}")
        stamps = []
        counts = dict(ev.counts)
        t0, c0 = time.perf_counter(), time.process_time()
        result = tune(problem, maxiter=args.iterations, evaluator=ev,
                      progress=lambda it, obj, viol, sec: stamps.append(
                          (it, obj, sec, time.process_time() - c0, dict(ev.counts))))
        print(f"[{method}] seconds_to_tune_return: {time.perf_counter() - t0:.2f}")
        n_it = max(len(stamps), 1)
        total, cpu, last = stamps[-1][2], stamps[-1][3], stamps[-1][4]
        for it, obj, sec, _, _ in stamps:
            print(f"[{method}] iteration {it}: objective {obj:.4e} at {sec:.1f} s")
        print(f"[{method}] slsqp_iterations: {len(stamps)}")
        print(f"[{method}] evaluations: {result.history.sizes['iteration']}")
        print(f"[{method}] eigen_solves_per_iteration: "
              f"{(last['designs'] - counts['designs']) / n_it:.2f}")
        print(f"[{method}] gradients_per_iteration: "
              f"{(last['gradients'] - counts['gradients']) / n_it:.2f}")
        print(f"[{method}] seconds_per_iteration: {total / n_it:.2f}")
        print(f"[{method}] cpu_seconds_per_iteration: {cpu / n_it:.2f}")
        print(f"[{method}] load_average_1min: {os.getloadavg()[0]:.2f}")
        print(f"[{method}] peak_rss_mb: {peak_rss_mb():.0f}"
              + ("" if reset else " (process peak: the reset is not available here)"))
        del ev, result       # one tuning at a time: the next method's evaluator starts afresh
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(f"peak_rss_mb: {peak:.0f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
