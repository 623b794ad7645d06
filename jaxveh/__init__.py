"""jaxveh: differentiable vehicle dynamics with a flexible chassis, in JAX.

Importing jaxveh enables float64 in JAX (see :mod:`jaxveh._core`) and, with
``JAXVEH_XLA_FLAGS=1``, XLA's classic CPU fusion emitters (see :mod:`jaxveh._xla`).
"""

from . import _xla as _xla

_xla.apply_cpu_flags()

from . import _core as _core  # noqa: E402
from ._core import (  # noqa: E402
    GRAVITY as GRAVITY,
    ParameterError as ParameterError,
    check_x64 as check_x64,
    run_time_checks_off as run_time_checks_off,
)
from ._parallel import core_count as core_count, map_on_cores as map_on_cores  # noqa: E402

__version__ = "0.1.0"
