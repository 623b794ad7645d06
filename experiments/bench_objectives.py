"""Objective + gradient benchmark on the 6-mode car (issue 14): the cost of an objective's
derivatives over the objective alone, for the objectives of a study file: by default the
steady-state metrics of experiments/studies/hard_points.toml (one skid-pad point: the
understeer and rear steer gradients); ``--study experiments/studies/step_steer.toml`` the
step-steer metrics of the fast car's time run.

Measures (best of ``--repeats`` calls after compilation, one process): the objectives'
values alone (``optimise.objective_values`` under ``jax.jit``), the values with their
forward-mode Jacobian with respect to the study's design variables (what ``jaxveh
optimise`` calls every iteration: ``optimise.build_design``), and with ``--reverse`` the
reverse-mode gradient of the first objective with respect to every floating-point leaf of
``CarParams`` (``jax.grad`` through the Newton solve by the implicit function theorem),
each with its compile time (the time runs' reverse mode: ``objective_values(...,
reverse=True)``).

    python experiments/bench_objectives.py [--study FILE] [--reverse] [--json]
"""

import argparse
import json
import os
import time
from pathlib import Path

import equinox as eqx
import jax
import numpy as np

import optimise
from jaxveh import run_time_checks_off

STUDY = Path(__file__).with_name("studies") / "hard_points.toml"


def _timed(fn, *args):
    start = time.perf_counter()
    out = jax.block_until_ready(fn(*args))
    return out, time.perf_counter() - start


def _best(fn, *args, repeats: int = 5) -> float:
    return min(_timed(fn, *args)[1] for _ in range(repeats))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", type=Path, default=STUDY, help="the study file (default: %(default)s)")
    ap.add_argument("--reverse", action="store_true", help="also the reverse-mode gradient w.r.t. every leaf")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", action="store_true", help="one JSON object on stdout")
    args = ap.parse_args()
    folder = Path(os.environ.get("JAXVEH_CACHE", Path.home() / ".cache" / "jaxveh" / "jax"))
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
    log = (lambda s: print(s, flush=True)) if not args.json else (lambda s: None)

    study = optimise.load_optimisation_study(args.study)
    design = optimise.build_design(study)
    initial = {v.name: v.initial for v in study.variables}
    z0 = np.asarray(design.problem.to_z(initial))
    car = optimise.design_car(design, initial)
    specs = design.specs
    res = {"study": str(args.study), "modes": study.modes, "objectives": [s.name for s in specs],
           "variables": list(initial)}

    forward = eqx.filter_jit(lambda c: optimise.objective_values(c, specs, design.prepared))
    with run_time_checks_off():
        values, res["forward_compile_s"] = _timed(forward, car)
        res["forward_s"] = _best(forward, car, repeats=args.repeats)
    log(f"values {np.asarray(values)}: {res['forward_s'] * 1e3:.1f} ms (compile {res['forward_compile_s']:.0f} s)")

    (v2, jac), res["jacobian_first_call_s"] = _timed(design.evaluate, z0)
    res["jacobian_s"] = _best(design.evaluate, z0, repeats=args.repeats)
    res["jacobian_over_forward"] = res["jacobian_s"] / res["forward_s"]
    res["values_agree"] = float(np.max(np.abs(np.asarray(v2) - np.asarray(values))))
    log(f"values + Jacobian ({len(initial)} variables, forward mode): {res['jacobian_s'] * 1e3:.1f} ms = "
        f"{res['jacobian_over_forward']:.2f} x forward (first call {res['jacobian_first_call_s']:.0f} s)")

    if args.reverse:
        first = specs[0]

        def objective(params):
            moved = eqx.tree_at(lambda c: c.params, car, params)
            return optimise.objective_values(moved, (first,), design.prepared, reverse=True)[0]

        grad = eqx.filter_jit(eqx.filter_value_and_grad(objective))
        with run_time_checks_off():
            (_, g), res["reverse_compile_s"] = _timed(grad, car.params)
            res["reverse_s"] = _best(grad, car.params, repeats=args.repeats)
        leaves = [x for x in jax.tree.leaves(g) if eqx.is_inexact_array(x)]
        res["reverse_leaves"] = int(sum(np.size(x) for x in leaves))
        res["reverse_finite"] = bool(all(np.all(np.isfinite(x)) for x in leaves))
        res["reverse_over_forward"] = res["reverse_s"] / res["forward_s"]
        log(f"reverse-mode gradient of {first.name} w.r.t. {res['reverse_leaves']} numbers: "
            f"{res['reverse_s'] * 1e3:.1f} ms = {res['reverse_over_forward']:.2f} x forward "
            f"(compile {res['reverse_compile_s']:.0f} s)")
    if args.json:
        print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
