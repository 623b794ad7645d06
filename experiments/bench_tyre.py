"""Benchmark of the Magic Formula tyre: vectorised throughput and per-call cost.

Reports compile time and points per second for 10^6 random (Fz, kappa, alpha, gamma)
points (one vmapped call, combined slip, all five outputs), the latency of one jitted
4-wheel call from Python (dispatch-bound) and inside a compiled loop (what a vehicle RHS
pays), and the cost of a gradient with respect to all
147 coefficients relative to the forward evaluation.

    .venv/bin/python experiments/bench_tyre.py --out results/bench_tyre
"""

import argparse
import json
import time
from pathlib import Path

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

import jaxveh  # noqa: F401  (float64)
from jaxveh.tyre import load_fsae_tyre, tyre_forces


def _time(fn, *args, repeat: int = 5) -> float:
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/bench_tyre"))
    ap.add_argument("--points", type=int, default=1_000_000)
    args = ap.parse_args()
    tyre = load_fsae_tyre()
    rng = np.random.default_rng(0)
    n = args.points
    pts = [jnp.asarray(x) for x in (rng.uniform(0, 1200, n), rng.uniform(-0.3, 0.3, n),
                                    np.deg2rad(rng.uniform(-15, 15, n)), np.deg2rad(rng.uniform(-3, 3, n)))]

    per_point = jax.vmap(tyre_forces, in_axes=(None, 0, 0, 0, 0, None))
    batched = eqx.filter_jit(lambda t, fz, k, a, g: per_point(t, fz, k, a, g, 11.0))
    t0 = time.perf_counter()
    jax.block_until_ready(batched(tyre, *pts))
    compile_batch = time.perf_counter() - t0
    run_batch = _time(batched, tyre, *pts)

    four = eqx.filter_jit(lambda t, x: per_point(t, x[0], x[1], x[2], x[3], 11.0))
    x4 = jnp.asarray(
        [[700.0, 650.0, 750.0, 720.0], [0.02, 0.01, 0.05, 0.04], [0.03, 0.02, 0.04, 0.05], [0.0, 0.0, 0.01, -0.01]]
    )
    t0 = time.perf_counter()
    jax.block_until_ready(four(tyre, x4))
    compile_four = time.perf_counter() - t0
    t0 = time.perf_counter()
    reps = 2000
    for _ in range(reps):
        r = four(tyre, x4)
    jax.block_until_ready(r)
    call_four = (time.perf_counter() - t0) / reps

    # in-graph cost: the vehicle RHS traces the tyre into its own jitted function, so time
    # 10^4 dependent 4-wheel calls inside one compiled loop (no Python dispatch per call)
    loops = 10_000

    @eqx.filter_jit
    def chained(t, x):
        def body(_, xc):
            f = jax.vmap(tyre_forces, in_axes=(None, 0, 0, 0, 0, None))(t, xc[0], xc[1], xc[2], xc[3], 11.0)
            return xc.at[1].add(1e-9 * f.fx).at[2].add(1e-9 * f.fy)
        return jax.lax.fori_loop(0, loops, body, x)

    jax.block_until_ready(chained(tyre, x4))
    in_graph_four = _time(chained, tyre, x4, repeat=3) / loops

    m = 100_000
    sub = [p[:m] for p in pts]
    params, static = eqx.partition(tyre, eqx.is_inexact_array)

    def loss(p, fz, k, a, g):
        f = jax.vmap(tyre_forces, in_axes=(None, 0, 0, 0, 0, None))(eqx.combine(p, static), fz, k, a, g, 11.0)
        return jnp.sum(f.fx**2 + f.fy**2 + f.mz**2)

    fwd = eqx.filter_jit(loss)
    grad = eqx.filter_jit(jax.grad(loss))
    jax.block_until_ready(fwd(params, *sub))
    jax.block_until_ready(grad(params, *sub))
    ratio = _time(grad, params, *sub, repeat=7) / _time(fwd, params, *sub, repeat=7)

    result = {
        "device": str(jax.devices()[0]),
        "points": n,
        "compile_batch_s": compile_batch,
        "run_batch_s": run_batch,
        "points_per_s": n / run_batch,
        "compile_four_wheel_s": compile_four,
        "four_wheel_call_us": call_four * 1e6,
        "four_wheel_in_graph_us": in_graph_four * 1e6,
        "grad_wrt_147_coefficients_over_forward": ratio,
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_tyre.json").write_text(json.dumps(result, indent=2))
    for k, v in result.items():
        print(f"{k}: {v:.4g}" if isinstance(v, float) else f"{k}: {v}")


if __name__ == "__main__":
    main()
