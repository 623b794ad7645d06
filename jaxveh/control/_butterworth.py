"""Digital Butterworth low-pass filter in state-space form (the road filter of eq. 3.39)."""

import math

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import Range, check, check_int

#: Sample time (s) of every discrete-time block.
SAMPLE_TIME = Range(0.0, low_open=True, what="sample time, s")
_CUTOFF = Range(0.0, low_open=True, what="cut-off frequency, Hz")
_NYQUIST = Range(0.0, 0.5, low_open=True, high_open=True, what="cut-off below the Nyquist frequency 1/(2 dt)")


class DiscreteStateSpace(eqx.Module):
    """``x[k+1] = a x[k] + b u[k]``, ``y[k] = c x[k] + d u[k]`` (single input, single output).

    Shapes: ``a`` (n, n), ``b`` (n, 1), ``c`` (1, n), ``d`` (1, 1).
    """

    a: Float[Array, "n n"]
    b: Float[Array, "n 1"]
    c: Float[Array, "1 n"]
    d: Float[Array, "1 1"]


def _analog_prototype(order: int, omega_c: Float[Array, ""]):
    """Analog Butterworth low-pass of cut-off ``omega_c`` (rad/s), unit DC gain.

    Realised as a cascade of second-order sections ``omega_c^2 / (s^2 + 2 zeta omega_c s +
    omega_c^2)`` (plus ``omega_c / (s + omega_c)`` for odd orders), each with states
    ``[y, y' / omega_c]``. Every state of the cascade is then a filtered copy of the input
    in the input's unit, which keeps the realisation well scaled (companion forms of the
    whole polynomial are ill-conditioned for poles crowded near the origin).
    """
    blocks = []
    for k in range(1, order // 2 + 1):
        zeta = math.sin((2 * k - 1) * math.pi / (2 * order))
        a_k = omega_c * jnp.array([[0.0, 1.0], [-1.0, -2.0 * zeta]])
        b_k = omega_c * jnp.array([[0.0], [1.0]])
        c_k = jnp.array([[1.0, 0.0]])
        blocks.append((a_k, b_k, c_k))
    if order % 2:
        blocks.append((-omega_c * jnp.ones((1, 1)), omega_c * jnp.ones((1, 1)), jnp.ones((1, 1))))
    # Series connection: section j is driven by the output of section j - 1.
    n = order
    a = jnp.zeros((n, n))
    b = jnp.zeros((n, 1))
    start = 0
    previous = None
    for a_k, b_k, c_k in blocks:
        size = a_k.shape[0]
        a = a.at[start : start + size, start : start + size].set(a_k)
        if previous is None:
            b = b.at[start : start + size].set(b_k)
        else:
            p_start, p_size, c_prev = previous
            a = a.at[start : start + size, p_start : p_start + p_size].set(b_k @ c_prev)
        previous = (start, size, c_k)
        start += size
    p_start, p_size, c_last = previous
    c = jnp.zeros((1, n)).at[:, p_start : p_start + p_size].set(c_last)
    return a, b, c


def butterworth_lowpass(
    order: int, cutoff_hz: Float[Array, ""] | float, dt: Float[Array, ""] | float
) -> DiscreteStateSpace:
    """Digital Butterworth low-pass filter, as ``scipy.signal.butter(order, cutoff_hz, fs=1/dt)``.

    The analog prototype's cut-off is pre-warped, ``omega_c = (2/dt) tan(pi cutoff_hz dt)``,
    and mapped with the bilinear (Tustin) transform, so the digital filter has exactly
    -3 dB at ``cutoff_hz`` and unit gain at DC, like SciPy's design (same transfer function;
    the state realisation differs). With ``M = (I - a dt/2)^-1``:
    ``a_d = M (I + a dt/2)``, ``b_d = dt M b``, ``c_d = c M``, ``d_d = (dt/2) c M b``.

    **Arguments:** ``order`` (static Python int >= 1), ``cutoff_hz`` in Hz (below the
    Nyquist frequency ``1/(2 dt)``), ``dt`` the sample time in s. Differentiable in
    ``cutoff_hz`` and ``dt``. Bad values raise ``ParameterError`` naming the argument and
    its allowed range (``eqx.error_if`` when traced).
    """
    order = check_int("butterworth_lowpass: order", order, 1, "static filter order")
    dt = check("butterworth_lowpass: dt", dt, SAMPLE_TIME)
    cutoff_hz = check("butterworth_lowpass: cutoff_hz", cutoff_hz, _CUTOFF)
    ratio = check("butterworth_lowpass: cutoff_hz * dt", cutoff_hz * dt, _NYQUIST)
    omega_c = 2.0 / dt * jnp.tan(jnp.pi * ratio)
    a, b, c = _analog_prototype(order, omega_c)
    eye = jnp.eye(order)
    half = 0.5 * dt
    m = jnp.linalg.solve(eye - half * a, eye)
    return DiscreteStateSpace(
        a=m @ (eye + half * a), b=dt * (m @ b), c=c @ m, d=half * (c @ m @ b)
    )
