"""Study (c) of issue 14 on the chapter-6 car: the rear toe link's inner point height (rear
L z) for zero rear-axle roll steer at 0.05 g on the 50 m skid-pad
(experiments/studies/hard_points.toml), solved on the flexible 6-mode car and on the rigid
car (the same study with modes = 0); each car's Jacobian at the design against central
differences; a scan of both objectives over the bounds; and each car evaluated at the
other's optimum (what a hard point chosen on the rigid model gives on the flexible car).
Writes both optimisations (history JSON/CSV, the optimum's car file), ``hard_points.json``
and ``hard_points.png``.

    python experiments/hard_points.py                    # results/hard_points/

The first run compiles each car's forward-mode program (minutes each on two cores); JAX's
disk cache keeps them for the next run.
"""

import argparse
import json
from pathlib import Path

import numpy as np
from _util import jacobian_check, study_values, use_disk_cache

import optimise

STUDY = Path(__file__).with_name("studies") / "hard_points.toml"
#: Points of the scan over the variable's bounds.
SCAN_POINTS = 11


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/hard_points"))
    args = ap.parse_args()
    use_disk_cache()
    base = optimise.load_optimisation_study(STUDY)
    (var,) = base.variables
    initial = {var.name: var.initial}
    pad = 1e-3 * (var.upper - var.lower)
    scan = np.linspace(var.lower + pad, var.upper - pad, SCAN_POINTS)
    report = {"study": str(STUDY), "variable": {"name": var.name, "path": var.path},
              "target": {base.terms[0].spec.name: base.terms[0].target}, "initial": initial, "scan": scan.tolist()}
    designs = {}
    for label, modes in (("flexible", base.modes), ("rigid", 0)):
        study = base._replace(modes=modes, name=f"hard_points_{label}", out=str(args.out / label))
        designs[label] = design = optimise.build_design(study)
        check = jacobian_check(design, initial)
        print(f"{label}: Jacobian vs central differences at the design, largest relative error "
              f"{check['max_relative_error']:.2e}", flush=True)
        result = optimise.optimise_study(study, design=design, progress=lambda e, label=label: print(
            f"  {label} {e['iteration']:3d}  objective {e['objective']:.3e}  |grad| {e['grad_norm']:.2e}  "
            f"{var.name} {e[var.name] * 1e3:.4f} mm", flush=True))
        files = optimise.write_outputs(result)
        report[label] = {"modes": modes, "optimum": result.optimum, "values": result.values,
                         "at_initial": study_values(design, initial), "converged": result.converged,
                         "message": result.message, "iterations": result.iterations,
                         "evaluations": result.evaluations, "wall_s": result.wall_s, "files": files,
                         "derivative_check": check,
                         "scan": [study_values(design, {var.name: float(x)}) for x in scan]}
    report["flexible_at_rigid_optimum"] = study_values(designs["flexible"], report["rigid"]["optimum"])
    report["rigid_at_flexible_optimum"] = study_values(designs["rigid"], report["flexible"]["optimum"])
    report["optimum_difference_mm"] = 1e3 * (report["flexible"]["optimum"][var.name]
                                             - report["rigid"]["optimum"][var.name])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "hard_points.json").write_text(json.dumps(report, indent=2))
    _figure(report, args.out / "hard_points.png")
    print(json.dumps({k: v for k, v in report.items() if k not in ("flexible", "rigid", "scan")}
                     | {k: {kk: report[k][kk] for kk in ("optimum", "values", "at_initial", "converged", "message")}
                        for k in ("flexible", "rigid")}, indent=2))


def _figure(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    name = report["variable"]["name"]
    x = np.asarray(report["scan"]) * 1e3
    quantities = list(report["flexible"]["values"])
    fig, axes = plt.subplots(1, len(quantities), figsize=(5.4 * len(quantities), 4.2), squeeze=False)
    for ax, q in zip(axes[0], quantities):
        for label, colour in (("flexible", "C0"), ("rigid", "C1")):
            r = report[label]
            ax.plot(x, [p[q] for p in r["scan"]], "-o", ms=3, color=colour, label=f"{label} ({r['modes']} modes)")
            ax.plot([r["optimum"][name] * 1e3], [r["values"][q]], "*", ms=14, color=colour,
                    label=f"optimum, {label}: {r['optimum'][name] * 1e3:.2f} mm")
        if q in report["target"]:
            ax.axhline(report["target"][q], color="k", lw=0.8, ls="--", label="target")
        ax.axvline(report["initial"][name] * 1e3, color="grey", lw=0.8, ls=":", label="design (Appendix B)")
        ax.set_xlabel(f"{name} (mm)")
        ax.set_ylabel(f"{q} at 0.05 g (deg/g)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Rear toe-link inner point height for zero rear-axle roll steer, R = 50 m")
    fig.tight_layout()
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    main()
