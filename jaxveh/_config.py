"""Numerical configuration: jaxveh runs in float64 throughout.

Constraint tolerances (1e-9 m), Riccati solutions and modal reductions need double
precision, so importing :mod:`jaxveh` enables ``jax_enable_x64``. Library entry points
call :func:`check_x64`, which raises if a user switched it off afterwards.
"""

import jax

jax.config.update("jax_enable_x64", True)


def check_x64() -> None:
    """Raise ``RuntimeError`` if JAX's 64-bit mode has been disabled."""
    if not jax.config.jax_enable_x64:
        raise RuntimeError(
            "jaxveh needs float64: jax_enable_x64 was switched off after importing "
            "jaxveh. Call jax.config.update('jax_enable_x64', True)."
        )
