"""Thesis Figs. 6.11 (bump test) and 6.12 (steering test), plus the roll test, on the
assembled car: rigid chassis, 6-mode flexible chassis balanced at every rig point, and the
6-mode chassis held as loaded at rest.

    .venv/bin/python experiments/fig_6_11_6_12_rigs.py --out results/fig_6_11_6_12

Writes bump_<variant>.png / .json, steer_<variant>.*, roll_<variant>.* and summary.json with
the values at +-25 mm and +-90 deg beside the thesis's figures (read off the plots) and the
time each rig took (compilation included, then a second run).
"""

import time

import numpy as np
from _util import output_dir, write_json

from jaxveh import plots, vehicle

#: Read off the thesis's figures (Adams/Car and its 14-DOF model agree there): ranges only,
#: the figures have no tabulated values.
THESIS = {
    "fig_6_11": "front bump over about +-30 mm: Fz about 700-1100 N, camber within +-2 deg, toe 0.01-0.09 deg, "
                "total track 1192-1204 mm",
    "fig_6_12": "steering +-200 deg: road-wheel angle about -40..+55 deg, camber -2..4 deg, track 1160-1210 mm, "
                "scrub radius 29-30 mm",
}
TRAVEL_MM = np.linspace(-50.0, 50.0, 21)
STEER_DEG = np.linspace(-120.0, 120.0, 17)
ROLL_DEG = np.linspace(-2.0, 2.0, 9)


def _timed(fn, *args):
    start = time.perf_counter()
    fn(*args)
    first = time.perf_counter() - start
    start = time.perf_counter()
    out = fn(*args)
    return out, first, time.perf_counter() - start


def _at(report_x, block, key, x):
    return float(np.interp(x, report_x, block[key]))


def main():
    out = output_dir("fig_6_11_6_12", __doc__)
    rigid, flexible = vehicle.load_car(modes=0), vehicle.load_car(modes=6)
    state = vehicle.static_equilibrium(flexible)
    variants = {"rigid": (rigid, True, None), "flexible": (flexible, True, None), "loaded": (flexible, False, state)}
    summary = {"thesis": THESIS, "variants": {}}
    for name, (car, balance, st) in variants.items():
        bump, t_bump, t_bump2 = _timed(vehicle.bump_report, car, TRAVEL_MM, balance, st)
        steer, t_steer, t_steer2 = _timed(vehicle.steer_report, car, STEER_DEG, balance, st)
        roll, t_roll, t_roll2 = _timed(vehicle.roll_report, car, ROLL_DEG, balance, st)
        for rig, report, plot in (("bump", bump, plots.plot_bump), ("steer", steer, plots.plot_steer),
                                  ("roll", roll, plots.plot_roll)):
            write_json(report, out / f"{rig}_{name}.json")
            plots.save(plot(report, title=f"{rig} test, {name} chassis"), out / f"{rig}_{name}.png")
        f = bump["front"]
        s = steer["front"]
        summary["variants"][name] = {
            "bump_front_at_mm": {str(x): {k: _at(f["travel_mm"], f, k, x) for k in
                                          ("fz_n", "camber_deg", "toe_deg", "track_mm")} for x in (-25.0, 25.0)},
            "steer_at_deg": {str(x): {k: _at(steer["steering_wheel_deg"], s, k, x) for k in
                                      ("left_deg", "right_deg", "left_camber_deg", "track_mm", "scrub_radius_mm")}
                             for x in (-90.0, 90.0)},
            "roll_stiffness_nm_per_deg": roll["roll_stiffness_nm_per_deg"],
            "seconds": {"bump": [t_bump, t_bump2], "steer": [t_steer, t_steer2], "roll": [t_roll, t_roll2]},
        }
        v = summary["variants"][name]
        print(f"{name}: bump +25 mm Fz {v['bump_front_at_mm']['25.0']['fz_n']:.0f} N, camber "
              f"{v['bump_front_at_mm']['25.0']['camber_deg']:.3f} deg; steer +90 deg left "
              f"{v['steer_at_deg']['90.0']['left_deg']:.2f} deg; roll stiffness "
              f"{roll['roll_stiffness_nm_per_deg']['front']:.1f} / {roll['roll_stiffness_nm_per_deg']['rear']:.1f} "
              f"Nm/deg; rigs {t_bump:.0f}/{t_steer:.0f}/{t_roll:.0f} s first, "
              f"{t_bump2:.2f}/{t_steer2:.2f}/{t_roll2:.2f} s compiled")
    write_json(summary, out / "summary.json")


if __name__ == "__main__":
    main()
