"""Design optimisation on top of jaxveh: named design variables with bounds, targets and
constraints, solved with Optax (augmented Lagrangian around a gradient optimiser)."""

from ._problem import (
    Problem as Problem,
    Result as Result,
    Variable as Variable,
    get_leaf as get_leaf,
    set_leaves as set_leaves,
    solve as solve,
    target as target,
)
