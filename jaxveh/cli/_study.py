"""``jaxveh sweep STUDY.toml``: a study file's design grid (``optimise``), chunked, resumable,
locally or on Ray; writes a netCDF Dataset and contour / line plots."""

from pathlib import Path
from typing import Optional

import typer

from .. import ParameterError
from ._common import emit_json, fail, write_json
from ._simulate import _compilation_cache


def _table(report: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    grid = Table(title=f"{report['n_points']} points, {report['backend']} backend, {report['wall_s']:.1f} s "
                       f"({report['computed_chunks']} chunks computed, {report['reused_chunks']} reused)")
    for column in ("", "path", "units", "min", "max", "n / arg-min"):
        grid.add_column(column)
    for name, v in report["variables"].items():
        grid.add_row(name, v["path"], v["units"], f"{v['min']:.6g}", f"{v['max']:.6g}", str(v["num"]))
    for name, q in report["quantities"].items():
        if q["min"] is None:
            grid.add_row(name, "", q["units"], "nan", "nan", "")
            continue
        arg = ", ".join(f"{k}={x:.4g}" for k, x in q["argmin"].items())
        grid.add_row(name, "", q["units"], f"{q['min']:.6g}", f"{q['max']:.6g}", arg)
    console.print(grid)
    if report.get("not_converged"):
        console.print(f"[yellow]{report['not_converged']} point(s) did not converge (data variable 'converged')")
    console.print(f"dataset: {report['dataset']}")
    for plot in report["plots"]:
        console.print(f"plot: {plot}")


def sweep(
    study: Path = typer.Argument(..., help="Study file (TOML; see docs/optimise.md)."),
    backend: Optional[str] = typer.Option(None, help="local or ray (default: run.backend of the file)."),
    address: Optional[str] = typer.Option(None, help="Ray cluster address (default: start Ray locally)."),
    num_cpus: Optional[int] = typer.Option(None, "--num-cpus", help="CPUs of a locally started Ray."),
    out: Optional[Path] = typer.Option(None, help="Output folder (default: run.out of the file)."),
    chunk: Optional[int] = typer.Option(None, help="Points per compiled call."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object: dataset, n_points, ..."),
) -> None:
    """Evaluate a study's grid (resuming from OUT/chunks), write OUT/NAME.nc and plots."""
    _compilation_cache()
    import optimise

    try:
        spec = optimise.load_study(study, backend=backend, address=address, out=out, chunk=chunk,
                                   num_cpus=num_cpus)
        if not as_json:
            typer.echo(f"jaxveh sweep: {spec.name}, model {spec.model}, {spec.n_points} points in chunks of "
                       f"{spec.chunk}, {spec.backend} backend -> {spec.out}", err=True)
        result = optimise.sweep(spec, progress=not as_json)
    except (ParameterError, RuntimeError) as e:
        fail(str(e))
    report = optimise.summary(result)
    write_json(report, Path(spec.out) / f"{spec.name}.json")
    if as_json:
        emit_json(report)
    else:
        _table(report)
