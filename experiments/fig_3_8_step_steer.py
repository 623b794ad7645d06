"""Fig. 3.8: step steer at 90 km/h, 1.5 deg road-wheel, cubic step over 0.1 s; rigid vs flexible."""

from _util import output_dir, write_json

from jaxveh.analytic._reports import step_steer_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_step_steer, save

THESIS = {"rigid": {"yaw_rate_response_time_s": 0.17, "yaw_rate_overshoot_pct": 9.5},
          "flexible": {"yaw_rate_response_time_s": 0.22, "yaw_rate_overshoot_pct": 14.5, "twist_settling_time_s": 1.2}}


def main():
    out = output_dir("fig_3_8", __doc__)
    report = step_steer_report(load_analytic_vehicle(), speed_kmh=90.0, steer_deg=1.5, rise_s=0.1, t_end=4.0)
    save(plot_step_steer(report), out / "fig_3_8.png")
    write_json(report | {"thesis": THESIS}, out / "fig_3_8.json")
    for name in ("rigid", "flexible"):
        for key, thesis in THESIS[name].items():
            print(f"{name:>8} {key}: code {report[name][key]:.3f}, thesis {thesis}")
        print(f"{name:>8} ay_steady_g: {report[name]['ay_steady_g']:.3f}")


if __name__ == "__main__":
    main()
