"""Why neglecting S c and S b matters more here than in the thesis (docs/analysis.md,
Table 7.2): the library car's step steer of Table 7.2 (90 km/h, 6 deg at the steering wheel)
with the steering ramped over 0.1, 0.2 and 0.4 s. S b carries the rack's rate into the
dependent velocities and S c the rack's acceleration (and the velocity products) into their
rates, so if these terms are what the two variants lose, their deviation from the complete
model must shrink as the step is spread out: about as the rack's largest rate (1 / rise) for
S b and its largest acceleration (1 / rise^2) for S c. Writes table_7_2_rise.json (default
results/table_7_2_rise)."""

import numpy as np
from _util import output_dir, use_disk_cache, write_json

from jaxveh.analysis import simplification_study
from jaxveh.analysis._simplifications import STEP_ANGLE_DEG, STEP_SPEED, STEP_START
from jaxveh.manoeuvre import step_steer
from jaxveh.vehicle import load_car

RISES_S = (0.1, 0.2, 0.4)
VARIANTS = ("neglect_sc", "neglect_sb")
CHANNELS = ("yaw_rate", "ay", "roll")


def main():
    out = output_dir("table_7_2_rise", __doc__)
    use_disk_cache()
    car = load_car(modes=6, form="library")
    report = {}
    for rise in RISES_S:
        m = step_steer(speed=STEP_SPEED, angle=float(np.deg2rad(STEP_ANGLE_DEG)), start=STEP_START, rise=rise,
                       duration=5.0)
        study = simplification_study(car, variants=VARIANTS, manoeuvre=m, repeats=1)
        report[f"{rise:g}"] = {v: {c: study["variants"][v]["relative_deviation"][c] for c in CHANNELS}
                               for v in VARIANTS}
        for v in VARIANTS:
            devs = ", ".join(f"{c} {report[f'{rise:g}'][v][c]:.2e}" for c in CHANNELS)
            print(f"rise {rise:g} s, {v}: relative deviation {devs}", flush=True)
    write_json(report, out / "table_7_2_rise.json")


if __name__ == "__main__":
    main()
