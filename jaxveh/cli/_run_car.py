"""The 14-DOF car in the main job (``jaxveh run``): its static set-up, the 50 m skid-pad by
root finding and the 90 km/h step steer, rigid and with the 6-mode flexible chassis (fast
form), written as JSON, CSV, netCDF and PNG files, with each figure's headline numbers
beside what the thesis states (:func:`report_markdown`)."""

import math
from pathlib import Path

import numpy as np
import typer

from ._common import write_curve_csv, write_json

#: The step steer of Fig. 7.6 on the car: 90 km/h, 6 deg at the steering wheel (about 1.5 deg
#: at the front wheels) from 0.5 s over 0.2 s, 5 s.
STEP = {"speed_kmh": 90.0, "steer_deg": 6.0, "duration_s": 5.0}
CHASSIS = {"rigid": 0, "flexible": 6}


def _at(curve: dict, key: str, ay_g: float) -> float:
    """``key`` of a skid-pad curve interpolated at ``ay_g`` (NaN beyond the curve)."""
    ay = np.asarray(curve["ay_g"])
    if not ay[0] <= ay_g <= ay[-1]:
        return float("nan")
    return float(np.interp(ay_g, ay, np.asarray(curve[key])))


def car_section(out: Path, car_file: Path | None, say) -> dict:
    """Run the car's analyses into ``out`` and return their summary (JSON-ready)."""
    from .. import plots
    from ..manoeuvre import simulate, skid_pad_report, step_steer, step_steer_metrics, write_netcdf
    from ..vehicle import load_car, vehicle_info

    cars = {label: load_car(car_file, modes=modes) for label, modes in CHASSIS.items()}
    say("  car: static set-up (6-mode chassis) ...")
    info = vehicle_info(cars["flexible"])
    write_json(info, out / "car_setup.json")
    summary = {"set_up": {k: info[k] for k in ("total_mass_kg", "corner_loads_n", "front_load_share",
                                                "ride_frequency_hz", "roll_stiffness_distribution",
                                                "chassis_modes_hz")}}
    say("  car: skid-pad R = 50 m by root finding, rigid and flexible ...")
    pads = {}
    for label, car in cars.items():
        pads[label] = skid_pad_report(car, 50.0, 2.5, 0.05)
        write_json(pads[label], out / f"car_skid_pad_{label}.json")
        write_curve_csv(out / f"car_skid_pad_{label}.csv", pads[label]["curve"])
    plots.save(plots.plot_skid_pad({k: p["curve"] for k, p in pads.items()}, title="skid-pad R = 50 m (car)"),
               out / "car_skid_pad.png")
    summary["skid_pad"] = {label: {
        "understeer_gradient_deg_per_g": p["understeer_gradient_deg_per_g"],
        "ay_limit_g": p["ay_limit_g"],
        "roll_at_0.4g_deg": _at(p["curve"], "roll_deg", 0.4),
        "roll_at_1g_deg": _at(p["curve"], "roll_deg", 1.0),
        "sideslip_at_1g_deg": _at(p["curve"], "sideslip_deg", 1.0),
        "lltd_front_share_at_1g": _at(p["curve"], "lltd_front_share", 1.0),
        "wall_time_s": p["wall_time_s"],
    } for label, p in pads.items()}
    say("  car: step steer 90 km/h, rigid and flexible ...")
    m = step_steer(speed=STEP["speed_kmh"] / 3.6, angle=math.radians(STEP["steer_deg"]),
                   duration=STEP["duration_s"])
    histories, steps = {}, {}
    for label, car in cars.items():
        run = simulate(car, m)
        write_netcdf(run, out / f"car_step_steer_{label}.nc", {"chassis": label})
        ch = {k: np.asarray(v) for k, v in run.channels.items()}
        histories[label] = {"t_s": np.asarray(run.ts)} | ch
        steps[label] = step_steer_metrics(run.ts, ch, m.steering) | {
            "steps": int(run.steps), "wall_time_s": run.wall_s, "stop_reason": run.stop_reason,
            "max_constraint_residual_m": float(np.max(ch["constraint_residual"]))}
        columns = {"t_s": np.asarray(run.ts)} | {k: v for k, v in ch.items() if v.ndim == 1}
        np.savetxt(out / f"car_step_steer_{label}.csv", np.column_stack(list(columns.values())), delimiter=",",
                   header=",".join(columns), comments="")
    plots.save(plots.plot_manoeuvre(histories, title="step steer 90 km/h, 6 deg (car)"), out / "car_step_steer.png")
    summary["step_steer_90kmh"] = steps
    return summary


def _fmt(x, digits: int = 3) -> str:
    return "n/a" if x is None or (isinstance(x, float) and math.isnan(x)) else f"{x:.{digits}g}"


def report_markdown(summary: dict) -> str:
    """A one-page report of the main job: each figure with its headline numbers beside the
    thesis's."""
    lines = ["# jaxveh main job: results", "",
             f"Vehicle files: chapter-3 `{summary['vehicle']}`; car `{summary.get('car_file', 'car.toml (shipped)')}`. "
             f"Wall time {summary['wall_time_s']:.0f} s (compilation included; JAX's disk cache keeps the "
             "compiled programs for the next run).", ""]
    car = summary.get("car")
    if car is not None:
        s = car["set_up"]
        lines += ["## The 14-DOF car (chapter 6, fast form)", "",
                  f"Mass {s['total_mass_kg']:.1f} kg, front load share {100 * s['front_load_share']:.1f} %, roll "
                  f"stiffness distribution lambda = {s['roll_stiffness_distribution']:.3f}, chassis modes "
                  + ", ".join(f"{f:.1f}" for f in s["chassis_modes_hz"]) + " Hz.", "",
                  "### Skid-pad, R = 50 m (Fig. 7.5)", "", "![skid-pad](car_skid_pad.png)", "",
                  "| quantity | rigid | 6 modes | thesis (Fig. 7.5) |", "|---|---|---|---|"]
        p = car["skid_pad"]
        rows = (("understeer gradient, deg/g (0.05 g)", "understeer_gradient_deg_per_g",
                 "understeering, about 0.7 (see docs/manoeuvre.md: the code's car deviates)"),
                ("roll at 0.4 g, deg", "roll_at_0.4g_deg", "linear in ay"),
                ("roll at 1 g, deg", "roll_at_1g_deg", "about 2"),
                ("sideslip at 1 g, deg", "sideslip_at_1g_deg", "from about +1 at low ay to about -3.5 at 1.2 g"),
                ("front share of load transfer at 1 g", "lltd_front_share_at_1g", "0.44 (Fig. 7.2, lambda 0.54)"),
                ("last steady state, g", "ay_limit_g", "the figure ends near 1.2 g"))
        for name, key, thesis in rows:
            lines.append(f"| {name} | {_fmt(p['rigid'][key])} | {_fmt(p['flexible'][key])} | {thesis} |")
        st = car["step_steer_90kmh"]
        lines += ["", "### Step steer, 90 km/h (Fig. 7.6)", "", "![step steer](car_step_steer.png)", "",
                  "| quantity | rigid | 6 modes | thesis (Fig. 7.6) |", "|---|---|---|---|"]
        rows = (("yaw-rate response time, s", "yaw_rate_response_time_s", "longer with the flexible chassis"),
                ("yaw-rate peak time, s", "yaw_rate_peak_time_s", "longer with the flexible chassis"),
                ("yaw-rate overshoot, %", "yaw_rate_overshoot_pct", "larger with the flexible chassis"),
                ("steady yaw rate, deg/s", "yaw_rate_steady_deg_s", "-"),
                ("steady ay, g", "ay_steady_g", "-"),
                ("integration steps", "steps", "-"))
        for name, key, thesis in rows:
            lines.append(f"| {name} | {_fmt(st['rigid'][key], 4)} | {_fmt(st['flexible'][key], 4)} | {thesis} |")
        lines.append("")
    lt, us = summary["load_transfer"], summary["understeer"]
    lines += ["## The chapter-3 model (Appendix A)", "",
              f"Front share of the lateral load transfer chi = {lt['chi']:.4f} (rigid {lt['chi_rigid']:.4f}); "
              f"understeer gradient {us['ku_deg_per_g']:.3f} deg/g (rigid {us['ku_rigid_deg_per_g']:.3f}).", "",
              "![skid-pad](skidpad.png)", "", "![step steer](step_steer.png)", "", "![frequency response](bode.png)",
              ""]
    for name, m in summary["step_steer_90kmh"].items():
        lines.append(f"- step steer {name}: yaw-rate response {m['yaw_rate_response_time_s']:.3f} s, overshoot "
                     f"{m['yaw_rate_overshoot_pct']:.1f} %, ay {m['ay_steady_g']:.3f} g")
    lines.append("")
    return "\n".join(lines)


def say_to(quiet: bool):
    def say(message: str) -> None:
        if not quiet:
            typer.echo(message, err=True)
    return say
