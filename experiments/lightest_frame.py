"""Study (d) of issue 14 on the chapter-6 car: the lightest chassis frame
(experiments/studies/lightest_frame.toml: four tube-size factors through the FE model and
its modal reduction into the 6-mode car) that keeps χ and ku near the rigid car's and the
first coupled chassis mode above a target. Prints the rigid car's references and the
shipped frame's values, checks the chain's forward-mode Jacobian against central
differences at the shipped frame, optimises, and writes the optimisation's outputs (history
JSON/CSV, the optimum's car and frame files), ``lightest_frame_summary.json`` and
``lightest_frame.png``.

    python experiments/lightest_frame.py                 # results/lightest_frame/

The first run compiles the study's program (the 6-mode car's steady states and its
linearisation, differentiated in forward mode: many minutes on two cores).
"""

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from _util import jacobian_check, use_disk_cache  # noqa: E402

import jaxveh.fe as fe  # noqa: E402
import optimise  # noqa: E402

STUDY = Path(__file__).with_name("studies") / "lightest_frame.toml"


def _frame_summary(frame) -> dict:
    return {"mass_kg": float(fe.frame_mass(frame)),
            "torsional_stiffness_nm_per_deg": float(fe.torsion_test(frame).stiffness_nm_per_deg),
            "free_free_hz": [float(f) for f in fe.chassis_modes(frame, 6)[0]],
            "sections_mm": {n: {"diameter": float(s.diameter) * 1e3, "thickness": float(s.thickness) * 1e3}
                            for n, s in zip(frame.section_names, frame.sections)}}


def _plot(path: Path, result, shipped, optimum) -> None:
    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(11, 4.2))
    history = result.history
    it = [e["iteration"] for e in history]
    ax1.plot(it, [e["chassis_mass"] for e in history], "k-", label="frame mass (kg)")
    ax1.set_xlabel("iteration")
    ax1.set_ylabel("frame mass (kg)")
    twin = ax1.twinx()
    for j, c in enumerate(result.constraints):
        twin.plot(it, [e[f"violation_{j}"] for e in history], lw=0.8, label=f"{c['name']} {c['kind']}")
    twin.axhline(0.0, color="0.6", lw=0.5)
    twin.set_ylabel("constraint violation (scaled; feasible <= 0)")
    twin.legend(fontsize=7, loc="upper right")
    ax1.set_title("(a) optimisation history")
    names = list(shipped["sections_mm"])
    x = np.arange(len(names))
    ax2.bar(x - 0.2, [shipped["sections_mm"][n]["diameter"] for n in names], 0.4, label="shipped")
    ax2.bar(x + 0.2, [optimum["sections_mm"][n]["diameter"] for n in names], 0.4, label="lightest feasible")
    ax2.set_xticks(x, names, rotation=60, ha="right", fontsize=7)
    ax2.set_ylabel("tube diameter (mm)")
    ax2.set_title(f"(b) {shipped['mass_kg']:.1f} kg -> {optimum['mass_kg']:.1f} kg")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    plt.close(fig)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--study", type=Path, default=STUDY)
    ap.add_argument("--out", type=Path, default=Path("results/lightest_frame"))
    args = ap.parse_args()
    use_disk_cache()
    study = optimise.load_optimisation_study(args.study, out=args.out)
    design = optimise.build_design(study)
    labels = [s.name for s in design.specs]
    initial = {v.name: v.initial for v in study.variables}
    at_initial = dict(zip(labels, (float(x) for x in design.evaluate(np.asarray(design.problem.to_z(initial)))[0])))
    rigid = {s.name: v for s, v in design.rigid_values.items()}
    print(f"rigid car: {rigid}\nshipped frame (initial design): {at_initial}", flush=True)
    check = jacobian_check(design, initial)
    print(f"Jacobian vs central differences at the shipped frame: largest relative error "
          f"{check['max_relative_error']:.2e}", flush=True)
    names = [v.name for v in study.variables]
    result = optimise.optimise_study(study, design=design, throw=False, progress=lambda e: print(
        f"  {e['iteration']:3d} outer {e['outer']}  mass {e['chassis_mass']:.3f} kg  merit {e['merit']:.4e}  "
        f"|grad| {e['grad_norm']:.2e}  " + "  ".join(f"{n} {e[n]:.4f}" for n in names + labels[1:]), flush=True))
    files = optimise.write_outputs(result)
    shipped = _frame_summary(optimise.load_car_frame(study.vehicle))
    optimum = _frame_summary(fe.load_frame(files["frame"])) if "frame" in files else None
    summary = {"study": str(args.study), "rigid": rigid, "shipped_values": at_initial, "optimum": result.optimum,
               "optimum_values": result.values, "constraints": result.constraints, "converged": result.converged,
               "message": result.message, "iterations": result.iterations, "evaluations": result.evaluations,
               "wall_s": result.wall_s, "derivative_check": check, "shipped_frame": shipped,
               "optimum_frame": optimum, "files": files}
    (args.out / "lightest_frame_summary.json").write_text(json.dumps(summary, indent=2))
    if optimum is not None:
        _plot(args.out / "lightest_frame.png", result, shipped, optimum)
    print(json.dumps({k: summary[k] for k in ("rigid", "shipped_values", "optimum", "optimum_values", "converged",
                                              "message")}, indent=2))


if __name__ == "__main__":
    main()
