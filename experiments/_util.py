"""Shared helpers of the experiment scripts: output folder argument, JSON writing, JAX's disk cache."""

import argparse
import os
from pathlib import Path

import jax

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


__all__ = ["output_dir", "use_disk_cache", "write_json"]
