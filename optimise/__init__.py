"""Design optimisation on top of jaxveh: named design variables with bounds, targets and
constraints, solved with Optax (augmented Lagrangian around a gradient optimiser); study
files and sensitivity maps at scale (``sweep``: chunked vmap, checkpoints, Ray)."""

from ._problem import (
    Problem as Problem,
    Result as Result,
    Variable as Variable,
    get_leaf as get_leaf,
    set_leaves as set_leaves,
    solve as solve,
    target as target,
)
from ._study import (
    BACKENDS as BACKENDS,
    LABELS as LABELS,
    MAX_POINTS as MAX_POINTS,
    MODELS as MODELS,
    QUANTITIES as QUANTITIES,
    Study as Study,
    SweepVariable as SweepVariable,
    check_study as check_study,
    load_study as load_study,
)
from ._sweep import (
    Model as Model,
    SweepResult as SweepResult,
    build_model as build_model,
    car_designs as car_designs,
    chunk_ranges as chunk_ranges,
    grid_hash as grid_hash,
    grid_points as grid_points,
    plot_sweep as plot_sweep,
    summary as summary,
    sweep as sweep,
    sweep_dataset as sweep_dataset,
)
