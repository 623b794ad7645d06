"""Fig. 7.6: step steer at 90 km/h on the 14-DOF car, rigid vs 6-mode flexible chassis (fast
form), beside the chapter-3 model's Fig. 3.8 step (1.5 deg road-wheel, cubic over 0.1 s).
The car's step is 6 deg at the steering wheel over 0.1 s (about 1.5 deg at the front
wheels through the rack and the kinematics; the measured value is reported)."""

import numpy as np
from _util import output_dir, write_json

from jaxveh.analytic._reports import step_steer_report
from jaxveh.manoeuvre import simulate, step_steer, step_steer_metrics
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import figure, save
from jaxveh.vehicle import load_car

STEER_DEG, START, RISE = 6.0, 0.5, 0.1


def main():
    out = output_dir("fig_7_6", __doc__)
    m = step_steer(speed=25.0, angle=np.deg2rad(STEER_DEG), start=START, rise=RISE, duration=5.0)
    report, histories = {}, {}
    for label, modes in (("rigid", 0), ("flexible", 6)):
        run = simulate(load_car(modes=modes), m)
        ch = {k: np.asarray(v) for k, v in run.channels.items()}
        report[label] = step_steer_metrics(run.ts, ch, m.steering) | {
            "front_road_wheel_angle_deg": float(np.mean(ch["road_wheel_angle"][-1, :2])),
            "steps": int(run.steps), "wall_s": run.wall_s}
        histories[label] = {"t_s": np.asarray(run.ts) - START, **ch}
    analytic = step_steer_report(load_analytic_vehicle(), speed_kmh=90.0, steer_deg=1.5, rise_s=RISE, t_end=4.0)
    report["chapter_3"] = {k: {key: analytic[k][key] for key in ("yaw_rate_response_time_s", "yaw_rate_overshoot_pct",
                                                                  "ay_steady_g")} for k in ("rigid", "flexible")}
    fig, axes = figure(2, 2, figsize=(10, 7))  # time from the start of the step
    panels = (("road_wheel_angle", "δ [deg]"), ("ay", "ay [g]"), ("yaw_rate", "r [deg/s]"), ("modes", "modal coord."))
    for ax, (key, ylabel) in zip(axes.flat, panels):
        for label, style in (("rigid", "-"), ("flexible", "--")):
            h = histories[label]
            y = h[key][:, :2].mean(axis=1) if key == "road_wheel_angle" else h[key]
            if key == "modes":
                if label == "flexible":
                    for k in range(y.shape[1]):
                        ax.plot(h["t_s"], y[:, k], label=f"mode {k + 1}")
                continue
            ax.plot(h["t_s"], y, style, label=f"multib. {label}")
        if key in ("ay", "yaw_rate"):
            for label, style in (("rigid", ":"), ("flexible", "-.")):
                a = analytic[label]["history"]
                ax.plot(a["t_s"], a["ay_g" if key == "ay" else "yaw_rate_deg_s"], style,
                        label=f"analytical {label}")
        ax.set(xlabel="t [s]", ylabel=ylabel, xlim=(0, 2))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    save(fig, out / "fig_7_6.png")
    write_json(report, out / "fig_7_6.json")
    for label in ("rigid", "flexible"):
        r = report[label]
        print(f"{label:>8}: response {r['yaw_rate_response_time_s']:.3f} s, peak {r['yaw_rate_peak_time_s']:.3f} s, "
              f"overshoot {r['yaw_rate_overshoot_pct']:.2f} %, ay {r['ay_steady_g']:.3f} g, "
              f"road wheels {r['front_road_wheel_angle_deg']:.2f} deg")


if __name__ == "__main__":
    main()
