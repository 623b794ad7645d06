"""jaxveh: differentiable vehicle dynamics with a flexible chassis, in JAX.

Importing jaxveh enables float64 in JAX (see :mod:`jaxveh._config`).
"""

from . import _config as _config
from ._config import check_x64 as check_x64

__version__ = "0.1.0"
