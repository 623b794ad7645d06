"""Study (b) of issue 14 on the chapter-6 car: the roll stiffness distribution λ (set through
the anti-roll bars) that gives a target understeer gradient at 0.05 g on the 50 m skid-pad,
on the flexible 6-mode car (experiments/studies/roll_balance.toml) and on the rigid car
(the same study with modes = 0); writes both optimisations (history JSON/CSV, the optimum's
car file), a comparison JSON and a figure of ku against λ with both optima marked.

    python experiments/roll_balance.py                      # results/roll_balance/
    python experiments/roll_balance.py --scan-only          # ku over λ only (choosing a target)

The first run compiles each car's forward-mode program (minutes each on two cores); JAX's
disk cache keeps them for the next run.
"""

import argparse
import json
import time
from pathlib import Path

import numpy as np
from _util import use_disk_cache

import optimise

STUDY = Path(__file__).with_name("studies") / "roll_balance.toml"
#: λ of the scan (the bounds' interior: the design variable stays strictly inside them).
SCAN = np.linspace(0.3005, 0.6995, 17)


def _scan(design) -> list:
    ku = []
    for lam in SCAN:
        values, _ = design.evaluate(np.asarray(design.problem.to_z({"lambda": float(lam)})))
        ku.append(float(values[0]))
    return ku


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/roll_balance"))
    ap.add_argument("--scan-only", action="store_true", help="only ku over λ on both cars")
    args = ap.parse_args()
    use_disk_cache()
    base = optimise.load_optimisation_study(STUDY)
    report = {"study": str(STUDY), "target_deg_per_g": base.terms[0].target, "ay_g": dict(base.terms[0].spec.settings)
              ["ay_g"], "radius_m": dict(base.terms[0].spec.settings)["radius"], "scan_lambda": SCAN.tolist()}
    for label, modes in (("flexible", base.modes), ("rigid", 0)):
        study = base._replace(modes=modes, name=f"roll_balance_{label}", out=str(args.out / label))
        start = time.perf_counter()
        design = optimise.build_design(study)
        report[f"scan_ku_{label}"] = _scan(design)
        report[f"scan_wall_s_{label}"] = time.perf_counter() - start
        print(f"{label} ({modes} modes): ku over λ = {np.round(report[f'scan_ku_{label}'], 4).tolist()} "
              f"({report[f'scan_wall_s_{label}']:.0f} s with compilation)", flush=True)
        if args.scan_only:
            continue
        result = optimise.optimise_study(study, design=design, progress=lambda e: print(
            f"  {e['iteration']:3d}  lambda {e['lambda']:.8f}  objective {e['objective']:.3e}  |grad| "
            f"{e['grad_norm']:.2e}", flush=True))
        files = optimise.write_outputs(result)
        report[label] = {"modes": modes, "lambda": result.optimum["lambda"],
                         "understeer_gradient_deg_per_g": result.values["understeer_gradient"],
                         "converged": result.converged, "message": result.message, "iterations": result.iterations,
                         "evaluations": result.evaluations, "wall_s": result.wall_s,
                         "arb_rates_nm_per_rad": np.asarray(result.car.params.arb_rates).tolist(), "files": files}
    if not args.scan_only:
        report["lambda_difference"] = report["flexible"]["lambda"] - report["rigid"]["lambda"]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "roll_balance.json").write_text(json.dumps(report, indent=2))
    _figure(report, args.out / "roll_balance.png")
    print(json.dumps({k: v for k, v in report.items() if not k.startswith("scan")}, indent=2))


def _figure(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    for label, colour in (("flexible", "C0"), ("rigid", "C1")):
        ax.plot(report["scan_lambda"], report[f"scan_ku_{label}"], "-o", ms=3, color=colour,
                label=f"{label} ({6 if label == 'flexible' else 0} modes)")
        if label in report:
            r = report[label]
            ax.plot([r["lambda"]], [r["understeer_gradient_deg_per_g"]], "*", ms=14, color=colour,
                    label=f"{'optimum' if r['converged'] else 'last iterate (not converged)'}, {label}: "
                          f"λ = {r['lambda']:.4f}")
    ax.axhline(report["target_deg_per_g"], color="k", lw=0.8, ls="--", label="target")
    ax.set_xlabel("roll stiffness distribution λ = kF / (kF + kR)")
    ax.set_ylabel(f"understeer gradient at {report['ay_g']:g} g (deg/g)")
    ax.set_title(f"Roll balance for a target ku, R = {report['radius_m']:g} m")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    main()
