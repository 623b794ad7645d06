"""``jaxveh chassis``: FE model of the chassis, torsion test, modes, reduction comparison."""

from pathlib import Path

import numpy as np
import typer

from .._core import ParameterError
from ._common import emit_json, fail, new_app

app = new_app("Chassis finite-element model: torsion test, free-free modes, Craig-Bampton.")

FrameOpt = typer.Option(None, "--frame", help="frame TOML file (default: the shipped FSAE 2009 frame)")
JsonOpt = typer.Option(False, "--json", help="print only JSON on stdout")


def _frame(path: Path | None):
    from .. import fe

    return fe.load_frame(path)


@app.command()
def torsion(frame: Path = FrameOpt, as_json: bool = JsonOpt) -> None:
    """Static torsion test (thesis section 6.2.2): stiffness in Nm/deg and frame mass."""
    from .. import fe

    try:
        r = fe.torsion_test(_frame(frame))
    except ParameterError as e:
        fail(str(e))
    out = {
        "torsional_stiffness_Nm_per_deg": float(r.stiffness_nm_per_deg),
        "mass_kg": float(r.mass),
        "deflection_mm": 1e3 * float(r.deflection),
        "torque_Nm": float(r.torque),
    }
    if as_json:
        emit_json(out)
    else:
        typer.echo(f"torsional stiffness {out['torsional_stiffness_Nm_per_deg']:.1f} Nm/deg "
                   f"(thesis FE 385, measured 360), mass {out['mass_kg']:.2f} kg (thesis 23.5)")


@app.command()
def modes(
    frame: Path = FrameOpt,
    n: int = typer.Option(6, "--n", help="number of elastic modes"),
    method: str = typer.Option("truncation", "--method", help="truncation | craig-bampton"),
    n_fixed: int = typer.Option(60, "--n-fixed", help="fixed-interface modes (craig-bampton)"),
    damping_ratio: float | None = typer.Option(
        None, "--damping-ratio", help="modal damping ratio of every mode, [0, 1) (default 0.025 unless --alpha/--beta)"
    ),
    alpha: float | None = typer.Option(None, "--alpha", help="Rayleigh mass-proportional damping (1/s), >= 0"),
    beta: float | None = typer.Option(None, "--beta", help="Rayleigh stiffness-proportional damping (s), >= 0"),
    as_json: bool = JsonOpt,
) -> None:
    """Lowest free-free elastic modes with automatic labels (thesis Table 6.4) and the
    damping ratio of each uncoupled mode (default modal damping 0.025, thesis 7.3;
    --alpha/--beta alone select Rayleigh damping alpha M + beta K)."""
    from .. import fe

    try:
        zeta_args = {"damping_ratio": damping_ratio, "alpha": alpha, "beta": beta}
        fe.damping_parameters(1, **zeta_args)  # named errors before the eigen-solve
        fr = _frame(frame)
        f, phi = fe.chassis_modes(fr, n, method, n_fixed)
        labels = fe.mode_labels(fr, phi)
        zeta = np.asarray(fe.modal_damping_ratios(f, **zeta_args))
    except ParameterError as e:
        fail(f"--n/--method/--frame/--damping-ratio/--alpha/--beta: {e}")
    used, a, b = fe.damping_parameters(1, **zeta_args)
    out = {
        "method": method,
        "damping": {"damping_ratio": float(used[0]), "alpha": float(a), "beta": float(b)},
        "modes": [
            {"mode": k + 1, "freq_hz": float(f[k]), "label": labels[k], "damping_ratio": float(zeta[k])}
            for k in range(n)
        ],
    }
    if as_json:
        emit_json(out)
    else:
        for m in out["modes"]:
            over = "  (over-critical)" if m["damping_ratio"] >= 1.0 else ""
            typer.echo(f"{m['mode']:3d} {m['freq_hz']:9.2f} Hz  zeta {m['damping_ratio']:.4f}{over}  {m['label']}")


@app.command()
def compare(
    frame: Path = FrameOpt,
    n: int = typer.Option(20, "--n", help="number of modes compared"),
    n_fixed: int = typer.Option(60, "--n-fixed", help="fixed-interface modes in the Craig-Bampton basis"),
    as_json: bool = JsonOpt,
) -> None:
    """Modal truncation vs Craig-Bampton: NRFD and MAC (thesis Fig. 6.9)."""
    from .. import fe

    try:
        c = fe.compare_reductions(_frame(frame), n, n_fixed)
    except ParameterError as e:
        fail(f"--n/--n-fixed/--frame: {e}")
    out = {k: np.asarray(v).tolist() for k, v in c.items() if k != "mac"}
    if as_json:
        emit_json(out)
    else:
        for k in range(n):
            typer.echo(f"{k + 1:3d} {out['freq_truncation_hz'][k]:9.2f} {out['freq_craig_bampton_hz'][k]:9.2f} Hz "
                       f"NRFD {out['nrfd'][k]:.2e} MAC {out['mac_diagonal'][k]:.3f}")


@app.command()
def export(
    out: Path = typer.Option(..., "--out", help="output .npz file"),
    frame: Path = FrameOpt,
    n: int = typer.Option(20, "--n", help="number of modes written"),
) -> None:
    """Write K, M, node table, DOF map and free-free modes to an NPZ file."""
    from .. import fe

    if out.suffix != ".npz":
        fail(f"--out must end in .npz, got {str(out)!r}")
    try:
        data = fe.export_npz(_frame(frame), out, n)
    except ParameterError as e:
        fail(f"--n/--frame: {e}")
    typer.echo(f"wrote {out} ({data['K'].shape[0]} DOF, {n} modes)", err=True)


@app.command()
def plot(
    out: Path = typer.Option(..., "--out", help="output folder for frame.png and modes.png"),
    frame: Path = FrameOpt,
) -> None:
    """PNG of the frame (Fig. 6.7) and of its six lowest modes (Fig. 6.8)."""
    from .. import fe
    from ..fe._plot import save_frame_and_modes

    try:
        fr = _frame(frame)
        f, phi = fe.chassis_modes(fr, 6)
        labels = fe.mode_labels(fr, phi)
    except ParameterError as e:
        fail(str(e))
    for p in save_frame_and_modes(fr, f, phi, labels, out):
        typer.echo(f"wrote {p}", err=True)
