"""Study (c) of issue 14 on the chapter-6 car: the inner track-rod heights (front and rear
L z) for zero rear roll steer and the rigid car's understeer gradient at 0.05 g on the 50 m
skid-pad (experiments/studies/hard_points.toml), solved on the flexible 6-mode car and on
the rigid car (the same study with modes = 0); then each car evaluated at the other's
optimum: what a design done on the rigid model gives on the flexible car; each car's
Jacobian at the design is checked against central differences. Writes both
optimisations (history JSON/CSV, the optimum's car file), ``hard_points.json`` and
``hard_points.png`` (the optimisers' paths in the hard-point plane; the objectives at the
design, at each optimum and crossed).

    python experiments/hard_points.py                    # results/hard_points/

The first run compiles each car's forward-mode program (minutes each on two cores); JAX's
disk cache keeps them for the next run.
"""

import argparse
import json
import os
from pathlib import Path

import jax
import numpy as np

import optimise

STUDY = Path(__file__).with_name("studies") / "hard_points.toml"


def _cache() -> None:
    folder = Path(os.environ.get("JAXVEH_CACHE", Path.home() / ".cache" / "jaxveh" / "jax"))
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)


def _values(design, point: dict) -> dict:
    values, _ = design.evaluate(np.asarray(design.problem.to_z(point)))
    return {s.name: float(v) for s, v in zip(design.specs, values)}


def _derivative_check(design, point: dict, step: float = 1e-4) -> dict:
    """The study's forward-mode Jacobian (per unconstrained variable) against central
    differences of the same compiled values at ``point``: the largest relative error."""
    z0 = np.asarray(design.problem.to_z(point))
    _, jac = design.evaluate(z0)
    fd = np.zeros_like(jac)
    for k in range(z0.size):
        dz = np.zeros_like(z0)
        dz[k] = step
        fd[:, k] = (design.evaluate(z0 + dz)[0] - design.evaluate(z0 - dz)[0]) / (2.0 * step)
    return {"jacobian": jac.tolist(), "central_differences": fd.tolist(), "step_z": step,
            "max_relative_error": float(np.max(np.abs(jac - fd)) / np.max(np.abs(fd)))}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/hard_points"))
    args = ap.parse_args()
    _cache()
    base = optimise.load_optimisation_study(STUDY)
    initial = {v.name: v.initial for v in base.variables}
    report = {"study": str(STUDY), "variables": {v.name: v.path for v in base.variables},
              "targets": {t.spec.name: t.target for t in base.terms}, "initial": initial}
    designs = {}
    for label, modes in (("flexible", base.modes), ("rigid", 0)):
        study = base._replace(modes=modes, name=f"hard_points_{label}", out=str(args.out / label))
        designs[label] = optimise.build_design(study)
        check = _derivative_check(designs[label], initial)
        print(f"{label}: Jacobian vs central differences at the design, largest relative error "
              f"{check['max_relative_error']:.2e}", flush=True)
        result = optimise.optimise_study(study, design=designs[label], progress=lambda e, label=label: print(
            f"  {label} {e['iteration']:3d}  objective {e['objective']:.3e}  |grad| {e['grad_norm']:.2e}  "
            + "  ".join(f"{k} {e[k] * 1e3:.3f} mm" for k in initial), flush=True))
        files = optimise.write_outputs(result)
        report[label] = {"modes": modes, "optimum": result.optimum, "values": result.values,
                         "at_initial": _values(designs[label], initial), "converged": result.converged,
                         "message": result.message, "iterations": result.iterations,
                         "evaluations": result.evaluations, "wall_s": result.wall_s, "files": files,
                         "derivative_check": check,
                         "path": [[e[k] for k in initial] for e in result.history]}
    report["flexible_at_rigid_optimum"] = _values(designs["flexible"], report["rigid"]["optimum"])
    report["rigid_at_flexible_optimum"] = _values(designs["rigid"], report["flexible"]["optimum"])
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "hard_points.json").write_text(json.dumps(report, indent=2))
    _figure(report, args.out / "hard_points.png")
    print(json.dumps({k: v for k, v in report.items() if k not in ("flexible", "rigid")}
                     | {k: {kk: report[k][kk] for kk in ("optimum", "values", "at_initial", "converged")}
                        for k in ("flexible", "rigid")}, indent=2))


def _figure(report: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = list(report["initial"])
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(11.0, 4.4))
    for label, colour in (("flexible", "C0"), ("rigid", "C1")):
        p = np.asarray(report[label]["path"]) * 1e3
        ax.plot(p[:, 0], p[:, 1], "-o", ms=3, color=colour, label=f"{label}: L-BFGS path")
        ax.plot(p[-1, 0], p[-1, 1], "*", ms=14, color=colour)
    ax.plot(*(np.asarray([report["initial"][n] for n in names]) * 1e3), "ks", label="design (Appendix B)")
    ax.set_xlabel(f"{names[0]} (mm)")
    ax.set_ylabel(f"{names[1]} (mm)")
    ax.set_title("inner track-rod heights")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    rows = [("design, flexible", report["flexible"]["at_initial"]), ("design, rigid", report["rigid"]["at_initial"]),
            ("flexible optimum", report["flexible"]["values"]), ("rigid optimum", report["rigid"]["values"]),
            ("flexible car at the rigid optimum", report["flexible_at_rigid_optimum"])]
    keys = list(report["targets"])
    x = np.arange(len(keys))
    for i, (label, values) in enumerate(rows):
        bx.bar(x + (i - 2) * 0.16, [values[k] for k in keys], 0.16, label=label)
    for j, k in enumerate(keys):
        bx.plot([j - 0.45, j + 0.45], [report["targets"][k]] * 2, "k--", lw=0.9)
    bx.set_xticks(x, [f"{k} (deg/g)" for k in keys])
    bx.axhline(0.0, color="k", lw=0.5)
    bx.set_title("objectives at 0.05 g, R = 50 m (dashed: targets)")
    bx.grid(alpha=0.3, axis="y")
    bx.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=150)


if __name__ == "__main__":
    main()
