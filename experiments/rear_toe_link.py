"""Study (c) of issue 14 with two hard points under chassis deformation: the heights of the
rear toe link's inner point and of the upper wishbone's outer point (rear L z, H z) for zero
rear-axle roll steer at 0.05 g on the 50 m skid-pad with the outer rear wheel's camber per g
held at the rigid car's design value (experiments/studies/rear_toe_link.toml), solved on the
flexible 6-mode car and on the rigid car (the same study with modes = 0); each car's
Jacobian at the design against central differences; both conditions mapped over the two
heights; and each car evaluated at the other's optimum. Writes both optimisations (history
JSON/CSV, the optimum's car file), ``rear_toe_link.json`` and ``rear_toe_link.png`` (the
lines where each condition holds, on both cars: they cross at the optima).

    python experiments/rear_toe_link.py                  # results/rear_toe_link/

The first run compiles each car's forward-mode program (minutes each on two cores); JAX's
disk cache keeps them for the next run.
"""

import argparse
import json
from pathlib import Path

import numpy as np
from _util import jacobian_check, study_values, use_disk_cache

import optimise

STUDY = Path(__file__).with_name("studies") / "rear_toe_link.toml"
#: Points of the map per variable (inside the bounds).
MAP_POINTS = 7
#: Half-width of the map around the design (m).
MAP_HALF_WIDTH = 0.008


def _map(design, variables, grids) -> dict:
    """Every value of the study on the grid of both variables (rows: the first variable)."""
    points = [[study_values(design, {variables[0].name: float(a), variables[1].name: float(b)})
               for b in grids[1]] for a in grids[0]]
    return {q: [[p[q] for p in row] for row in points] for q in points[0][0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/rear_toe_link"))
    args = ap.parse_args()
    use_disk_cache()
    base = optimise.load_optimisation_study(STUDY)
    variables = base.variables
    initial = {v.name: v.initial for v in variables}
    grids = [np.linspace(max(v.lower, v.initial - MAP_HALF_WIDTH), min(v.upper, v.initial + MAP_HALF_WIDTH),
                         MAP_POINTS) for v in variables]
    report = {"study": str(STUDY), "variables": [{"name": v.name, "path": v.path} for v in variables],
              "initial": initial, "grids": [g.tolist() for g in grids],
              "conditions": {base.terms[0].spec.name: base.terms[0].target,
                             base.constraints[0].spec.name: base.constraints[0].bound}}
    designs = {}
    for label, modes in (("flexible", base.modes), ("rigid", 0)):
        study = base._replace(modes=modes, name=f"rear_toe_link_{label}", out=str(args.out / label))
        designs[label] = design = optimise.build_design(study)
        check = jacobian_check(design, initial)
        print(f"{label}: Jacobian vs central differences at the design, largest relative error "
              f"{check['max_relative_error']:.2e}", flush=True)
        result = optimise.optimise_study(study, design=design, progress=lambda e, label=label: print(
            f"  {label} {e['iteration']:3d}  objective {e['objective']:.3e}  "
            + "  ".join(f"{v.name} {e[v.name] * 1e3:.4f} mm" for v in variables), flush=True))
        files = optimise.write_outputs(result)
        report[label] = {"modes": modes, "optimum": result.optimum, "values": result.values,
                         "at_initial": study_values(design, initial), "converged": result.converged,
                         "message": result.message, "iterations": result.iterations,
                         "evaluations": result.evaluations, "wall_s": result.wall_s, "files": files,
                         "derivative_check": check, "map": _map(design, variables, grids)}
    report["flexible_at_rigid_optimum"] = study_values(designs["flexible"], report["rigid"]["optimum"])
    report["rigid_at_flexible_optimum"] = study_values(designs["rigid"], report["flexible"]["optimum"])
    report["optimum_difference_mm"] = {v.name: 1e3 * (report["flexible"]["optimum"][v.name]
                                                      - report["rigid"]["optimum"][v.name]) for v in variables}
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "rear_toe_link.json").write_text(json.dumps(report, indent=2))
    _figure(report, args.out / "rear_toe_link.png")
    print(json.dumps({k: v for k, v in report.items() if k not in ("flexible", "rigid", "grids")}
                     | {k: {kk: report[k][kk] for kk in ("optimum", "values", "at_initial", "converged", "message")}
                        for k in ("flexible", "rigid")}, indent=2))


def _figure(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (a, b) = (v["name"] for v in report["variables"])
    x, y = (np.asarray(g) * 1e3 for g in report["grids"])
    fig, axes = plt.subplots(1, 2, figsize=(11.5, 4.8))
    titles = {"rear_steer_gradient": "rear-axle steer gradient at 0.05 g (deg/g)",
              "camber_gradient": "outer rear wheel's camber gradient at 0.05 g (deg/g)"}
    for ax, (q, level) in zip(axes, report["conditions"].items()):
        flexible = np.asarray(report["flexible"]["map"][q])
        cs = ax.contourf(y, x, flexible, levels=15, cmap="RdBu_r")
        fig.colorbar(cs, ax=ax, label=f"{q}, flexible car")
        for label, style in (("flexible", "-"), ("rigid", "--")):
            values = np.asarray(report[label]["map"][q])
            ax.contour(y, x, values, levels=[level], colors="k", linestyles=style)
            opt = report[label]["optimum"]
            ax.plot(opt[b] * 1e3, opt[a] * 1e3, "*" if label == "flexible" else "o", ms=12, color="gold",
                    mec="k", label=f"optimum, {label}: {opt[a] * 1e3:.2f}, {opt[b] * 1e3:.2f} mm")
        ax.plot([report["initial"][b] * 1e3], [report["initial"][a] * 1e3], "kx", ms=9, label="design (Appendix B)")
        ax.plot([], [], "k-", label=f"{q} = {level:g}, flexible (6 modes)")
        ax.plot([], [], "k--", label=f"{q} = {level:g}, rigid")
        ax.set_xlabel(f"{b} (mm)")
        ax.set_ylabel(f"{a} (mm)")
        ax.set_title(titles.get(q, q), fontsize=10)
        ax.legend(fontsize=7, loc="lower right")
    fig.suptitle("Rear L z and H z: zero rear-axle roll steer with the rigid car's outer rear camber per g (R = 50 m)")
    fig.tight_layout()
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    main()
