"""Benchmark of the chassis FE pipeline (dense JAX, CPU).

Times, for the shipped FSAE frame and for the same frame meshed ~10x finer: assembly,
full generalised eigen-solve, torsion test, and the gradient of the first frequency
w.r.t. all section sizes relative to the forward solve. Compile time is reported apart.

    .venv/bin/python experiments/bench_fe.py [--skip-large]
"""

import argparse
import json
import time
from importlib import resources
from pathlib import Path

import jax
import tomllib

import jaxveh.fe as fe


def timed(fn, *args, repeat=3):
    """(first-call seconds incl. compile, best of ``repeat`` warm seconds; the first call
    again if ``repeat`` is 0)."""
    t0 = time.perf_counter()
    jax.block_until_ready(fn(*args))
    first = time.perf_counter() - t0
    best = first if repeat == 0 else float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        best = min(best, time.perf_counter() - t0)
    return first, best


def bench(frame, repeat, with_grad=True):
    n_dof = fe.frame_mesh(frame).n_dof
    assemble = jax.jit(fe.assemble)
    K, M = assemble(frame)
    eig = jax.jit(fe.generalised_eigh)
    f1 = jax.jit(lambda fr: fe.chassis_modes(fr, 1)[0][0])
    grad = jax.jit(jax.grad(lambda secs: fe.chassis_modes(fe.with_sections(frame, secs), 1)[0][0]))
    out = {"n_nodes": fe.frame_mesh(frame).n_nodes, "n_dof": n_dof}
    out["assembly_compile_s"], out["assembly_s"] = timed(assemble, frame, repeat=repeat)
    out["eigensolve_compile_s"], out["eigensolve_s"] = timed(eig, K, M, repeat=repeat)
    out["torsion_compile_s"], out["torsion_s"] = timed(fe.torsion_test, frame, repeat=repeat)
    if with_grad:
        out["f1_compile_s"], out["f1_forward_s"] = timed(f1, frame, repeat=repeat)
        out["grad_compile_s"], out["f1_grad_s"] = timed(grad, frame.sections, repeat=repeat)
        out["grad_over_forward"] = out["f1_grad_s"] / out["f1_forward_s"]
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--skip-large", action="store_true", help="only the shipped frame")
    ap.add_argument("--large-grad", action="store_true", help="also time the gradient on the 10x frame")
    ap.add_argument("--out", type=Path, default=None, help="optional JSON output file")
    args = ap.parse_args()
    text = resources.files("jaxveh.fe").joinpath("data/fsae_2009_frame.toml").read_text()
    table = tomllib.loads(text)
    print(f"devices: {jax.devices()}")
    results = {"fsae_frame": bench(fe.frame_from_dict(table, "fsae"), repeat=3)}
    report("fsae_frame", results["fsae_frame"])
    if not args.skip_large:
        table["frame"]["max_element_length"] = 36.0  # mm: ~10x the DOF count
        # one timed call each (a dense 7000-DOF eigen-solve takes minutes on 2 cores)
        results["fsae_frame_10x"] = bench(fe.frame_from_dict(table, "fsae-10x"), repeat=0, with_grad=args.large_grad)
        report("fsae_frame_10x", results["fsae_frame_10x"])
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=2))


def report(name, r):
    """Print one frame's timings."""
    print(f"{name}: {r['n_nodes']} nodes, {r['n_dof']} DOF")
    first = r["assembly_compile_s"]
    print(f"  assembly      {r['assembly_s'] * 1e3:9.1f} ms  (first call incl. compile {first:.2f} s)")
    print(f"  eigen-solve   {r['eigensolve_s'] * 1e3:9.1f} ms  (first call {r['eigensolve_compile_s']:.2f} s)")
    print(f"  torsion test  {r['torsion_s'] * 1e3:9.1f} ms", flush=True)
    if "f1_grad_s" in r:
        print(f"  f1 forward    {r['f1_forward_s'] * 1e3:9.1f} ms, gradient {r['f1_grad_s'] * 1e3:9.1f} ms "
              f"-> gradient / forward = {r['grad_over_forward']:.2f}", flush=True)


if __name__ == "__main__":
    main()
