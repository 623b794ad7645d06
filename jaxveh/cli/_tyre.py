"""``jaxveh tyre ...``: evaluate, plot and fit Magic Formula 5.2 tyres (.tir files)."""

import math
from pathlib import Path
from typing import Optional

import numpy as np
import typer

from ..params import ParameterError
from ._common import emit_json, fail, new_app, write_json

app = new_app("Magic Formula 5.2 tyres: evaluate, plot Fig. B.1 panels, fit .tir files.")

TirOpt = typer.Option(None, "--tir", help=".tir property file (default: the shipped FSAE 20.0x7.0-13 tyre).")
JsonOpt = typer.Option(False, "--json", help="Print a machine-readable JSON result on stdout.")


def _tyre(path: Optional[Path], option: str = "--tir"):
    from ..tyre import load_fsae_tyre, read_tir

    try:
        return load_fsae_tyre() if path is None else read_tir(path)
    except FileNotFoundError:
        fail(f"{option}: file not found: {path}")
    except (ParameterError, ValueError) as e:
        fail(f"{option}: {e}")


def _finite(value: float, option: str) -> float:
    if not math.isfinite(value):
        fail(f"{option} must be a finite number, got {value}")
    return value


@app.command("eval")
def evaluate(
    tir: Optional[Path] = TirOpt,
    fz: float = typer.Option(..., "--fz", help="Normal load [N] (<= 0: lifted off, zero force)."),
    kappa: float = typer.Option(0.0, "--kappa", help="Longitudinal slip [-] (ISO-W, positive driving)."),
    alpha_deg: float = typer.Option(0.0, "--alpha-deg", help="Slip angle [deg] (ISO-W: positive gives Fy < 0)."),
    gamma_deg: float = typer.Option(0.0, "--gamma-deg", help="Inclination angle [deg] (ISO-W)."),
    vx: Optional[float] = typer.Option(None, "--vx", help="Forward speed [m/s] (default: the file's LONGVL)."),
    moments: bool = typer.Option(False, "--moments", help="Also report Mx and My [Nm]."),
    as_json: bool = JsonOpt,
):
    """Forces Fx, Fy [N] and aligning moment Mz [Nm] at one operating point (ISO-W axes)."""
    import jax.numpy as jnp

    from ..tyre import tyre_forces

    t = _tyre(tir)
    options = ((fz, "--fz"), (kappa, "--kappa"), (alpha_deg, "--alpha-deg"), (gamma_deg, "--gamma-deg"))
    fz_, kappa_, alpha_, gamma_ = (jnp.asarray(_finite(v, o)) for v, o in options)
    speed = None if vx is None else jnp.asarray(_finite(vx, "--vx"))
    f = tyre_forces(t, fz_, kappa_, jnp.deg2rad(alpha_), jnp.deg2rad(gamma_), speed)
    result = {"fx": float(f.fx), "fy": float(f.fy), "mz": float(f.mz)}
    if moments:
        result.update(mx=float(f.mx), my=float(f.my))
    if as_json:
        emit_json(result)
    else:
        units = {"fx": "N", "fy": "N", "mz": "Nm", "mx": "Nm", "my": "Nm"}
        for key, value in result.items():
            typer.echo(f"{key}: {value:.6g} {units[key]}")


LoadsOpt = typer.Option(
    None,
    "--loads",
    help="Comma-separated loads [N], each > 0 (default: FNOMIN x 1/3, 2/3, 1, 4/3 = Fig. B.1's 250-1000 N for FSAE).",
)


def _loads(text: Optional[str]):
    if text is None:
        return None
    try:
        loads = tuple(float(v) for v in text.split(","))
    except ValueError:
        fail(f"--loads must be comma-separated numbers, got {text!r}")
    if not all(math.isfinite(v) and v > 0.0 for v in loads):
        fail(f"--loads must be finite and > 0 N, got {text!r}")
    return loads


@app.command()
def plot(
    tir: Optional[Path] = TirOpt,
    out: Path = typer.Option(..., "--out", help="Folder for the PNGs and peaks.json."),
    loads: Optional[str] = LoadsOpt,
):
    """The four panels of Fig. B.1 (Fx-kappa, Fy-alpha, Mz-alpha, Fx-Fy at FNOMIN) as PNGs."""
    from ..tyre import peak_table, plot_fig_b1

    t = _tyre(tir)
    fz = _loads(loads)
    name = "FSAE 20.0x7.0-13 (shipped)" if tir is None else Path(tir).name
    paths = plot_fig_b1(t, out, title=name, loads=fz)
    write_json({"tir": name, "peaks": peak_table(t, fz)}, Path(out) / "peaks.json")
    for p in paths:
        typer.echo(str(p))


@app.command()
def peaks(tir: Optional[Path] = TirOpt, loads: Optional[str] = LoadsOpt, as_json: bool = JsonOpt):
    """Peak Fx, |Fy|, Mz per load (FSAE: 250/500/750/1000 N) and the slips where they occur."""
    from ..tyre import peak_table

    rows = peak_table(_tyre(tir), _loads(loads))
    if as_json:
        emit_json(rows)
        return
    typer.echo(
        f"{'Fz [N]':>7} {'Fx max [N]':>10} {'kappa':>6} {'|Fy| max [N]':>12} {'alpha [deg]':>11} "
        f"{'Mz max [Nm]':>11} {'alpha [deg]':>11}"
    )
    for r in rows:
        typer.echo(
            f"{r['fz']:7.0f} {r['fx_peak']:10.0f} {r['kappa_peak']:6.3f} {r['fy_peak']:12.0f} "
            f"{r['alpha_peak_deg']:11.2f} {r['mz_max']:11.1f} {r['alpha_mz_max_deg']:11.2f}"
        )


@app.command()
def fit(
    data: Path = typer.Argument(
        ..., help="CSV: fz, kappa, alpha (or alpha_deg), gamma (or gamma_deg), fx, fy, mz [, vx, pressure]."
    ),
    out: Path = typer.Option(..., "--out", help="Fitted .tir file to write."),
    start: Optional[Path] = typer.Option(
        None, "--start", help="Initial .tir (default: shipped FSAE tyre, FNOMIN = median load)."
    ),
    max_steps: int = typer.Option(400, "--max-steps", help="Levenberg-Marquardt steps per stage, >= 1."),
    as_json: bool = JsonOpt,
):
    """Fit MF 5.2 coefficients (pure Fx, pure Fy, pure Mz, then combined) and write a .tir."""
    from ..tyre import fit_tir, read_tyre_csv, write_tir

    if max_steps < 1:
        fail(f"--max-steps must be >= 1, got {max_steps}")
    if not data.exists():
        fail(f"DATA: file not found: {data}")
    try:
        measurements = read_tyre_csv(data)
    except ParameterError as e:
        fail(f"DATA: {e}")
    report = fit_tir(measurements, None if start is None else _tyre(start, "--start"), max_steps=max_steps)
    write_tir(out, report.tyre)
    result = {"tir": str(out), "rows": int(np.asarray(measurements.fz).shape[0]), "stages": list(report.stages)}
    if as_json:
        emit_json(result)
    else:
        for s in report.stages:
            typer.echo(str(s))
        typer.echo(f"wrote {out}")
