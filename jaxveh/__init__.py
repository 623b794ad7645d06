"""jaxveh: differentiable vehicle dynamics with a flexible chassis, in JAX.

Importing jaxveh enables float64 in JAX (see :mod:`jaxveh._core`).
"""

from . import _core as _core
from ._core import (
    GRAVITY as GRAVITY,
    ParameterError as ParameterError,
    check_x64 as check_x64,
    run_time_checks_off as run_time_checks_off,
)

__version__ = "0.1.0"
