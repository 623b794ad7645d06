"""``jaxveh optimise STUDY.toml``: an optimisation study file (``optimise``) on the car:
progress per iteration, a summary table, the history (JSON, CSV) and the optimum as a car
file for ``--vehicle``."""

import math
from pathlib import Path
from typing import Optional

import typer

from .. import ParameterError
from ._common import emit_json, fail
from ._simulate import _compilation_cache


def _progress(entry: dict, names) -> None:
    variables = "  ".join(f"{k} {entry[k]:.6g}" for k in names)
    typer.echo(f"  {entry['iteration']:3d}  objective {entry['objective']:.6e}  |grad| {entry['grad_norm']:.2e}  "
               f"{variables}", err=True)


def _table(report: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    status = "converged" if report["converged"] else "not converged"
    table = Table(title=f"{report['study']}: {status} after {report['iterations']} iterations, "
                        f"{report['evaluations']} evaluations, {report['wall_s']:.1f} s ({report['method']}, "
                        f"{report['modes']} modes)")
    for column in ("", "value", "units", "bounds / initial"):
        table.add_column(column)
    for name, value in report["optimum"].items():
        v = report["variables"][name]
        table.add_row(name, f"{value:.8g}", v["units"], f"[{v['lower']:g}, {v['upper']:g}] from {v['initial']:g}")
    for name, value in report["values"].items():
        table.add_row(name, f"{value:.8g}", report["units"][name], "")
    for c in report["constraints"]:
        table.add_row(f"{c['name']} {c['kind']} {c['bound']:g}", f"{c['value']:.8g}", "",
                      f"violation {c['violation']:.2e}")
    table.add_row("objective", f"{report['objective']:.6e}", "", "")
    console.print(table)
    console.print(report["message"])
    for kind, path in report["files"].items():
        console.print(f"{kind}: {path}")


def optimise(
    study: Path = typer.Argument(..., help="Optimisation study file (TOML; see docs/objectives.md)."),
    out: Optional[Path] = typer.Option(None, help="Output folder (default: the file's [run] out)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object: optimum, objective, converged, ..."),
) -> None:
    """Optimise a study's design variables; write OUT/NAME.json, OUT/NAME_history.csv and the
    optimum's car file OUT/NAME_car.toml."""
    _compilation_cache()
    import optimise as opt

    try:
        spec = opt.load_optimisation_study(study, out=out)
        names = [v.name for v in spec.variables]
        if not as_json:
            typer.echo(f"jaxveh optimise: {spec.name}, {spec.modes} modes, {', '.join(names)} by "
                       f"{spec.optimiser['method']} -> {spec.out} (the first run compiles the car: minutes)", err=True)
        progress = None if as_json else (lambda entry: _progress(entry, names))
        result = opt.optimise_study(spec, progress=progress, throw=False)
    except ParameterError as e:
        fail(str(e))
    files = opt.write_outputs(result)
    report = opt.result_report(result, files)
    if as_json:
        emit_json({k: v for k, v in report.items() if k != "history"}
                  | {"objective": report["objective"] if math.isfinite(report["objective"]) else None})
    else:
        _table(report)
    if result.failed:
        typer.echo(f"error: {result.message} (history in {files['csv']})", err=True)
        raise typer.Exit(code=1)
