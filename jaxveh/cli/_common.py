"""Helpers shared by the CLI sub-commands: JSON output and option parsing."""

import json
from pathlib import Path

import numpy as np
import typer


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
