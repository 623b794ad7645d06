"""Solver choice for the car's manoeuvres (issue 11, item 4): explicit Tsit5 against IMEX
KenCarp5 and KenCarp4 (the car's linearisation implicit, taken again in time segments, one
factorisation per step: jaxveh.manoeuvre._imex) and fully implicit Kvaerno5 (Optimistix's Newton), on the fast
6-mode car's 5 s step steer at 90 km/h, at the
thesis's tolerances (0.5 % and 0.1 %) and at 1e-4, against an rtol 1e-9 Tsit5 reference:
steps, wall time after compilation, and the worst relative error of yaw rate, ay, roll and
the modal coordinates (each over its largest value).

    .venv/bin/python experiments/solver_choice.py --json
    .venv/bin/python experiments/solver_choice.py --solvers tsit5 kencarp5 --out results/solver_choice
    .venv/bin/python experiments/solver_choice.py --solvers tsit5 kencarp5 kencarp4 --tolerances 1e-4 1e-5 1e-6
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

import jaxveh  # noqa: F401  (float64)
from jaxveh.manoeuvre import SOLVERS, simulate, step_steer
from jaxveh.vehicle import load_car

TOLERANCES = (5e-3, 1e-3, 1e-4)
CHANNELS = ("yaw_rate", "ay", "roll", "modes")


def errors(run, reference) -> dict:
    """Worst |run - reference| over max |reference| per channel."""
    out = {}
    for k in CHANNELS:
        x, y = np.asarray(run.channels[k]), np.asarray(reference.channels[k])
        out[k] = float(np.max(np.abs(x - y)) / np.max(np.abs(y)))
    return out


def compare(solvers, tolerances, log) -> dict:
    car = load_car(modes=6)
    m = step_steer(angle=np.deg2rad(6.0))
    reference = simulate(car, m, rtol=1e-9)
    res = {"reference": {"solver": "tsit5", "rtol": 1e-9, "steps": int(reference.steps)}, "runs": []}
    for solver in solvers:
        t0 = time.perf_counter()
        simulate(car, m, solver=solver, rtol=tolerances[0])
        first = time.perf_counter() - t0
        for rtol in tolerances:
            run = simulate(car, m, solver=solver, rtol=rtol)
            row = {"solver": solver, "rtol": rtol, "steps": int(run.steps), "rejected_steps": int(run.rejected_steps),
                   "wall_s": run.wall_s, "first_call_s": first, "errors": errors(run, reference)}
            res["runs"].append(row)
            log(f"{solver:9s} rtol {rtol:7.0e}: {row['steps']:5d} steps ({row['rejected_steps']} rejected), "
                f"{row['wall_s']:6.2f} s, worst error {max(row['errors'].values()):.1e} "
                f"(yaw rate {row['errors']['yaw_rate']:.1e})")
    return res


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--solvers", nargs="+", default=list(SOLVERS), choices=SOLVERS)
    parser.add_argument("--tolerances", nargs="+", type=float, default=list(TOLERANCES), help="rtol values")
    parser.add_argument("--json", action="store_true", help="print one JSON object on stdout (progress on stderr)")
    parser.add_argument("--out", type=Path, help="also write solver_choice.json into this folder")
    args = parser.parse_args()

    def log(msg):
        print(msg, file=sys.stderr if args.json else sys.stdout, flush=True)

    res = compare(args.solvers, args.tolerances, log)
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "solver_choice.json").write_text(json.dumps(res, indent=2))
    if args.json:
        print(json.dumps(res))


if __name__ == "__main__":
    main()
