"""Time-invariant optimal preview control (thesis section 3.3.6, eqs. 3.38-3.46).

The plant of eq. (3.41)-(3.42) stacks three blocks, ``z = [xf, xd, yr]``:

- ``xf``: a digital Butterworth low-pass filter (eq. 3.39) driven by white noise ``yri``;
  its output ``yf`` is the road lateral position entering the preview horizon;
- ``xd``: the vehicle, discretised with a zero-order hold (eq. 3.38), input ``delta``;
- ``yr``: a shift register of ``n_preview + 1`` road samples (eq. 3.40): ``yr[i]`` is the
  road lateral position ``i u dt`` metres ahead of the car (``yr[0]`` at the car), and each
  step moves every sample one place nearer; ``yr[n_preview]`` is fed by the filter.

The cost (eq. 3.43) weighs the path error ``y = c_y xd - yr[0]`` (``C = [0 Cd Cr]``,
``Cr = [-1 0 ... 0]``) by ``q_weight`` and the input by ``r_weight``. The optimal
control is ``u = -K z`` (eq. 3.44) with ``K`` from the discrete Riccati equation (3.45),
split into filter gains ``Kf``, vehicle-state gains ``Kd`` and preview gains ``Kp``.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from ..params import Range, check, check_int, check_static
from ._butterworth import SAMPLE_TIME, butterworth_lowpass
from ._discretise import zoh
from ._riccati import RESULTS, solve_dare

#: Share of the area under |Kp| that defines the preview distance (3.46).
_FRACTION = Range(0.0, 1.0, low_open=True, what="share of the area under |Kp|")
#: Weights Q and R of the cost (3.43).
_WEIGHT = Range(0.0, low_open=True, what="cost weight (3.43)")


class PreviewPlant(eqx.Module):
    """Discrete preview plant ``z[k+1] = a z + b u + e yri``, ``y = c z`` (eq. 3.41).

    State order ``[xf (n_filter), xd (n_vehicle), yr (n_preview + 1)]``.
    """

    a: Float[Array, "N N"]
    b: Float[Array, "N 1"]
    e: Float[Array, "N 1"]
    c: Float[Array, "1 N"]
    n_filter: int = eqx.field(static=True)
    n_vehicle: int = eqx.field(static=True)
    n_preview: int = eqx.field(static=True)


class PreviewGains(eqx.Module):
    """Optimal preview controller ``u = -(Kf xf + Kd xd + Kp yr)`` (eq. 3.44).

    Units follow the plant: with ``u`` the steering-wheel angle in rad and the road in m,
    ``preview`` (``Kp``) is in rad per metre of road lateral position; ``preview[i]``
    acts on the road sample ``i u dt`` metres ahead (``i = 0 ... n_preview``).

    - ``filter`` (``Kf``), ``vehicle`` (``Kd``), ``preview`` (``Kp``): the gain blocks.
    - ``p``: Riccati solution of the whole plant (differentiable).
    - ``residual``, ``spectral_radius``, ``result``: diagnostics of the Riccati solve
      (relative residual, closed-loop spectral radius, :class:`RESULTS` item).
    """

    filter: Float[Array, " n_filter"]
    vehicle: Float[Array, " n_vehicle"]
    preview: Float[Array, " n_preview_plus_1"]
    p: Float[Array, "N N"]
    residual: Float[Array, ""]
    spectral_radius: Float[Array, ""]
    result: RESULTS


def _shift_register(n_preview: int):
    """``Ar`` (ones on the first upper diagonal) and ``Br`` (last element one), eq. 3.40."""
    size = n_preview + 1
    return jnp.eye(size, k=1), jnp.zeros((size, 1)).at[-1, 0].set(1.0)


def preview_plant(
    a_c: Float[Array, "n n"],
    b_c: Float[Array, "n 1"] | Float[Array, " n"],
    c_y: Float[Array, " n"],
    *,
    dt: Float[Array, ""] | float = 0.01,
    n_preview: int = 200,
    cutoff_hz: Float[Array, ""] | float = 2.0,
    filter_order: int = 4,
) -> PreviewPlant:
    """Assemble the preview plant of eq. (3.42) from a continuous single-input model.

    **Arguments:**

    - ``a_c`` (n, n), ``b_c`` (n, 1) or (n,): continuous-time model ``x' = a_c x + b_c u``.
    - ``c_y`` (n,): row selecting the lateral position (m) from the model state (``Cd``).
    - ``dt``: sample time (s); ``n_preview`` (static): number of preview points ``q``;
      ``cutoff_hz``, ``filter_order`` (static): Butterworth road filter.

    ``dt`` > 0, ``n_preview`` >= 1, ``filter_order`` >= 1 and ``0 < cutoff_hz < 1/(2 dt)``
    are checked (``ParameterError``; traced values: ``eqx.error_if``).
    """
    a_c = jnp.asarray(a_c)
    b_c = jnp.asarray(b_c)
    if b_c.ndim == 1:
        b_c = b_c[:, None]
    c_y = jnp.asarray(c_y)
    n = a_c.shape[0]
    if b_c.shape != (n, 1) or c_y.shape != (n,):
        raise ValueError(
            f"preview_plant: need a_c ({n}, {n}), b_c ({n}, 1) and c_y ({n},); got "
            f"{a_c.shape}, {b_c.shape}, {c_y.shape}."
        )
    n_preview = check_int("preview_plant: n_preview", n_preview, 1, "static number of preview points")
    a_d, b_d = zoh(a_c, b_c, dt)
    road = butterworth_lowpass(filter_order, cutoff_hz, dt)
    a_r, b_r = _shift_register(n_preview)
    nf, nr = filter_order, n_preview + 1
    zeros = jnp.zeros
    a = jnp.block(
        [
            [road.a, zeros((nf, n)), zeros((nf, nr))],
            [zeros((n, nf)), a_d, zeros((n, nr))],
            [b_r @ road.c, zeros((nr, n)), a_r],
        ]
    )
    b = jnp.concatenate([zeros((nf, 1)), b_d, zeros((nr, 1))], axis=0)
    e = jnp.concatenate([road.b, zeros((n, 1)), b_r @ road.d], axis=0)
    c_r = zeros(nr).at[0].set(-1.0)
    c = jnp.concatenate([zeros(nf), c_y, c_r])[None, :]
    return PreviewPlant(a=a, b=b, e=e, c=c, n_filter=nf, n_vehicle=n, n_preview=n_preview)


@eqx.filter_jit
def preview_controller(
    a_c: Float[Array, "n n"],
    b_c: Float[Array, "n 1"] | Float[Array, " n"],
    c_y: Float[Array, " n"],
    *,
    dt: Float[Array, ""] | float = 0.01,
    n_preview: int = 200,
    q_weight: Float[Array, ""] | float = 1000.0,
    r_weight: Float[Array, ""] | float = 1.0,
    cutoff_hz: Float[Array, ""] | float = 2.0,
    filter_order: int = 4,
    throw: bool = True,
) -> PreviewGains:
    """Time-invariant optimal preview gains (eqs. 3.41-3.45) of a continuous model.

    Defaults are the thesis's: ``dt = 0.01`` s, ``q = 200`` preview points, ``Q = 1000``,
    ``R = 1``, 4th-order Butterworth road filter at 2 Hz. The cost is
    ``sum Q (c_y xd - yr[0])^2 + R u^2``. Differentiable in every array argument; vmap
    over a batch of models. ``throw`` as in :func:`jaxveh.control.solve_dare`.

    Arguments as :func:`preview_plant`; ``q_weight`` (1/m^2) and ``r_weight`` (1/rad^2)
    are the scalar weights of eq. (3.43), both > 0 (``ParameterError``, or ``eqx.error_if``
    when traced).
    """
    plant = preview_plant(
        a_c, b_c, c_y, dt=dt, n_preview=n_preview, cutoff_hz=cutoff_hz, filter_order=filter_order
    )
    q = check("preview_controller: q_weight", q_weight, _WEIGHT) * (plant.c.T @ plant.c)
    r = check("preview_controller: r_weight", r_weight, _WEIGHT).reshape(1, 1)
    solution = solve_dare(plant.a, plant.b, q, r, throw=throw)
    k = solution.k[0]
    nf, nv = plant.n_filter, plant.n_vehicle
    return PreviewGains(
        filter=k[:nf],
        vehicle=k[nf : nf + nv],
        preview=k[nf + nv :],
        p=solution.p,
        residual=solution.residual,
        spectral_radius=solution.spectral_radius,
        result=solution.result,
    )


def preview_distance(
    preview: Float[Array, " n_points"],
    speed: Float[Array, ""] | float,
    dt: Float[Array, ""] | float = 0.01,
    *,
    fraction: float = 0.98,
    interpolate: bool = False,
) -> Float[Array, ""]:
    """Preview distance ``Lp = n u dt`` (eq. 3.46), in m.

    ``preview[i]`` is the gain on the road sample ``l_i = i u dt`` ahead (``i = 0 ... q``).
    ``n`` is the smallest index whose cumulative sum ``sum_{j <= n} |Kp_j|`` exceeds
    ``fraction`` of the total, so ``Lp`` is the shortest preview holding that fraction of
    the area under ``|Kp|``.

    With ``interpolate=False`` (the thesis's definition) ``Lp`` moves in steps of
    ``u dt`` and has zero derivative almost everywhere. ``interpolate=True`` places the
    crossing linearly between ``n - 1`` and ``n``, which makes ``Lp`` continuous and
    differentiable in the gains (useful for sweeps and optimisation).

    **Arguments:** ``preview`` the gains (any unit), ``speed`` ``u`` in m/s (> 0), ``dt`` in
    s (> 0), ``fraction`` in (0, 1].
    """
    speed = check("preview_distance: speed", speed, Range(0.0, low_open=True, what="forward speed u, m/s"))
    dt = check("preview_distance: dt", dt, SAMPLE_TIME)
    check_static("preview_distance: fraction", fraction, _FRACTION)
    magnitude = jnp.abs(jnp.asarray(preview))
    magnitude = eqx.error_if(
        magnitude,
        ~(jnp.sum(magnitude) > 0.0),
        "preview_distance: the preview gains are all zero or not finite; Lp is undefined.",
    )
    cumulative = jnp.cumsum(magnitude)
    target = fraction * cumulative[-1]
    n = jnp.argmax(cumulative > target)
    index = n.astype(magnitude.dtype)
    if interpolate:
        before = jnp.where(n > 0, cumulative[jnp.maximum(n - 1, 0)], 0.0)
        # magnitude[n] > 0 here: the cumulative sum strictly increased at n.
        index = index - 1.0 + (target - before) / magnitude[n]
    return index * speed * dt
