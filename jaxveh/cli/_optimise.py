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


def _stiffness_table(report: dict) -> None:
    from rich.console import Console
    from rich.table import Table

    console = Console()
    table = Table(title=f"{report['study']}: within {report['tolerance'] * 100:g} % of the rigid car at lambda = "
                        f"{', '.join(f'{x:g}' for x in report['lambda'])} ({report['evaluations']} designs, "
                        f"{report['wall_s']:.0f} s)")
    for column in ("mode", "mu_min", "f_min (Hz)", "f at mu = 1 (Hz)", "binding", "status"):
        table.add_column(column)
    for m in report["per_mode"]:
        mu = "-" if m["mu_min"] is None else f"{m['mu_min']:.4g}"
        f = "-" if m["frequency_hz"] is None else f"{m['frequency_hz']:.1f}"
        binding = "" if m["binding_quantity"] is None else f"{m['binding_quantity']} at lambda {m['binding_lambda']:g}"
        table.add_row(str(m["mode"]), mu, f, f"{m['nominal_frequency_hz']:.1f}", binding, m["status"])
    console.print(table)
    joint = report["joint"]
    if joint is not None and joint["factor"] is not None:
        console.print(f"all modes at their minima: worst deviation {joint['worst_deviation_at_minima']}; common "
                      f"factor {joint['factor']:.4g} -> mu = {[round(m, 4) for m in joint['mu']]}")
    for kind, path in report["files"].items():
        console.print(f"{kind}: {path}")


def _stiffness(opt, study: Path, out: Optional[Path], as_json: bool) -> None:
    try:
        spec = opt.load_stiffness_study(study, out=out)
        if not as_json:
            typer.echo(f"jaxveh optimise: {spec.name}, how stiff is stiff enough ({spec.modes} modes) -> {spec.out} "
                       "(the first run compiles the car: minutes)", err=True)
        result = opt.stiffness_requirement(spec, progress=None if as_json else (lambda s: typer.echo(s, err=True)))
    except ParameterError as e:
        fail(str(e))
    except RuntimeError as e:
        typer.echo(f"error: {e}", err=True)
        raise typer.Exit(code=1) from None
    files = opt.write_stiffness_outputs(result)
    report = opt.stiffness_report(result) | {"files": files}
    if as_json:
        emit_json(report)
    else:
        _stiffness_table(report)


def _pareto(opt, spec, as_json: bool) -> None:
    c = spec.constraints[spec.pareto.constraint]
    if not as_json:
        typer.echo(f"jaxveh optimise: {spec.name}, epsilon-constraint front over {c.spec.name} {c.kind} "
                   f"{', '.join(f'{v:g}' for v in spec.pareto.values)} -> {spec.out}", err=True)
    front = opt.pareto_front(spec, progress=None if as_json else (lambda s: typer.echo("  " + s, err=True)))
    files = opt.write_pareto_outputs(front)
    report = opt.pareto_report(front) | {"files": files}
    if as_json:
        emit_json(report)
        return
    from rich.console import Console
    from rich.table import Table

    table = Table(title=f"{spec.name}: objective against {c.spec.name} {c.kind} bound ({front.wall_s:.0f} s)")
    names = [v.name for v in spec.variables]
    for column in ("bound", "objective", c.spec.name, *names, "active", "status"):
        table.add_column(column)
    for p in report["points"]:
        status = "failed" if p["failed"] else "converged" if p["converged"] else "not converged"
        fmt = lambda x: "-" if x is None else f"{x:.6g}"  # noqa: E731
        table.add_row(f"{p['bound']:g}", fmt(p["objective"]), fmt(p["constrained_value"]),
                      *(fmt(p["optimum"][n]) for n in names), str(p["active"]), status)
    console = Console()
    console.print(table)
    for kind, path in files.items():
        console.print(f"{kind}: {path}")


def optimise(
    study: Path = typer.Argument(..., help="Study file (TOML; see docs/objectives.md): an optimisation, or a "
                                           "stiffness requirement (a [requirement] table)."),
    out: Optional[Path] = typer.Option(None, help="Output folder (default: the file's [run] out)."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object: optimum, objective, converged, ..."),
) -> None:
    """Optimise a study's design variables; write OUT/NAME.json, OUT/NAME_history.csv and the
    optimum's car file OUT/NAME_car.toml. A stiffness-requirement study (how stiff is stiff
    enough) writes OUT/NAME.json and OUT/NAME.png."""
    _compilation_cache()
    import optimise as opt

    if opt.is_stiffness_study(study):
        _stiffness(opt, study, out, as_json)
        return
    try:
        spec = opt.load_optimisation_study(study, out=out)
        if spec.pareto is not None:
            _pareto(opt, spec, as_json)
            return
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
