"""Sensitivity maps at scale: a study's grid (:mod:`optimise._study`) evaluated in chunks of
one shape, each chunk one compiled call (the chapter-3 model vmapped over the chunk; the
car's designs one after the other inside the call, ``jax.lax.map``, since batching them
batches LAPACK solves, which can deadlock jaxlib 0.10.2 on CPU: docs/optimise.md),
checkpointed to disk and gathered into an xarray Dataset (netCDF) with contour / line plots.

The grid's points are numbered in C order (the first variable outermost) and cut into
chunks of ``study.chunk`` points; the last chunk is padded with copies of the grid's last
point, so every call has one shape and the car's evaluation compiles once. With several
local devices each chunk's points are sharded across them (the batch is padded to a
multiple of the device count). Every finished chunk is written to
``OUT/chunks/chunk_NNNN.npz`` (NNNN the chunk's number) beside ``OUT/chunks/manifest.json`` (the grid's hash and the
chunk size): a rerun reads the chunks there and computes only the missing ones, and refuses
a folder that holds another grid or another chunk size. ``backend = "ray"`` ships the chunks
as Ray tasks (a local ``ray.init`` or a cluster's ``address``); the workers run the same
code, so the Dataset is identical to the local backend's.

Model ``"car"``: the chapter-6 car (:func:`jaxveh.vehicle.load_car`), path variables set on
its ``CarParams`` (:func:`jaxveh.vehicle.set_car_params`, vmapped over the chunk), then λ through
the anti-roll bars (:func:`jaxveh.analysis.arb_rates_for_distribution`, on the car with the
chunk's other values, so λ is exact for every design), evaluated by
:func:`jaxveh.analysis.load_transfer_batch`; a data variable ``converged`` (1 where all the
steady states converged) comes with it. Model ``"analytic"``: the chapter-3 vehicle
(:func:`jaxveh.params.load_analytic_vehicle`), path variables first, then λ and µ by
:func:`jaxveh.analytic.with_distribution` (total roll stiffness kept), in one jitted vmap.
"""

import functools
import hashlib
import json
import os
import time
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple, Optional

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
import xarray as xr

import jaxveh
import jaxveh.analytic as analytic
from jaxveh import ParameterError, analysis, vehicle
from jaxveh.params import check_analytic_vehicle, get_at, load_analytic_vehicle, set_all, set_at

from ._objectives import objective_values, prepare
from ._study import CONVERGED, QUANTITIES, SWEEP_LABELS, Study, check_study, quantity_specs

#: File of the chunk manifest inside ``OUT/chunks``.
MANIFEST = "manifest.json"
#: netCDF engine (the one :func:`jaxveh.manoeuvre.write_netcdf` uses: SciPy, netCDF3).
NETCDF_ENGINE = "scipy"


# ---- the grid -------------------------------------------------------------------------------


def grid_points(study: Study, start: int = 0, stop: Optional[int] = None) -> np.ndarray:
    """Grid points ``start`` to ``stop`` (flat C-order indices) as an ``(n, n_variables)``
    float64 array, the first variable outermost."""
    stop = study.n_points if stop is None else stop
    index = np.unravel_index(np.arange(start, stop), study.shape)
    return np.stack([np.asarray(v.values)[i] for v, i in zip(study.variables, index)], axis=-1)


def chunk_ranges(study: Study) -> list[tuple[int, int]]:
    """``(start, stop)`` flat indices of every chunk."""
    n, c = study.n_points, study.chunk
    return [(s, min(n, s + c)) for s in range(0, n, c)]


def _file_digest(path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest() if path else "shipped"


def grid_hash(study: Study) -> str:
    """SHA-256 of everything that fixes the grid's values: the model, the vehicle file's
    contents, the mode count, the variables (names, paths, values), the quantities and the
    car's ay and radius. The run settings (backend, chunk, folder) are not in it."""
    spec = {
        "model": study.model,
        "vehicle": _file_digest(study.vehicle),
        "modes": study.modes if study.model == "car" else None,
        "variables": [[v.name, v.path, [float(x).hex() for x in v.values]] for v in study.variables],
        "quantities": list(study.quantities),
        "ay_g": [float(a).hex() for a in study.ay_g] if study.model == "car" else None,
        "radius": float(study.radius).hex() if study.model == "car" else None,
        "settings": [[name, [[k, repr(v)] for k, v in items]] for name, items in study.settings],
    }
    return hashlib.sha256(json.dumps(spec, sort_keys=True).encode()).hexdigest()


def _outputs(study: Study) -> tuple[str, ...]:
    return study.quantities + ((CONVERGED,) if study.model == "car" else ())


# ---- the models -----------------------------------------------------------------------------


class Model(NamedTuple):
    """A study's model: the base parameter pytree holder ``base`` (the ``Car`` or the
    ``AnalyticVehicle``) and ``evaluate(points) -> {output: (n,) array}`` on an
    ``(n, n_variables)`` array of grid points (one compiled call per shape of ``points``)."""

    base: object
    evaluate: Callable


def _model_where(study: Study, i: int) -> str:
    return study.where(f"variables[{i}].path")


def _check_path(study: Study, i: int, tree, check: Callable) -> None:
    """The variable's path exists, names one number, and each of its values passes ``check``."""
    var = study.variables[i]
    where = _model_where(study, i)
    try:
        leaf = get_at(tree, var.path)
    except ParameterError as e:
        raise ParameterError(f"{where} = {var.path!r} is not allowed: {e}") from None
    if not eqx.is_array_like(leaf):
        raise ParameterError(f"{where} = {var.path!r} is not allowed: it names a {type(leaf).__name__}, not a "
                             "number; name one of its fields")
    if np.ndim(leaf):
        raise ParameterError(f"{where} = {var.path!r} is not allowed: it names an array of shape "
                             f"{list(np.shape(leaf))}; a variable needs one number, add its indices "
                             f"(e.g. {var.path}[{', '.join(['0'] * np.ndim(leaf))}])")
    if not np.issubdtype(np.asarray(leaf).dtype, np.floating):
        raise ParameterError(f"{where} = {var.path!r} is not allowed: it names a {np.asarray(leaf).dtype} "
                             "value; a variable needs a float parameter")
    for x in var.values:
        try:
            check(set_at(tree, var.path, x))
        except ParameterError as e:
            raise ParameterError(f"{study.where(f'variables[{i}]')} value {x!r} of {var.path!r} is out of "
                                 f"range: {e}") from None


def _split(study: Study):
    """(indices and paths of the path variables, {label: index})."""
    paths = tuple((i, v.path) for i, v in enumerate(study.variables) if v.path not in SWEEP_LABELS[study.model])
    labels = {v.path: i for i, v in enumerate(study.variables) if v.path in SWEEP_LABELS[study.model]}
    return paths, labels


def _devices():
    return jax.local_devices()


def _shard(tree, n: int):
    """Put the leading axis (length ``n``) of every leaf across the local devices (when there
    are several and ``n`` divides evenly)."""
    devices = _devices()
    if len(devices) < 2 or n % len(devices):
        return tree
    mesh = jax.sharding.Mesh(np.asarray(devices), ("points",))
    sharding = jax.sharding.NamedSharding(mesh, jax.sharding.PartitionSpec("points"))
    return jax.tree.map(lambda x: jax.device_put(x, sharding) if eqx.is_array(x) and x.ndim else x, tree)


def _batch_size(n: int) -> int:
    d = len(_devices())
    return -(-n // d) * d


def _pad(points: np.ndarray, size: int) -> np.ndarray:
    """``points`` padded to ``size`` rows with copies of the last row."""
    extra = size - points.shape[0]
    return np.concatenate([points, np.repeat(points[-1:], extra, axis=0)]) if extra > 0 else points


_ANALYTIC = {
    "chi": analytic.chi,
    "chi_rigid": analytic.chi_rigid,
    "chi_error": lambda v: jnp.abs(analytic.chi(v) - analytic.chi_rigid(v)) / analytic.chi_rigid(v),
    "understeer_gradient": lambda v: analytic.understeer_gradient(v) * analytic.RAD_PER_MS2_TO_DEG_PER_G,
    "understeer_gradient_rigid": lambda v: analytic.understeer_gradient_rigid(v) * analytic.RAD_PER_MS2_TO_DEG_PER_G,
}
assert set(_ANALYTIC) == set(QUANTITIES["analytic"])


def _analytic_point(vehicle_, x, paths, labels, quantities):
    """The chapter-3 quantities at one grid point ``x``: paths first, then λ and µ."""
    v = set_all(vehicle_, {p: x[i] for i, p in paths})
    lam = x[labels["lambda"]] if "lambda" in labels else None
    mu = x[labels["mu"]] if "mu" in labels else None
    if lam is not None or mu is not None:
        v = analytic.with_distribution(v, lam=lam, mu=mu)
    return {q: _ANALYTIC[q](v) for q in quantities}


@eqx.filter_jit
def _analytic_batch(vehicle_, points, paths, labels, quantities):
    return jax.vmap(lambda x: _analytic_point(vehicle_, x, paths, dict(labels), quantities))(points)


def _analytic_model(study: Study) -> Model:
    base = load_analytic_vehicle(study.vehicle)
    paths, labels = _split(study)
    for i, _ in paths:
        _check_path(study, i, base, check_analytic_vehicle)
    labels_t = tuple(sorted(labels.items()))

    def evaluate(points):
        n = points.shape[0]
        size = _batch_size(n)
        x = _shard(jnp.asarray(_pad(np.asarray(points, np.float64), size)), size)
        out = _analytic_batch(base, x, paths, labels_t, study.quantities)
        return {q: np.asarray(out[q])[:n] for q in study.quantities}

    return Model(base=base, evaluate=evaluate)


def car_designs(car, study: Study, points: np.ndarray, memo: Optional[dict] = None):
    """Stacked ``CarParams`` of the grid ``points`` (``(n, n_variables)``): the path
    variables set by one vmapped :func:`jaxveh.vehicle.set_car_params`, then λ through the anti-roll
    bars on the car with each point's other values: one vectorised
    :func:`jaxveh.analysis.arb_rates_for_distribution` call per distinct set of them, for
    every λ of the grid at once, kept in ``memo`` (a dict the caller keeps between chunks)."""
    paths, labels = _split(study)
    pts = jnp.asarray(points, jnp.float64)
    stacked = eqx.filter_vmap(lambda x: vehicle.set_car_params(car.params, {p: x[i] for i, p in paths}))(pts)
    if "lambda" not in labels:
        return stacked
    memo = {} if memo is None else memo
    k = labels["lambda"]
    others = [i for i, _ in paths]
    points = np.asarray(points, np.float64)
    keys = [tuple(row) for row in points[:, others]]
    for key in dict.fromkeys(keys):
        rows = [j for j, kk in enumerate(keys) if kk == key]
        if any((key, points[j, k]) not in memo for j in rows):
            lams = np.union1d(study.variables[k].values, points[rows, k])
            one = jax.tree.map(lambda x, r=rows[0]: x[r] if eqx.is_array(x) else x, stacked)
            design = eqx.tree_at(lambda c: c.params, car, one)
            rates = np.asarray(analysis.arb_rates_for_distribution(design, jnp.asarray(lams)))
            memo.update({(key, lam): r for lam, r in zip(lams, rates)})
    rates = np.stack([memo[(key, points[j, k])] for j, key in enumerate(keys)])
    return eqx.tree_at(lambda p: p.arb_rates, stacked, jnp.asarray(rates))


def _objectives_batch(car, designs, specs, prepared, speeds):
    """The objectives ``specs`` of the car with each of the stacked ``designs``, at each of
    ``speeds`` (km/h; ``None``: the specs' own), one design after the other inside the
    compiled call (``jax.lax.map``: batched LAPACK solves can deadlock, as in
    :func:`jaxveh.analysis.load_transfer_batch`)."""
    def one(args):
        p, speed = args
        overrides = None if speed is None else {"speed_kmh": speed}
        return objective_values(eqx.tree_at(lambda c: c.params, car, p), specs, prepared, overrides=overrides)

    return jax.lax.map(one, (designs, speeds))


_compiled_objectives = eqx.filter_jit(_objectives_batch)


def _car_model(study: Study) -> Model:
    car = vehicle.load_car(study.vehicle, modes=study.modes)
    paths, _ = _split(study)
    check = lambda params: vehicle.check_car(eqx.tree_at(lambda c: c.params, car, params))
    for i, _ in paths:
        _check_path(study, i, car.params, check)
    specs = quantity_specs(study)
    prepared = prepare(car, specs)
    speed = _split(study)[1].get("speed_kmh")

    memo = {}  # anti-roll-bar rates by (other values, λ): one call per distinct other values

    def evaluate(points):
        points = np.asarray(points, np.float64)
        n = points.shape[0]
        size = _batch_size(n)
        designs = _shard(car_designs(car, study, _pad(points, size), memo), size)
        out, ok = {}, np.ones(n, dtype=bool)
        if "chi" in study.quantities:
            lt = analysis.load_transfer_batch(car, designs, study.ay_g, study.radius)
            out["chi"] = np.asarray(lt.chi_low_ay)[:n]
            ok &= np.asarray(jnp.all(lt.ok, axis=-1))[:n]
        if specs:
            speeds = None if speed is None else _shard(jnp.asarray(_pad(points, size)[:, speed]), size)
            with jaxveh.run_time_checks_off():  # every value of each variable was checked on the car
                values = np.asarray(_compiled_objectives(car, designs, specs, prepared, speeds))[:n]
            for j, spec in enumerate(specs):
                out[spec.name] = values[:, j]
            ok &= np.all(np.isfinite(values), axis=1)
        out[CONVERGED] = ok.astype(np.int8)
        return out

    return Model(base=car, evaluate=evaluate)


def _model_key(study: Study) -> Study:
    """The study with its run settings neutral (models are shared between runs)."""
    return study._replace(backend="local", chunk=1, out="", address=None, num_cpus=None, description="", name="s",
                          file=None)


@functools.lru_cache(maxsize=4)
def _cached_model(key: Study, file: Optional[str], digest: str) -> Model:
    study = key._replace(file=file)
    return _car_model(study) if study.model == "car" else _analytic_model(study)


def build_model(study: Study) -> Model:
    """The study's :class:`Model`: loads the vehicle and checks each path variable (it exists,
    names one number, every value of it is in range; ``ParameterError`` naming the file and
    key). Kept per process (the car takes a while to load, its programs to compile)."""
    check_study(study)
    return _cached_model(_model_key(study), study.file, _file_digest(study.vehicle))


# ---- checkpoints ----------------------------------------------------------------------------


def _chunk_file(folder: Path, index: int) -> Path:
    return folder / f"chunk_{index:04d}.npz"


def _prepare(study: Study, folder: Path, digest: str) -> dict:
    """Create or check ``folder``'s manifest; refuse another grid or chunk size."""
    manifest = {"grid_hash": digest, "chunk": study.chunk, "n_points": study.n_points,
                "n_chunks": len(chunk_ranges(study)), "shape": list(study.shape),
                "variables": [v.name for v in study.variables], "outputs": list(_outputs(study)),
                "model": study.model}
    path = folder / MANIFEST
    if path.is_file():
        try:
            old = json.loads(path.read_text())
        except json.JSONDecodeError:
            old = None
        if not isinstance(old, dict) or old.get("grid_hash") != digest:
            raise ParameterError(f"{folder} holds the chunks of another grid (manifest grid_hash "
                                 f"{(old or {}).get('grid_hash')!r}, this study's {digest!r}): use another "
                                 "output folder (--out) or delete that one")
        if old.get("chunk") != study.chunk:
            raise ParameterError(f"{folder} holds chunks of {old.get('chunk')} points, this run asks for "
                                 f"{study.chunk}: rerun with --chunk {old.get('chunk')} to resume, or use "
                                 "another output folder (--out)")
        return old
    folder.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(manifest, indent=2))
    os.replace(tmp, path)
    return manifest


def _save_chunk(folder: Path, index: int, start: int, stop: int, digest: str, values: dict) -> None:
    tmp = folder / f".chunk_{index:04d}.tmp.npz"
    with open(tmp, "wb") as f:
        np.savez(f, start=start, stop=stop, grid_hash=digest, **values)
    os.replace(tmp, _chunk_file(folder, index))


def _load_chunk(folder: Path, index: int, start: int, stop: int, digest: str, outputs) -> Optional[dict]:
    """A finished chunk's values, or ``None`` if absent, unreadable or not this grid's."""
    path = _chunk_file(folder, index)
    if not path.is_file():
        return None
    try:
        with np.load(path) as data:
            if (str(data["grid_hash"]) != digest or int(data["start"]) != start or int(data["stop"]) != stop):
                return None
            values = {k: np.asarray(data[k]) for k in outputs}
    except (OSError, KeyError, ValueError):
        return None
    if any(v.shape != (stop - start,) for v in values.values()):
        return None
    return values


# ---- backends -------------------------------------------------------------------------------


def _progress(enabled: bool, total: int, description: str):
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                        TimeRemainingColumn(), console=Console(stderr=True), disable=not enabled)
    return progress, progress.add_task(description, total=total)


def _chunk_points(study: Study, start: int, stop: int) -> np.ndarray:
    """A chunk's points padded to the one chunk shape (``chunk`` rows, or all the points when
    the grid is smaller than a chunk)."""
    return _pad(grid_points(study, start, stop), min(study.chunk, study.n_points))


def _run_local(study, todo, evaluate, done):
    for index, (start, stop) in todo:
        points = _chunk_points(study, start, stop)
        values = evaluate(points)
        done(index, {k: np.asarray(v)[: stop - start] for k, v in values.items()})


def _worker_chunk(study: Study, start: int, stop: int, cache_dir: Optional[str]) -> dict:
    """A Ray task: one chunk's outputs (unpadded), on a worker (float64 from importing jaxveh)."""
    jaxveh.check_x64()
    if cache_dir and not jax.config.jax_compilation_cache_dir:
        jax.config.update("jax_compilation_cache_dir", cache_dir)
        jax.config.update("jax_persistent_cache_min_compile_time_secs", 1.0)
    values = build_model(study).evaluate(_chunk_points(study, start, stop))
    return {k: np.asarray(v)[: stop - start] for k, v in values.items()}


def _run_ray(study, todo, done):
    try:
        import ray
    except ImportError:
        raise ParameterError(f"{study.where('run.backend')} = 'ray' needs Ray: pip install 'jaxveh[cluster]'") from None
    started = False
    if not ray.is_initialized():
        with warnings.catch_warnings():
            # Ray starts its processes by fork + exec, which JAX's fork warning cannot tell apart.
            warnings.filterwarnings("ignore", message="os.fork", category=RuntimeWarning)
            if study.address:
                ray.init(address=study.address, log_to_driver=False)
            else:
                ray.init(num_cpus=study.num_cpus, include_dashboard=False, log_to_driver=False)
        started = True
    try:
        task = ray.remote(num_cpus=1)(_worker_chunk)
        cache = jax.config.jax_compilation_cache_dir or None
        pending = {task.remote(study, start, stop, cache): (index, start, stop) for index, (start, stop) in todo}
        while pending:
            ready, _ = ray.wait(list(pending), num_returns=1)
            index, _, _ = pending.pop(ready[0])
            done(index, ray.get(ready[0]))
    finally:
        if started:
            ray.shutdown()


# ---- the Dataset ----------------------------------------------------------------------------


def sweep_dataset(study: Study, values: dict, digest: str) -> xr.Dataset:
    """The Dataset of the flat grid ``values`` ({output: (n_points,)}): one dimension per
    variable (coordinates with ``units``, ``path``), one data variable per output."""
    dims = [v.name for v in study.variables]
    coords = {v.name: (v.name, np.asarray(v.values), {"units": v.units, "path": v.path,
                                                       "scale": "log" if v.log else "linear"})
              for v in study.variables}
    data = {}
    for q in study.quantities:
        units, description = QUANTITIES[study.model][q]
        data[q] = (dims, np.asarray(values[q], np.float64).reshape(study.shape),
                   {"units": units, "long_name": description})
    if study.model == "car":
        data[CONVERGED] = (dims, np.asarray(values[CONVERGED], np.int8).reshape(study.shape),
                           {"units": "1", "long_name": "1 where every steady state of the point converged"})
    attrs = {"study": study.name, "description": study.description, "model": study.model,
             "vehicle": study.vehicle or "shipped", "grid_hash": digest, "n_points": study.n_points,
             "software": f"jaxveh {jaxveh.__version__}"}
    if study.model == "car":
        attrs.update(modes=study.modes, ay_g=np.asarray(study.ay_g, float), radius_m=float(study.radius))
    return xr.Dataset(data, coords=coords, attrs=attrs)


def plot_sweep(dataset: xr.Dataset, quantity: str, path):
    """Line (one variable) or filled contour (two variables; log axes where the grid is
    geometric) plot of ``dataset[quantity]`` saved to ``path``; ``None`` for more variables."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    da = dataset[quantity]
    if da.ndim not in (1, 2):
        return None
    label = f"{quantity} ({da.attrs.get('units', '')})"
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    axes = [dataset[d] for d in da.dims]

    def axis_label(c):
        path = c.attrs.get("path", c.name)
        return f"{c.name}{f' = {path}' if path != c.name else ''} ({c.attrs.get('units', '')})"

    if da.ndim == 1:
        ax.plot(axes[0].values, da.values, "o-")
        ax.set_xlabel(axis_label(axes[0]))
        ax.set_ylabel(label)
        if axes[0].attrs.get("scale") == "log":
            ax.set_xscale("log")
    else:
        y, x = axes
        if len(x) < 2 or len(y) < 2:
            plt.close(fig)
            return None
        cs = ax.contourf(x.values, y.values, da.values, levels=12)
        ax.contour(x.values, y.values, da.values, levels=cs.levels, colors="k", linewidths=0.4)
        fig.colorbar(cs, ax=ax, label=label)
        ax.set_xlabel(axis_label(x))
        ax.set_ylabel(axis_label(y))
        for c, setter in ((x, ax.set_xscale), (y, ax.set_yscale)):
            if c.attrs.get("scale") == "log":
                setter("log")
    ax.set_title(dataset.attrs.get("study", ""))
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    plt.close(fig)
    return path


# ---- the sweep ------------------------------------------------------------------------------


class SweepResult(NamedTuple):
    """A finished sweep: the ``dataset``, the netCDF file ``path``, the ``plots`` written,
    ``n_points``, the chunk indices ``computed`` in this run and ``reused`` from disk, the
    ``backend`` and the wall time ``wall_s`` (s)."""

    dataset: xr.Dataset
    path: Path
    plots: tuple[Path, ...]
    n_points: int
    computed: tuple[int, ...]
    reused: tuple[int, ...]
    backend: str
    wall_s: float


def sweep(study: Study, *, progress: bool = False, evaluate: Optional[Callable] = None,
          plots: bool = True) -> SweepResult:
    """Evaluate ``study``'s grid chunk by chunk on its backend, resuming from the chunks
    already in ``study.out``/chunks (module docs); write ``OUT/NAME.nc`` and, for one or two
    variables, ``OUT/NAME_QUANTITY.png``. ``evaluate`` replaces the model's
    ``evaluate(points) -> {output: values}`` (local backend only; e.g. to count calls).
    ``progress`` shows a progress bar on stderr."""
    t0 = time.perf_counter()
    check_study(study)
    if evaluate is not None and study.backend != "local":
        raise ParameterError(f"{study.where('run.backend')} = {study.backend!r}: a custom evaluate runs on the "
                             "local backend only")
    out = Path(study.out)
    folder = out / "chunks"
    digest = grid_hash(study)
    outputs = _outputs(study)
    if evaluate is None:
        evaluate = build_model(study).evaluate  # checks every path before any chunk runs, Ray or not
    _prepare(study, folder, digest)
    ranges = chunk_ranges(study)
    flat = {k: np.full(study.n_points, np.nan) for k in outputs}
    todo, reused = [], []
    for index, (start, stop) in enumerate(ranges):
        values = _load_chunk(folder, index, start, stop, digest, outputs)
        if values is None:
            todo.append((index, (start, stop)))
        else:
            reused.append(index)
            for k in outputs:
                flat[k][start:stop] = values[k]
    computed = []
    bar, task = _progress(progress, len(ranges), f"{study.name}: {study.n_points} points")
    with bar:
        bar.update(task, completed=len(reused))

        def done(index, values):
            start, stop = ranges[index]
            missing = [k for k in outputs if k not in values]
            if missing:
                raise RuntimeError(f"chunk {index}: the evaluation returned no {missing}")
            values = {k: np.asarray(values[k])[: stop - start] for k in outputs}
            _save_chunk(folder, index, start, stop, digest, values)
            for k in outputs:
                flat[k][start:stop] = values[k]
            computed.append(index)
            bar.advance(task)

        if todo:
            if study.backend == "ray":
                _run_ray(study, todo, done)
            else:
                _run_local(study, todo, evaluate, done)
    dataset = sweep_dataset(study, flat, digest)
    path = out / f"{study.name}.nc"
    dataset.to_netcdf(path, engine=NETCDF_ENGINE)
    written = []
    if plots:
        for q in study.quantities:
            p = plot_sweep(dataset, q, out / f"{study.name}_{q}.png")
            if p is not None:
                written.append(p)
    return SweepResult(dataset=dataset, path=path, plots=tuple(written), n_points=study.n_points,
                       computed=tuple(sorted(computed)), reused=tuple(reused), backend=study.backend,
                       wall_s=time.perf_counter() - t0)


def summary(result: SweepResult) -> dict:
    """JSON-ready summary: ``dataset`` (path), ``n_points``, chunks computed and reused, the
    backend, wall time, plots, and min / max of every quantity (and its arg-min point)."""
    ds = result.dataset
    quantities = {}
    for name, da in ds.data_vars.items():
        if name == CONVERGED:
            continue
        values = da.values
        finite = np.isfinite(values)
        entry = {"units": da.attrs.get("units", ""), "min": None, "max": None, "argmin": None}
        if finite.any():
            i = np.unravel_index(np.nanargmin(values), values.shape)
            entry.update(min=float(np.nanmin(values)), max=float(np.nanmax(values)),
                         argmin={d: float(ds[d].values[j]) for d, j in zip(da.dims, i)})
        quantities[name] = entry
    out = {"dataset": str(result.path), "n_points": int(result.n_points), "backend": result.backend,
           "computed_chunks": len(result.computed), "reused_chunks": len(result.reused),
           "wall_s": float(result.wall_s), "plots": [str(p) for p in result.plots], "quantities": quantities,
           "variables": {d: {"units": ds[d].attrs.get("units", ""), "path": ds[d].attrs.get("path", d),
                             "min": float(ds[d].min()), "max": float(ds[d].max()), "num": int(ds.sizes[d])}
                         for d in ds.dims}}
    if CONVERGED in ds:
        out["not_converged"] = int(ds[CONVERGED].size - int(ds[CONVERGED].sum()))
    return out
