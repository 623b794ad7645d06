"""Shared helpers of the experiment scripts: output folder argument, JSON writing, JAX's disk cache,
checks of an optimisation study's compiled values and Jacobian."""

import argparse
import os
from pathlib import Path

import jax
import numpy as np

from jaxveh.cli._common import write_json


def output_dir(default: str, description: str) -> Path:
    """Parse ``--out`` (default ``results/<default>``) and create the folder."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", type=Path, default=Path("results") / default, help="output folder")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    return out


def use_disk_cache() -> None:
    """Keep compiled programs in JAX's disk cache (``$JAXVEH_CACHE``, default
    ``~/.cache/jaxveh/jax``), so a second run of a study skips the car's compilation."""
    folder = Path(os.environ.get("JAXVEH_CACHE", Path.home() / ".cache" / "jaxveh" / "jax"))
    jax.config.update("jax_compilation_cache_dir", str(folder))
    jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)


def study_values(design, point: dict) -> dict:
    """A study's objective and constraint values (name -> value) at ``point`` (variable
    name -> value), from its compiled program (``optimise.build_design``)."""
    values, _ = design.evaluate(np.asarray(design.problem.to_z(point)))
    return {s.name: float(v) for s, v in zip(design.specs, values)}


def jacobian_check(design, point: dict, step: float = 1e-4) -> dict:
    """A study's forward-mode Jacobian (per unconstrained variable) against central
    differences of the same compiled values at ``point``: the largest error relative to
    each row's largest entry."""
    z0 = np.asarray(design.problem.to_z(point))
    _, jac = design.evaluate(z0)
    fd = np.zeros_like(jac)
    for k in range(z0.size):
        dz = np.zeros_like(z0)
        dz[k] = step
        fd[:, k] = (design.evaluate(z0 + dz)[0] - design.evaluate(z0 - dz)[0]) / (2.0 * step)
    rows = np.max(np.abs(fd), axis=1, keepdims=True)
    rows = np.where(rows > 0.0, rows, 1.0)
    return {"jacobian": jac.tolist(), "central_differences": fd.tolist(), "step_z": step,
            "max_relative_error": float(np.max(np.abs(jac - fd) / rows))}


__all__ = ["jacobian_check", "output_dir", "study_values", "use_disk_cache", "write_json"]
