"""Design optimisation on top of jaxveh: named design variables with bounds, targets and
constraints, solved with Optax (augmented Lagrangian around a gradient optimiser)."""

from ._problem import (
    Problem as Problem,
)
from ._problem import (
    Result as Result,
)
from ._problem import (
    Variable as Variable,
)
from ._problem import (
    get_leaf as get_leaf,
)
from ._problem import (
    set_leaves as set_leaves,
)
from ._problem import (
    solve as solve,
)
from ._problem import (
    target as target,
)
