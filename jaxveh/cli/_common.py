"""Helpers shared by the CLI sub-commands: JSON output and option parsing."""

import json
from pathlib import Path

import numpy as np
import typer


def new_app(help: str, **options) -> typer.Typer:
    """A Typer (sub-)application whose help texts keep square brackets: Rich's Markdown mode
    instead of its markup, which takes units and file keys (``[deg]``, ``[run] out``) for
    tags and drops them."""
    return typer.Typer(help=help, no_args_is_help=True, rich_markup_mode="markdown", **options)


def to_jsonable(obj):
    """Convert arrays, NumPy scalars and nested containers to plain Python values."""
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if hasattr(obj, "shape"):
        arr = np.asarray(obj)
        return arr.item() if arr.ndim == 0 else arr.tolist()
    if isinstance(obj, (np.floating, np.integer, np.bool_)):
        return obj.item()
    return obj


def emit_json(obj) -> None:
    """Print ``obj`` as JSON on stdout."""
    typer.echo(json.dumps(to_jsonable(obj), indent=2))


def write_json(obj, path: Path) -> None:
    """Write ``obj`` as JSON to ``path``, creating parent folders."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(to_jsonable(obj), indent=2))


def fail(message: str) -> None:
    """Print an error to stderr and exit with status 2."""
    typer.echo(f"error: {message}", err=True)
    raise typer.Exit(code=2)


def write_curve_csv(path: Path, curve: dict) -> None:
    """A skid-pad curve (name -> values per point; 2-D entries per corner or mode) as CSV."""
    header, columns = [], []
    for key, values in curve.items():
        v = np.asarray(values)
        if v.ndim == 1:
            header.append(key)
            columns.append(v)
        else:
            labels = ("fl", "fr", "rl", "rr") if key == "fz_n" else range(1, v.shape[1] + 1)
            for k, label in enumerate(labels):
                header.append(key.replace("_n", f"_{label}_n") if key == "fz_n" else f"{key}_{label}")
                columns.append(v[:, k])
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=",".join(header), comments="")
