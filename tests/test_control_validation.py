"""Input validation of the control API: sample times, filter orders and cut-offs, cost
weights, preview settings and the Riccati inputs give named errors, concrete and traced."""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
import pytest

from jaxveh.control import butterworth_lowpass, preview_controller, preview_distance, preview_plant, solve_dare, zoh
from jaxveh.params import ParameterError

A = np.array([[0.0, 1.0], [-2.0, -0.5]])
B = np.array([[0.0], [1.0]])
C = np.array([1.0, 0.0])


@pytest.mark.parametrize(
    "call, match",
    [
        (lambda: zoh(A, B, 0.0), r"zoh: dt must lie in \(0, inf\) \(sample time, s\); got 0"),
        (lambda: butterworth_lowpass(0, 2.0, 0.01), r"butterworth_lowpass: order must be a Python int >= 1"),
        (lambda: butterworth_lowpass(2.5, 2.0, 0.01), r"butterworth_lowpass: order must be a Python int >= 1"),
        (lambda: butterworth_lowpass(4, 2.0, -0.01), r"butterworth_lowpass: dt must lie in \(0, inf\)"),
        (lambda: butterworth_lowpass(4, 0.0, 0.01), r"butterworth_lowpass: cutoff_hz must lie in \(0, inf\)"),
        (lambda: butterworth_lowpass(4, 60.0, 0.01), r"cutoff_hz \* dt must lie in \(0, 0\.5\) \(cut-off below"),
        (lambda: preview_plant(A, B, C, n_preview=0), r"preview_plant: n_preview must be a Python int >= 1"),
        (lambda: preview_plant(A, B, C, filter_order=0), r"order must be a Python int >= 1"),
        (lambda: preview_controller(A, B, C, n_preview=20, r_weight=0.0), r"r_weight must lie in \(0, inf\)"),
        (lambda: preview_controller(A, B, C, n_preview=20, q_weight=-1.0), r"q_weight must lie in \(0, inf\)"),
        (lambda: preview_distance(jnp.ones(5), 0.0), r"preview_distance: speed must lie in \(0, inf\)"),
        (lambda: preview_distance(jnp.ones(5), 10.0, dt=0.0), r"preview_distance: dt must lie in \(0, inf\)"),
        (lambda: preview_distance(jnp.ones(5), 10.0, fraction=1.5), r"fraction must lie in \(0, 1\]"),
        (lambda: solve_dare(A, B, np.eye(2), np.eye(1), max_steps=0), r"solve_dare: max_steps must be a Python int"),
        (lambda: solve_dare(A, B, np.eye(2), np.eye(1), rtol=0.0), r"solve_dare: rtol must lie in \(0, inf\)"),
    ],
)
def test_bad_arguments_name_argument_and_range(call, match):
    with pytest.raises(ParameterError, match=match):
        call()


def test_traced_bad_values_raise_at_run_time():
    discretise = eqx.filter_jit(lambda dt: zoh(A, B, dt)[0])
    assert np.all(np.isfinite(np.asarray(discretise(jnp.asarray(0.01)))))
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"zoh: dt must lie in \(0, inf\)"):
        discretise(jnp.asarray(-0.01))
    gains = eqx.filter_jit(lambda r: preview_controller(A, B, C, n_preview=20, r_weight=r).preview)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"r_weight must lie in \(0, inf\)"):
        gains(jnp.asarray(-1.0))
    # solve_dare is jitted: r is traced inside, whether the caller's r is concrete or not.
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"solve_dare: r must be positive definite"):
        solve_dare(A, B, np.eye(2), np.zeros((1, 1)))
    nyquist = eqx.filter_jit(lambda fc: butterworth_lowpass(4, fc, 0.01).a)
    with pytest.raises(eqx.EquinoxRuntimeError, match=r"cut-off below the Nyquist frequency"):
        nyquist(jnp.asarray(51.0))
