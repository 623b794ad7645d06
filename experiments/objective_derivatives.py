"""Every objective of the library on the 6-mode car: its forward-mode derivatives with respect
to four design variables of different kinds (λ through the anti-roll bars, the first
chassis mode's stiffness multiplier µ_1 on a log scale, the front and rear toe links' inner
point heights) against central differences of the same compiled values, at the shipped design.
One study per shared computation (``optimise.SOURCES``: the skid-pad point, the load
transfer, the linearisation's first mode, the steering and road responses, the preview
driver, the step steer's time run, the corner kinematics), each compiled once; the
objectives that take a corner use their default one. Writes
``objective_derivatives.json`` (per objective: the Jacobian row, the central differences,
the largest error relative to the row's largest entry).

    python experiments/objective_derivatives.py                          # every source (hours on 2 cores)
    python experiments/objective_derivatives.py --sources linear preview # some of them

Each source's program compiles for minutes on two cores (the forward-mode derivatives of
the car's steady state, linearisation or time run); JAX's disk cache keeps most of them.
"""

import argparse
import json
import time
from pathlib import Path

from _util import jacobian_check, use_disk_cache

import optimise
from optimise import OBJECTIVES, SOURCES, objective_spec
from optimise._optimise_study import Bound, DesignVariable, OptimisationStudy, Term

#: The design variables (name, path, bounds, initial value at the shipped design, log scale).
VARIABLES = (
    DesignVariable("lambda", "lambda", 0.3, 0.7, 0.5),
    DesignVariable("mu_1", "chassis.stiffness_scale[0]", 0.1, 10.0, 1.0, log=True, units="1"),
    DesignVariable("front_L_z", "vehicle.hard_points_front.points[7, 2]", 0.295, 0.335, 0.315, units="m"),
    DesignVariable("rear_L_z", "vehicle.hard_points_rear.points[7, 2]", 0.295, 0.335, 0.315, units="m"),
)
#: Central-difference step in the unconstrained variables.
STEP = 1e-4


def source_study(source: str, modes: int) -> OptimisationStudy:
    """A study evaluating every objective of ``source`` (default settings) at once: the
    first as the objective, the others as bounds never active."""
    specs = [objective_spec(name) for name, objective in OBJECTIVES.items() if objective.source == source]
    return OptimisationStudy(name=f"derivatives_{source}", variables=VARIABLES,
                             terms=(Term(specs[0], "minimise", None),),
                             constraints=tuple(Bound(s, "<=", 1e30) for s in specs[1:]), modes=modes)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sources", nargs="+", default=list(SOURCES), choices=list(SOURCES))
    ap.add_argument("--modes", type=int, default=6)
    ap.add_argument("--out", type=Path, default=Path("results/objective_derivatives"))
    args = ap.parse_args()
    use_disk_cache()
    args.out.mkdir(parents=True, exist_ok=True)
    path = args.out / "objective_derivatives.json"
    report = json.loads(path.read_text()) if path.exists() else {}
    report.update(modes=args.modes, step_z=STEP, variables=[v._asdict() for v in VARIABLES])
    initial = {v.name: v.initial for v in VARIABLES}
    for source in args.sources:
        start = time.perf_counter()
        design = optimise.build_design(source_study(source, args.modes))
        check = jacobian_check(design, initial, STEP)
        wall = time.perf_counter() - start
        for i, spec in enumerate(design.specs):
            row, fd = check["jacobian"][i], check["central_differences"][i]
            error = max(abs(a - b) for a, b in zip(row, fd)) / (max(abs(c) for c in fd) or 1.0)
            report.setdefault("objectives", {})[spec.name] = {
                "source": source, "units": OBJECTIVES[spec.name].units, "forward_mode": row,
                "central_differences": fd, "max_relative_error": error}
            print(f"{source:18s} {spec.name:28s} " + "  ".join(f"{a:+.6e}" for a in row)
                  + f"   error {error:.1e}", flush=True)
        report.setdefault("wall_s", {})[source] = wall
        path.write_text(json.dumps(report, indent=2))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
