"""``jaxveh analytic ...``: the chapter-3 analyses from the command line."""

from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..analytic import _reports as reports
from ..params import ParameterError, load_analytic_vehicle
from ..plots import plot_bode, plot_map, plot_preview, plot_root_locus, plot_skidpad, plot_step_steer, save
from ._common import emit_json, fail, new_app, write_json

app = new_app("Chapter-3 analytic models (Appendix A vehicle by default).")

VehicleOpt = typer.Option(None, "--vehicle", help="Appendix-A-style TOML file (default: shipped appendix_a.toml).")
LamOpt = typer.Option(
    None, "--lam", help="Roll stiffness proportion λ = kF/(kF+kR), in (0, 1). Default: from the file."
)
MuOpt = typer.Option(
    None, "--mu", help="Normalised chassis torsional stiffness µ = kC/(kF+kR), > 0. Default: from the file."
)
JsonOpt = typer.Option(False, "--json", help="Print a machine-readable JSON result on stdout.")
PlotOpt = typer.Option(None, "--plot", help="Write a PNG figure to this file.")
OutOpt = typer.Option(None, "--out", help="Write JSON data (and a PNG) into this folder.")


def _vehicle(path: Optional[Path], lam=None, mu=None):
    try:
        return reports.configure(load_analytic_vehicle(path), lam, mu)
    except (ParameterError, ValueError) as e:
        fail(str(e))


def _run(fn, *args, **kwargs):
    try:
        return fn(*args, **kwargs)
    except ValueError as e:
        fail(str(e))


def _finish(result: dict, as_json: bool, out: Optional[Path], name: str, summary: dict | None = None) -> None:
    if out is not None:
        write_json(result, Path(out) / f"{name}.json")
    if as_json:
        emit_json(result)
    else:
        for key, value in (summary if summary is not None else result).items():
            typer.echo(f"{key}: {value}")


@app.command()
def lltd(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    as_json: bool = JsonOpt,
):
    """Lateral load transfer proportion χ (eq. 3.6), rigid χ0 (3.3), ζ (3.7) and ∂χ/∂λ."""
    _finish(reports.lltd_report(_vehicle(vehicle, lam, mu)), as_json, None, "lltd")


@app.command()
def understeer(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    as_json: bool = JsonOpt,
):
    """Linear understeer gradient with roll steer, flexible (3.16) and rigid (3.11), deg/g."""
    _finish(reports.understeer_report(_vehicle(vehicle, lam, mu)), as_json, None, "understeer")


@app.command()
def skidpad(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    radius: float = typer.Option(50.0, help="Circle radius (m)."),
    ay_max_g: float = typer.Option(1.3, help="Highest lateral acceleration of the sweep (g)."),
    n: int = typer.Option(27, help="Number of ay points."),
    as_json: bool = JsonOpt,
    plot: Optional[Path] = PlotOpt,
    out: Optional[Path] = OutOpt,
):
    """Steady-state skid-pad by root finding: δd and 1/ku versus ay, four variants (Fig. 3.6)."""
    result = _run(reports.skidpad_report, _vehicle(vehicle, lam, mu), radius=radius, ay_max_g=ay_max_g, n=n)
    if plot is not None or out is not None:
        fig = plot_skidpad(result)
        save(fig, plot if plot is not None else Path(out) / "skidpad.png")
    limits = {name: v["ay_limit_g"] for name, v in result["variants"].items()}
    _finish(result, as_json, out, "skidpad", {"ay_limit_g": limits})


@app.command("step-steer")
def step_steer(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    speed_kmh: float = typer.Option(90.0, "--speed-kmh", help="Constant speed (km/h)."),
    steer_deg: float = typer.Option(1.5, "--steer-deg", help="Road-wheel steer amplitude (deg)."),
    rise_s: float = typer.Option(0.1, "--rise-s", help="Duration of the cubic smoothed step (s)."),
    t_end: float = typer.Option(4.0, "--t-end", help="Simulated time (s)."),
    as_json: bool = JsonOpt,
    plot: Optional[Path] = PlotOpt,
    out: Optional[Path] = OutOpt,
):
    """Step steer with Diffrax, rigid and flexible chassis (Fig. 3.8) and its metrics."""
    result = _run(reports.step_steer_report, _vehicle(vehicle, lam, mu), speed_kmh, steer_deg, rise_s, t_end)
    if plot is not None or out is not None:
        save(plot_step_steer(result), plot if plot is not None else Path(out) / "step_steer.png")
    if out is not None:
        write_json(result, Path(out) / "step_steer.json")
    metrics = {name: {k: v for k, v in result[name].items() if k != "history"} for name in ("rigid", "flexible")}
    compact = {k: v for k, v in result.items() if k not in ("rigid", "flexible")} | metrics
    if as_json:
        emit_json(compact)
    else:
        for key, value in compact.items():
            typer.echo(f"{key}: {value}")


@app.command()
def eig(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="Speed of the straight-running trim (km/h)."),
    rigid: bool = typer.Option(False, "--rigid", help="Rigid chassis (φF = φR)."),
    as_json: bool = JsonOpt,
    plot: Optional[Path] = PlotOpt,
):
    """Modes of the linearised model: frequency, damping ratio and label; --plot draws the
    root locus versus µ = 0.1...10 at this speed (Fig. 3.9a)."""
    veh = _vehicle(vehicle, lam, mu)
    result = _run(reports.eig_report, veh, speed_kmh, rigid)
    if plot is not None:
        loci = reports.root_locus(veh, speed_kmh, np.geomspace(0.1, 10.0, 80))
        save(plot_root_locus({"eigenvalues": loci}, title=f"µ = 0.1 (□) ... 10 (○), {speed_kmh:g} km/h"), plot)
    if as_json:
        emit_json(result)
    else:
        for m in result["modes"]:
            typer.echo(f"{m['label']:>14}: {m['freq_hz']:.3f} Hz, damping ratio {m['damping_ratio']:.3f}")


@app.command()
def bode(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    speed_kmh: float = typer.Option(50.0, "--speed-kmh", help="Speed (km/h)."),
    f_min: float = typer.Option(0.1, "--f-min", help="Lowest frequency (Hz)."),
    f_max: float = typer.Option(5.0, "--f-max", help="Highest frequency (Hz)."),
    n: int = typer.Option(200, help="Number of frequencies (log-spaced)."),
    steering_wheel: bool = typer.Option(
        False, "--steering-wheel", help="Per steering-wheel angle instead of road-wheel angle."
    ),
    as_json: bool = JsonOpt,
    plot: Optional[Path] = PlotOpt,
    out: Optional[Path] = OutOpt,
):
    """Yaw-rate and lateral-acceleration frequency response to steering (Fig. 3.10)."""
    result = _run(reports.bode_report, _vehicle(vehicle, lam, mu), speed_kmh, f_min, f_max, n, not steering_wheel)
    if plot is not None or out is not None:
        save(plot_bode(result), plot if plot is not None else Path(out) / "bode.png")
    summary = {
        name: {
            "yaw_rate_db_at_fmin": result[name]["yaw_rate_db_per_s"][0],
            "ay_db_at_fmin": result[name]["ay_db_g_per_deg"][0],
        }
        for name in ("rigid", "flexible")
    }
    _finish(result, as_json, out, "bode", summary)


@app.command()
def preview(
    vehicle: Optional[Path] = VehicleOpt,
    lam: Optional[float] = LamOpt,
    mu: Optional[float] = MuOpt,
    speed_kmh: float = typer.Option(100.0, "--speed-kmh", help="Speed (km/h)."),
    rigid: bool = typer.Option(False, "--rigid", help="Rigid chassis (φF = φR)."),
    n_preview: int = typer.Option(200, "--n-preview", help="Preview points q."),
    dt: float = typer.Option(0.01, "--dt", help="Sample time (s)."),
    as_json: bool = JsonOpt,
    plot: Optional[Path] = PlotOpt,
):
    """Optimal preview gains (deg/m) and preview distance Lp (m), eqs. 3.38-3.46 (Fig. 3.11)."""
    result = _run(reports.preview_report, _vehicle(vehicle, lam, mu), speed_kmh, rigid, dt, n_preview)
    if plot is not None:
        save(plot_preview({"rigid" if rigid else f"µ = {result['mu']:g}": result}), plot)
    if as_json:
        emit_json(result)
    else:
        typer.echo(
            f"preview distance Lp = {result['preview_distance_m']:.2f} m at {speed_kmh:g} km/h "
            f"(Riccati residual {result['riccati_residual']:.1e})"
        )


@app.command("map")
def design_map(
    vehicle: Optional[Path] = VehicleOpt,
    quantity: str = typer.Option("chi_error", help="chi, chi_error, chi_sensitivity_error, ku_deg_per_g or ku_error."),
    n_lam: int = typer.Option(101, "--n-lam", help="Grid points in λ."),
    n_mu: int = typer.Option(101, "--n-mu", help="Grid points in µ (log-spaced)."),
    lam_min: float = typer.Option(0.0, "--lam-min"),
    lam_max: float = typer.Option(1.0, "--lam-max"),
    mu_min: float = typer.Option(0.1, "--mu-min"),
    mu_max: float = typer.Option(10.0, "--mu-max"),
    minimum: bool = typer.Option(False, "--minimum", help="Also compute the chapter-3 minimum-stiffness answers."),
    as_json: bool = JsonOpt,
    plot: Optional[Path] = PlotOpt,
    out: Optional[Path] = OutOpt,
):
    """λ x µ design map by vmap (Figs. 3.3c-d, 3.4c); --minimum adds the smallest µ per target."""
    veh = _vehicle(vehicle)
    result = _run(reports.map_report, veh, quantity, (lam_min, lam_max), (mu_min, mu_max), n_lam, n_mu)
    if minimum:
        result["minimum_stiffness"] = _run(reports.minimum_stiffness_report, veh)
    if plot is not None or out is not None:
        save(plot_map(result, quantity), plot if plot is not None else Path(out) / f"map_{quantity}.png")
    summary = {"quantity": quantity, "max": float(np.max(result["values"])), "min": float(np.min(result["values"]))}
    if minimum:
        summary["minimum_stiffness"] = result["minimum_stiffness"]
    _finish(result, as_json, out, f"map_{quantity}", summary)
