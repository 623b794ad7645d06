"""``jaxveh run``: the main job — the 14-DOF car and the chapter-3 model of the default
vehicle, with results, plots and a report."""

import csv
import time
from pathlib import Path
from typing import Optional

import typer

from ..analytic import _reports as reports
from ..params import ParameterError, load_analytic_vehicle
from ..plots import plot_bode, plot_skidpad, plot_step_steer, save
from ._common import emit_json, fail, write_json


def _write_csv(path: Path, columns: dict) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    names = list(columns)
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(names)
        writer.writerows(zip(*(columns[n] for n in names)))


def run(
    out: Path = typer.Option(Path("results"), "--out", help="Output folder."),
    vehicle: Optional[Path] = typer.Option(None, "--vehicle", help="Appendix-A-style TOML (default: shipped)."),
    as_json: bool = typer.Option(False, "--json", help="Print the summary as JSON."),
    car: Optional[Path] = typer.Option(None, "--car", help="car TOML file of the 14-DOF car (default: shipped)."),
    chapter3_only: bool = typer.Option(False, "--chapter3-only", help="Skip the 14-DOF car (minutes of compilation)."),
    quiet: bool = typer.Option(False, "--quiet", help="No progress messages."),
):
    """The main job: the 14-DOF car with its flexible chassis (static set-up, 50 m skid-pad
    by root finding, 90 km/h step steer; rigid vs 6 modes) and the chapter-3 analysis (load
    transfer, understeer, modes, skid-pad, step steer, frequency response). Writes
    ``summary.json``, ``report.md``, CSV/netCDF curves and time histories, and PNG figures
    into ``--out``."""
    from ._run_car import car_section, report_markdown, say_to
    from ._simulate import _compilation_cache

    say = say_to(quiet)
    try:
        veh = load_analytic_vehicle(vehicle)
    except ParameterError as e:
        fail(str(e))
    start = time.perf_counter()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    car_summary = None
    if not chapter3_only:
        _compilation_cache()
        say(f"jaxveh: the 14-DOF car -> {out}/ (the first run compiles for minutes)")
        try:
            car_summary = car_section(out, car, say)
        except (ParameterError, RuntimeError) as e:
            fail(str(e))
    say(f"jaxveh: chapter-3 analysis -> {out}/")
    summary = {
        "vehicle": str(vehicle) if vehicle else "appendix_a.toml (shipped)",
        "load_transfer": reports.lltd_report(veh),
        "understeer": reports.understeer_report(veh),
        "modes_50kmh": reports.eig_report(veh, 50.0)["modes"],
    }
    say("  skid-pad (R = 50 m, four variants) ...")
    skid = reports.skidpad_report(veh)
    write_json(skid, out / "skidpad.json")
    for name, data in skid["variants"].items():
        keys = ("ay_g", "delta_dynamic_deg", "steering_sensitivity_g_per_deg", "phi_front_deg", "phi_rear_deg")
        _write_csv(out / f"skidpad_{name}.csv", {k: data[k] for k in keys})
    save(plot_skidpad(skid), out / "skidpad.png")
    summary["skidpad_ay_limit_g"] = {name: data["ay_limit_g"] for name, data in skid["variants"].items()}
    say("  step steer (90 km/h, 1.5 deg) ...")
    step = reports.step_steer_report(veh)
    for name in ("rigid", "flexible"):
        _write_csv(out / f"step_steer_{name}.csv", step[name]["history"])
    save(plot_step_steer(step), out / "step_steer.png")
    summary["step_steer_90kmh"] = {
        name: {k: v for k, v in step[name].items() if k != "history"} for name in ("rigid", "flexible")
    }
    say("  frequency response (50 km/h) ...")
    bode = reports.bode_report(veh)
    write_json(bode, out / "bode.json")
    save(plot_bode(bode), out / "bode.png")
    if car_summary is not None:
        summary["car_file"] = str(car) if car else "car.toml (shipped)"
        summary["car"] = car_summary
    summary["wall_time_s"] = time.perf_counter() - start
    write_json(summary, out / "summary.json")
    (out / "report.md").write_text(report_markdown(summary))
    if as_json:
        emit_json(summary)
    else:
        lt, us = summary["load_transfer"], summary["understeer"]
        typer.echo(
            f"chi = {lt['chi']:.4f} (rigid {lt['chi_rigid']:.4f}), "
            f"ku = {us['ku_deg_per_g']:.3f} deg/g (rigid {us['ku_rigid_deg_per_g']:.3f})"
        )
        for name, m in summary["step_steer_90kmh"].items():
            typer.echo(
                f"chapter 3, step steer {name:>8}: yaw-rate response {m['yaw_rate_response_time_s']:.3f} s, "
                f"overshoot {m['yaw_rate_overshoot_pct']:.1f} %, ay {m['ay_steady_g']:.3f} g"
            )
        for name, m in (car_summary or {}).get("step_steer_90kmh", {}).items():
            typer.echo(
                f"car, step steer {name:>8}: yaw-rate response {m['yaw_rate_response_time_s']:.3f} s, "
                f"overshoot {m['yaw_rate_overshoot_pct']:.1f} %, ay {m['ay_steady_g']:.3f} g"
            )
        for name, p in (car_summary or {}).get("skid_pad", {}).items():
            typer.echo(f"car, skid-pad {name:>8}: understeer gradient {p['understeer_gradient_deg_per_g']:.3f} deg/g, "
                       f"roll {p['roll_at_1g_deg']:.2f} deg at 1 g, last steady state {p['ay_limit_g']:.2f} g")
        typer.echo(f"wrote {out}/summary.json, report.md, CSV, netCDF and PNG files in "
                   f"{summary['wall_time_s']:.1f} s")
