"""Fig. 7.5: skid-pad on a 50 m circle, the 14-DOF car rigid vs 6-mode flexible (steady
states by root finding on the fast car), beside the chapter-3 model's rigid and flexible
curves (Fig. 3.6's model, Appendix A vehicle): dynamic steer angle, understeer gradient,
sideslip and roll against ay; the front share of the lateral load transfer."""

import numpy as np
from _util import output_dir, write_json

from jaxveh.analytic._reports import skidpad_report
from jaxveh.manoeuvre import skid_pad_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_skid_pad, save
from jaxveh.vehicle import load_car

RADIUS = 50.0


def main():
    out = output_dir("fig_7_5", __doc__)
    report, curves = {}, {}
    for label, modes in (("multib. rigid", 0), ("multib. flex.", 6)):
        r = skid_pad_report(load_car(modes=modes), RADIUS, ay_max_g=2.5, step_g=0.05)
        report[label] = r
        curves[label] = r["curve"]
    analytic = skidpad_report(load_analytic_vehicle(), variants=("rigid", "flexible"), radius=RADIUS)
    for name, label in (("rigid", "analytical rigid"), ("flexible", "analytical flex.")):
        v = analytic["variants"][name]
        curves[label] = {"ay_g": v["ay_g"], "delta_dynamic_deg": v["delta_dynamic_deg"],
                         "understeer_gradient_deg_per_g": 1.0 / np.asarray(v["steering_sensitivity_g_per_deg"]),
                         "sideslip_deg": [np.nan] * len(v["ay_g"]),
                         "roll_deg": (0.5 * (np.asarray(v["phi_front_deg"]) + np.asarray(v["phi_rear_deg"]))).tolist()}
    report["chapter_3"] = analytic
    save(plot_skid_pad(curves, title=f"skid-pad R = {RADIUS:g} m (Fig. 7.5)"), out / "fig_7_5.png")
    write_json(report, out / "fig_7_5.json")
    for label in ("multib. rigid", "multib. flex."):
        r = report[label]
        c = r["curve"]
        i = int(np.argmin(np.abs(np.asarray(c["ay_g"]) - 1.0)))
        ku, at = r["understeer_gradient_deg_per_g"], r["understeer_gradient_at_g"]
        print(f"{label:>14}: ku {ku:+.3f} deg/g at {at:.2f} g, "
              f"limit {r['ay_limit_g']:.2f} g; at {c['ay_g'][i]:.2f} g: roll {c['roll_deg'][i]:.2f} deg, sideslip "
              f"{c['sideslip_deg'][i]:.2f} deg, chi {c['lltd_front_share'][i]:.3f}; {r['wall_time_s']:.0f} s")
    print("thesis Fig. 7.5: understeer (delta_d rising to ~2.5 deg, 1/ku ~1.4 g/deg at low ay), roll ~2 deg at 1 g, "
          "sideslip falling to about -3.5 deg at 1.2 g")


if __name__ == "__main__":
    main()
