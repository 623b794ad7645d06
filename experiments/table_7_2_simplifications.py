"""Table 7.2 and section 7.6: the library car's 5 s step steer at 90 km/h (Fig. 7.6's) with the
complete flexible model (6 modes) and each simplification of the equations of motion —
constant mass matrix, neglected Gr/Ge, neglected S c ("vector c"), neglected S b, neglected
centre-of-mass shift, projection matrices held for 5 steps — beside the rigid chassis: steps,
wall time after compilation, and each channel's largest deviation from the complete model
(absolute, relative to the channel's largest value, and as a share of what the flexibility
itself changes). Writes table_7_2.json, table_7_2.md and table_7_2.png."""

import jax
from _util import output_dir, write_json

from jaxveh.analysis import simplification_study
from jaxveh.plots import plot_simplifications, save
from jaxveh.vehicle import load_car

#: The thesis's Table 7.2 (Fortran, 2.4 GHz processor, rtol 1e-4), CPU seconds of the 5 s step steer.
THESIS_STEP_STEER_S = {"rigid": 0.7, "complete": 0.9, "constant_mass": 0.8, "neglect_gyroscopic": 0.8,
                       "neglect_sc": 0.6}
CHANNELS = ("yaw_rate", "ay", "roll", "sideslip", "fz", "modes")


def _markdown(report: dict) -> str:
    rows = report["variants"]
    head = "| variant | steps | rejected | wall s | thesis CPU s | " + " | ".join(
        f"{c} rel. dev." for c in CHANNELS) + " |"
    lines = [head, "|" + "---|" * (5 + len(CHANNELS))]
    for name, row in rows.items():
        dev = row.get("relative_deviation", {})
        cells = " | ".join(f"{dev[c]:.1e}" if c in dev else "-" for c in CHANNELS)
        thesis = THESIS_STEP_STEER_S.get(name)
        lines.append(f"| {name} | {row['steps']} | {row['rejected_steps']} | {row['wall_s']:.2f} | "
                     f"{'-' if thesis is None else thesis} | {cells} |")
    effect = report["flexibility_effect"]
    lines += ["", "Share of the flexibility's own effect (max |variant - complete| / max |complete - rigid|):", "",
              "| variant | " + " | ".join(c for c in CHANNELS if c in effect) + " |",
              "|---|" + "---|" * sum(c in effect for c in CHANNELS)]
    for name, row in rows.items():
        share = row.get("share_of_flexibility_effect")
        if share is not None:
            lines.append(f"| {name} | " + " | ".join(f"{share[c]:.1e}" for c in CHANNELS if c in effect) + " |")
    return "\n".join(lines) + "\n"


def main():
    out = output_dir("table_7_2", __doc__)
    jax.config.update("jax_compilation_cache_dir", str(out / "jax-cache"))
    done = {}

    def progress(name, row):  # each finished row at once: the whole table takes long to compile
        done[name] = row
        write_json(done, out / "table_7_2_partial.json")
        print(f"{name}: {row['steps']} steps, {row['wall_s']:.2f} s", flush=True)

    report = simplification_study(load_car(modes=6, form="library"), load_car(modes=0, form="library"),
                                  on_variant=progress)
    report["thesis_cpu_s"] = THESIS_STEP_STEER_S
    write_json(report, out / "table_7_2.json")
    (out / "table_7_2.md").write_text(_markdown(report))
    save(plot_simplifications(report, CHANNELS), out / "table_7_2.png")
    print(_markdown(report))


if __name__ == "__main__":
    main()
