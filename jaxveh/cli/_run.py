"""``jaxveh run``: the main job — a complete analysis of the default vehicle with results and plots."""

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
):
    """Chapter-3 analysis of the vehicle: load transfer, understeer, modes, skid-pad,
    step steer and frequency response, rigid vs flexible chassis. Writes ``summary.json``,
    CSV time histories and curves, and PNG figures into ``--out``."""
    try:
        veh = load_analytic_vehicle(vehicle)
    except ParameterError as e:
        fail(str(e))
    start = time.perf_counter()
    out = Path(out)
    typer.echo(f"jaxveh: chapter-3 analysis -> {out}/", err=True)
    summary = {
        "vehicle": str(vehicle) if vehicle else "appendix_a.toml (shipped)",
        "load_transfer": reports.lltd_report(veh),
        "understeer": reports.understeer_report(veh),
        "modes_50kmh": reports.eig_report(veh, 50.0)["modes"],
    }
    typer.echo("  skid-pad (R = 50 m, four variants) ...", err=True)
    skid = reports.skidpad_report(veh)
    write_json(skid, out / "skidpad.json")
    for name, data in skid["variants"].items():
        keys = ("ay_g", "delta_dynamic_deg", "steering_sensitivity_g_per_deg", "phi_front_deg", "phi_rear_deg")
        _write_csv(out / f"skidpad_{name}.csv", {k: data[k] for k in keys})
    save(plot_skidpad(skid), out / "skidpad.png")
    summary["skidpad_ay_limit_g"] = {name: data["ay_limit_g"] for name, data in skid["variants"].items()}
    typer.echo("  step steer (90 km/h, 1.5 deg) ...", err=True)
    step = reports.step_steer_report(veh)
    for name in ("rigid", "flexible"):
        _write_csv(out / f"step_steer_{name}.csv", step[name]["history"])
    save(plot_step_steer(step), out / "step_steer.png")
    summary["step_steer_90kmh"] = {
        name: {k: v for k, v in step[name].items() if k != "history"} for name in ("rigid", "flexible")
    }
    typer.echo("  frequency response (50 km/h) ...", err=True)
    bode = reports.bode_report(veh)
    write_json(bode, out / "bode.json")
    save(plot_bode(bode), out / "bode.png")
    summary["wall_time_s"] = time.perf_counter() - start
    write_json(summary, out / "summary.json")
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
                f"step steer {name:>8}: yaw-rate response {m['yaw_rate_response_time_s']:.3f} s, "
                f"overshoot {m['yaw_rate_overshoot_pct']:.1f} %, ay {m['ay_steady_g']:.3f} g"
            )
        typer.echo(f"wrote {out}/summary.json, CSV and PNG files in {summary['wall_time_s']:.1f} s")
