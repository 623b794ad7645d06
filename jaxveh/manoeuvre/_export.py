"""Export of a manoeuvre's channels as an xarray Dataset (netCDF): a ``time`` coordinate in
seconds, per-corner channels on a ``corner`` axis (FL, FR, RL, RR), modal coordinates on a
``mode`` axis (1 ... n; no modal variable for a rigid chassis), each variable's unit in
its ``units`` attribute."""

from pathlib import Path

import numpy as np

from ..vehicle import CORNERS

#: Corner labels of the ``corner`` coordinate, in the channels' order: FL, FR, RL, RR.
CORNER_LABELS = tuple("".join(word[0] for word in c.split("_")).upper() for c in CORNERS)


def run_dataset(run, attrs: dict | None = None):
    """The :class:`CarRun` ``run`` as an :class:`xarray.Dataset` (see module docs);
    ``attrs``: global attributes (strings or numbers: manoeuvre, speed, ...)."""
    import xarray as xr

    n_modes = np.asarray(run.channels["modes"]).shape[-1] if "modes" in run.channels else 0
    data = {}
    for name, values in run.channels.items():
        v = np.asarray(values)
        if v.size == 0:  # the rigid car's modal coordinates: netCDF 3 has no empty fixed axis
            continue
        if v.ndim == 1:
            dims = ("time",)
        elif name == "modes":
            dims = ("time", "mode")
        else:
            dims = ("time", "corner")
        data[name] = (dims, v, {"units": run.units[name]})
    coords = {"time": ("time", np.asarray(run.ts), {"units": "s"}), "corner": list(CORNER_LABELS)}
    if n_modes:
        coords["mode"] = np.arange(1, n_modes + 1)
    meta = {"form": run.form, "stop_reason": run.stop_reason, "steps": int(run.steps),
            "rejected_steps": int(run.rejected_steps)} | (attrs or {})
    return xr.Dataset(data, coords=coords, attrs=meta)


def write_netcdf(run, path, attrs: dict | None = None) -> Path:
    """Write :func:`run_dataset` to ``path`` (netCDF 3, SciPy's writer: no compiled netCDF
    library needed); returns the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    run_dataset(run, attrs).to_netcdf(path, engine="scipy")
    return path
