"""Shared helpers of the experiment scripts: output folder argument and JSON writing."""

import argparse
from pathlib import Path

from jaxveh.cli._common import write_json


def output_dir(default: str, description: str) -> Path:
    """Parse ``--out`` (default ``results/<default>``) and create the folder."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--out", type=Path, default=Path("results") / default, help="output folder")
    out = parser.parse_args().out
    out.mkdir(parents=True, exist_ok=True)
    return out


__all__ = ["output_dir", "write_json"]
