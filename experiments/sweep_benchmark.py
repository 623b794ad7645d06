"""Benchmark of ``optimise.sweep``: grid throughput (evaluations per second) against the chunk
size on the local backend, and Ray with local workers against local on the same sweep.

Each configuration runs the same λ x µ grid twice into fresh folders: ``first`` includes
compiling the chunk's program (once per chunk shape), ``warm`` reuses it (the same process;
for Ray the same workers), so ``warm`` is the steady throughput of the machinery: the
compiled vmapped call, padding, one checkpoint file per chunk, the Dataset and netCDF file
(no plots). Ray's ``init_s`` is starting a local Ray; its first run also starts the workers
and imports jaxveh in each (programs come from JAX's disk cache, ``~/.cache/jaxveh`` as for
``jaxveh sweep``, once the local runs have compiled them). Prints JSON.

    .venv/bin/python experiments/sweep_benchmark.py                          # chapter-3 model
    .venv/bin/python experiments/sweep_benchmark.py --model car --n 4 --chunks 4 --ray-chunk 4
"""

import argparse
import json
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import optimise
from jaxveh.cli._simulate import _compilation_cache
from optimise import Study, SweepVariable


def grid_study(model: str, n: int, chunk: int, out: Path, backend: str = "local", num_cpus=None) -> Study:
    """An n x n grid: λ 0.3-0.7 x µ 0.1-10 (log): µ = kC / (kF + kR) on the chapter-3 model, the
    first mode's stiffness multiplier on the car (6 modes)."""
    lam = SweepVariable("lambda", "lambda", tuple(np.linspace(0.3, 0.7, n)), "1")
    if model == "car":
        mu = SweepVariable("mu_1", "chassis.stiffness_scale[0]", tuple(np.geomspace(0.1, 10.0, n)), "1", True)
    else:
        mu = SweepVariable("mu", "mu", tuple(np.geomspace(0.1, 10.0, n)), "1", True)
    return Study(name="bench", model=model, variables=(lam, mu), quantities=("chi",), backend=backend,
                 chunk=chunk, out=str(out), num_cpus=num_cpus)


def _run(study: Study) -> float:
    t0 = time.perf_counter()
    result = optimise.sweep(study, plots=False)
    assert result.computed == tuple(range(len(optimise.chunk_ranges(study))))
    return time.perf_counter() - t0


def _pair(make, n_points: int) -> dict:
    first, warm = _run(make("first")), _run(make("warm"))
    def sig(x):
        return float(f"{x:.4g}")

    return {"first_s": sig(first), "warm_s": sig(warm), "evals_per_s_first": sig(n_points / first),
            "evals_per_s_warm": sig(n_points / warm)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", choices=("analytic", "car"), default="analytic")
    ap.add_argument("--n", type=int, default=64, help="grid points per axis (n x n)")
    ap.add_argument("--chunks", default="1,16,64,256", help="chunk sizes of the local runs")
    ap.add_argument("--ray-workers", type=int, default=2, help="Ray workers (0: skip Ray)")
    ap.add_argument("--ray-chunk", type=int, default=64, help="chunk size of the Ray vs local comparison")
    args = ap.parse_args()
    _compilation_cache()  # as jaxveh sweep: JAX's disk cache, shared with the Ray workers
    n_points = args.n**2
    report = {"model": args.model, "grid": [args.n, args.n], "n_points": n_points, "local": {}}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for chunk in (int(c) for c in args.chunks.split(",")):
            report["local"][str(chunk)] = _pair(
                lambda tag, chunk=chunk: grid_study(args.model, args.n, chunk, tmp / f"local_{chunk}_{tag}"), n_points)
        if args.ray_workers:
            import ray

            chunk = args.ray_chunk
            local = report["local"].get(str(chunk)) or _pair(
                lambda tag: grid_study(args.model, args.n, chunk, tmp / f"local_{chunk}_{tag}"), n_points)
            t0 = time.perf_counter()
            with warnings.catch_warnings():  # Ray's fork + exec, not a fork of JAX's threads
                warnings.filterwarnings("ignore", message="os.fork", category=RuntimeWarning)
                ray.init(num_cpus=args.ray_workers, include_dashboard=False, log_to_driver=False)
            init_s = time.perf_counter() - t0
            try:  # Ray already running: sweep uses these workers and leaves Ray up between the two runs
                remote = _pair(lambda tag: grid_study(args.model, args.n, chunk, tmp / f"ray_{tag}", "ray"), n_points)
            finally:
                ray.shutdown()
            report["ray_vs_local"] = {"chunk": chunk, "workers": args.ray_workers, "init_s": round(init_s, 3),
                                      "ray": remote, "local": local}
    print(json.dumps(report, indent=2))


if __name__ == "__main__":
    main()
