"""A worked step-steer study on the chapter-6 car (experiments/studies/step_steer.toml): the
quickest yaw response to the 90 km/h step steer that keeps 98 % of the design's steady yaw
rate, over both anti-roll bars and the rear toe link's inner point height. Runs the study
(SLSQP on the forward-mode Jacobian of the 6-mode car's 5 s run), writes its outputs, and
draws the yaw-rate histories of the design and the optimum (the objectives' own runs).

    python experiments/step_steer_study.py                  # results/step_steer/

The first run compiles the study's program and the plain run (minutes each on two cores);
JAX's disk cache keeps them for the next run.
"""

import argparse
import json
from pathlib import Path

import numpy as np
from _util import use_disk_cache

import optimise

STUDY = Path(__file__).with_name("studies") / "step_steer.toml"


def _run_settings(study) -> dict:
    """The step steer's settings of the study's objective (speed, angle, rtol, ...)."""
    settings = dict(study.terms[0].spec.settings)
    return {k: settings[k] for k in ("speed_kmh", "angle_deg", "rise_s", "duration_s", "rtol") if k in settings}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/step_steer"))
    args = ap.parse_args()
    use_disk_cache()
    study = optimise.load_optimisation_study(STUDY)._replace(out=str(args.out))
    design = optimise.build_design(study)
    result = optimise.optimise_study(study, design=design, progress=lambda e: print(
        f"  {e['iteration']:3d}  objective {e['objective']:.6e}  |grad| {e['grad_norm']:.2e}  "
        + "  ".join(f"{v.name} {e[v.name]:.6g}" for v in study.variables)
        + "  " + "  ".join(f"{k} {x:.6g}" for k, x in e.items() if k.startswith("step_steer")), flush=True))
    files = optimise.write_outputs(result)
    settings = _run_settings(study)
    histories = {}
    for label, car in (("design", design.car), ("optimum", result.car)):
        ts, yaw_rate, ok = optimise.step_steer_run(car, **settings)
        histories[label] = {"t_s": np.asarray(ts).tolist(), "yaw_rate_deg_s": np.asarray(yaw_rate).tolist(),
                            "ok": bool(ok)}
    first = result.history[0]
    design_point = {"variables": {v.name: first[v.name] for v in study.variables},
                    "values": {k: first[k] for k in result.values}}
    report = {"study": str(STUDY), "settings": settings, "design": design_point,
              "optimum": {"variables": result.optimum, "values": result.values}, "converged": result.converged,
              "message": result.message, "iterations": result.iterations, "evaluations": result.evaluations,
              "wall_s": result.wall_s, "files": files}
    (args.out / "step_steer_summary.json").write_text(json.dumps(report, indent=2))
    (args.out / "step_steer_histories.json").write_text(json.dumps(histories))
    _figure(histories, report, args.out / "step_steer.png")
    print(json.dumps(report, indent=2))


def _figure(histories: dict, report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for label, colour in (("design", "C1"), ("optimum", "C0")):
        h, values = histories[label], report[label]["values"]
        ax.plot(h["t_s"], h["yaw_rate_deg_s"], color=colour,
                label=f"{label}: response {values['step_steer_response_time']:.4f} s, "
                      f"steady {values['step_steer_steady_yaw_rate']:.2f} deg/s")
    s = report["settings"]
    ax.set_xlabel("time (s)")
    ax.set_ylabel("yaw rate (deg/s)")
    ax.set_title(f"Step steer {s.get('angle_deg', 6.0):g} deg at {s.get('speed_kmh', 90.0):g} km/h, 6-mode car")
    ax.set_xlim(0.0, 2.0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    main()
