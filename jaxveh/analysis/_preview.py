"""Time-invariant optimal preview control of the linearised 14-DOF car (thesis section 7.5,
Fig. 7.10): the controller of :mod:`jaxveh.control` (section 3.3.6) on the fast car's exact
linearisation about straight running.

**The plant.** :func:`jaxveh.analysis.linearise` gives ``x_dot = A x + B0 d + B1 d_dot +
B2 d_ddot`` in the steering-wheel angle ``d`` (the tyres read the steering rate, the corner
kinematics the rack's acceleration). The state change ``x_hat = x - (B1 + A B2) d - B2
d_dot`` turns it into ``x_hat_dot = A x_hat + (B0 + A B1 + A^2 B2) d``, exact for smooth
steering; the lateral position ``y = C x`` (the sprung mass's c.g., m) then reads ``C
x_hat + C (B1 + A B2) d + C B2 d_dot``, whose feedthrough the preview plant cannot hold: it
is dropped and reported (``feedthrough``; -1.4 mm per rad of steering-wheel angle on the
default car at 100 km/h, from the rack's and wheels' steering inertia: a tenth of a
millimetre for a typical correction). The neutral states that neither feed back nor can be steered are removed: the
distance run ``x`` and the four wheel-spin angles (the DARE needs a stabilisable plant).
Lateral position, heading, the chassis's vertical and modal motion, suspension, wheel spin
rates, the tyres' relaxation and the speed loop stay: about 50 states for six modes.

**Controller.** Defaults are the thesis's (section 7.5): 100 km/h, 250 preview points,
``dt = 0.01`` s, tracking weight 1000, steering weight 1, 4th-order 2 Hz road filter. The
gains ``Kp`` are rad of steering-wheel angle per m of road ahead; the preview distance
``Lp`` covers 98 % of the area under ``|Kp|`` (eq. 3.46), interpolated between samples so
that it is differentiable (``interpolate=True`` of :func:`jaxveh.control.preview_distance`).

**Derivatives.** ``d Lp / d mu_i`` by forward mode: the linearisation's tangent along the
stiffness multiplier (:func:`jaxveh.analysis.linear_tangent`, the program the eigenvalue
derivatives use) pushed through the plant, the Riccati solution (implicit derivative) and
the preview distance.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, run_time_checks_off
from ..control import RESULTS, preview_controller, preview_distance
from ._linear import linear_tangent, linearise, output_index, stiffness_direction

#: Section 7.5's settings: speed (m/s), preview points, sample time (s), weights, road filter.
PREVIEW_SPEED = 100.0 / 3.6
N_PREVIEW = 250
DT = 0.01
Q_WEIGHT, R_WEIGHT = 1000.0, 1.0
CUTOFF_HZ = 2.0
#: Share of the area under |Kp| the preview distance covers (eq. 3.46).
FRACTION = 0.98
#: Stiffness multiplier of a frozen chassis mode (its states are then residualised).
FREEZE = 1e8


def _kept_states(n_state: int, n_q: int) -> np.ndarray:
    """State indices without the distance run ``q[0]`` and the four spin angles."""
    drop = {0, *range(n_q - 4, n_q)}
    return np.asarray([i for i in range(n_state) if i not in drop])


def _plant(a, b, c, n_q: int):
    """``(a, b_eff, c_y, feedthrough)`` of the steering input on the kept states (module
    docs): ``b`` (3, n, 5) the input derivatives' matrices, ``c`` (1, n) the lateral
    position's row. Pure JAX (differentiable)."""
    b0, b1, b2 = b[0, :, 4], b[1, :, 4], b[2, :, 4]
    a_b2 = a @ b2
    b_eff = b0 + a @ b1 + a @ a_b2
    keep = _kept_states(a.shape[0], n_q)
    feedthrough = jnp.stack([c[0] @ (b1 + a_b2), c[0] @ b2])
    return a[keep][:, keep], b_eff[keep], c[0, keep], feedthrough


def _lp(a, b, c, speed, n_q: int, n_preview: int):
    """``(Kp, Lp, spectral radius)`` of the car's matrices (pure, differentiable)."""
    a_k, b_k, c_k, _ = _plant(a, b, c, n_q)
    gains = preview_controller(a_k, b_k, c_k, dt=DT, n_preview=n_preview, q_weight=Q_WEIGHT, r_weight=R_WEIGHT,
                               cutoff_hz=CUTOFF_HZ, throw=False)
    lp = preview_distance(gains.preview, speed, DT, fraction=FRACTION, interpolate=True)
    return gains.preview, lp, gains.spectral_radius, gains.result


#: The pure core of :func:`car_preview` (jit, vmap, grad): ``(Kp, Lp, spectral radius,
#: result)`` of the linearisation's ``(a, b, c)`` with the lateral position as the only
#: output row, at ``speed`` (m/s), ``n_q`` position coordinates and ``n_preview`` points.
preview_core = _lp
_compiled_lp = eqx.filter_jit(_lp)


@eqx.filter_jit
def _lp_tangent(a, b, c, da, db, dc, speed, n_q: int, n_preview: int):
    return jax.jvp(lambda a, b, c: _lp(a, b, c, speed, n_q, n_preview)[1], (a, b, c), (da, db, dc))


class PreviewResult(eqx.Module):
    """Optimal preview of the car at ``speed`` (m/s): ``gains`` Kp (rad of steering-wheel
    angle per m of road lateral position) at ``distance`` (m) ahead, the preview distance
    ``lp`` (m, interpolated), the closed loop's ``spectral_radius`` (< 1: stable) and the
    dropped ``feedthrough`` of the steering angle and rate on the lateral position (m/rad,
    m s/rad)."""

    gains: Float[Array, " np1"]
    distance: Float[Array, " np1"]
    lp: Float[Array, ""]
    speed: Float[Array, ""]
    spectral_radius: Float[Array, ""]
    feedthrough: Float[Array, "2"]


def _check(speed, n_preview):
    if not 0.0 < float(speed) <= 100.0:
        raise ParameterError(f"speed = {speed!r} is out of range: allowed (0, 100] m/s")
    if not isinstance(n_preview, int) or n_preview < 2:
        raise ParameterError(f"n_preview = {n_preview!r} is out of range: allowed an int >= 2")


def _frozen_states(n_q: int, n_modes: int, modes: int) -> np.ndarray:
    """State indices of the chassis modes ``modes`` ... ``n_modes - 1`` (0-based): their
    coordinates and rates."""
    frozen = np.arange(modes, n_modes)
    return np.concatenate([6 + frozen, n_q + 6 + frozen])


def _residualise(a, b, c, fast):
    """The model with the states ``fast`` held quasi-static (their rates set to zero and
    solved for), kept as decoupled dummy states (rate ``-x / DT``, no input, not observed)
    so that the matrices keep their size (one compiled Riccati program for every k). NumPy."""
    a, b, c = (np.array(x) for x in (a, b, c))
    slow = np.setdiff1d(np.arange(a.shape[0]), fast)
    a_ff, a_sf = a[np.ix_(fast, fast)], a[np.ix_(slow, fast)]
    x_a = np.linalg.solve(a_ff, a[np.ix_(fast, slow)])
    a_new = np.zeros_like(a)
    a_new[np.ix_(slow, slow)] = a[np.ix_(slow, slow)] - a_sf @ x_a
    a_new[fast, fast] = -1.0 / DT
    for k in range(b.shape[0]):
        b[k][slow] -= a_sf @ np.linalg.solve(a_ff, b[k][fast])
        b[k][fast] = 0.0
    c[:, slow] -= c[:, fast] @ x_a
    c[:, fast] = 0.0
    return a_new, b, c


def _result(a, b, c, speed, n_q: int, n_preview: int) -> PreviewResult:
    with run_time_checks_off():
        kp, lp, rho, result = _compiled_lp(jnp.asarray(a), jnp.asarray(b), jnp.asarray(c), speed, n_q, n_preview)
    if not bool(result == RESULTS.successful):
        raise RuntimeError(f"the preview Riccati equation was not solved at {float(speed):g} m/s: "
                           f"{RESULTS[result]} (closed-loop spectral radius {float(rho):.6f})")
    feed = _plant(jnp.asarray(a), jnp.asarray(b), jnp.asarray(c), n_q)[3]
    distance = jnp.arange(n_preview + 1, dtype=jnp.float64) * speed * DT
    return PreviewResult(gains=kp, distance=distance, lp=lp, speed=speed, spectral_radius=rho, feedthrough=feed)


def car_preview(car, speed: float = PREVIEW_SPEED, n_preview: int = N_PREVIEW, modes: int | None = None
                ) -> PreviewResult:
    """The TI-optimal preview controller of the linearised car at ``speed`` (m/s; default
    100 km/h) with ``n_preview`` points (module docs). With ``modes = k`` only the first k
    chassis modes flex: the others are frozen (stiffness × :data:`FREEZE`) and their states
    held quasi-static (residualised), which tends to the car with k modes (k = 0: rigid)."""
    _check(speed, n_preview)
    n = car.n_modes
    modes = n if modes is None else modes
    if isinstance(modes, bool) or not isinstance(modes, (int, np.integer)) or not 0 <= modes <= n:
        raise ParameterError(f"modes = {modes!r} is out of range: allowed integers 0 to {n} (the car's modes)")
    if modes < n:
        scale = car.params.chassis.stiffness_scale
        car = eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, car,
                          jnp.where(jnp.arange(n) < modes, scale, scale * FREEZE))
    lin = linearise(car, speed, outputs=("y",))
    y = output_index(lin, "y")
    a, b, c = lin.a, lin.b, lin.c[y : y + 1]
    if modes < n:
        a, b, c = _residualise(a, b, c, _frozen_states(lin.n_q, n, modes))
    return _result(a, b, c, lin.speed, lin.n_q, n_preview)


def preview_distance_sensitivity(car, mode: int, speed: float = PREVIEW_SPEED, n_preview: int = N_PREVIEW):
    """``(Lp, d Lp / d mu)``: the preview distance (m) and its derivative with respect to
    chassis mode ``mode``'s stiffness multiplier (0-based; m per unit of mu), forward mode
    through the trim, the Jacobians and the Riccati equation."""
    _check(speed, n_preview)
    (a, b, c), (da, db, dc) = linear_tangent(car, stiffness_direction(car, mode), speed)
    n_q = 14 + car.n_modes
    with run_time_checks_off():
        return _lp_tangent(a, b, c, da, db, dc, jnp.asarray(speed, jnp.float64), n_q, n_preview)


def _designs(car, stacked):
    """The cars of stacked parameters (leading axis), one by one."""
    n = jax.tree.leaves(stacked)[0].shape[0]
    return [eqx.tree_at(lambda c: c.params, car, jax.tree.map(lambda x, k=k: x[k], stacked)) for k in range(n)]


def preview_by_modes(car, speed: float = PREVIEW_SPEED, n_preview: int = N_PREVIEW) -> list[PreviewResult]:
    """The preview of the car with its first k chassis modes, k = 0 ... n (Fig. 7.10c;
    :func:`car_preview` with ``modes = k``): one compiled linearisation and one Riccati
    program serve every k; entry 0 is the rigid chassis."""
    _check(speed, n_preview)
    return [car_preview(car, speed, n_preview, modes=k) for k in range(car.n_modes + 1)]


def preview_vs_mode_stiffness(car, mus, speed: float = PREVIEW_SPEED, n_preview: int = N_PREVIEW) -> np.ndarray:
    """Preview distance (m) with each chassis mode's stiffness multiplied by each ``mus``
    (rows: modes, columns: µ; Fig. 7.10d), the other modes as they are."""
    from ._load_transfer import mode_stiffness_designs

    _check(speed, n_preview)
    mus = np.asarray(mus, float)
    lps = [float(car_preview(c, speed, n_preview).lp) for c in _designs(car, mode_stiffness_designs(car, mus))]
    return np.reshape(lps, (car.n_modes, mus.size))


def _json(r: PreviewResult) -> dict:
    return {"preview_distance_m": float(r.lp), "distance_m": np.asarray(r.distance).tolist(),
            "gains_deg_per_m": np.degrees(np.asarray(r.gains)).tolist(),
            "closed_loop_spectral_radius": float(r.spectral_radius),
            "dropped_feedthrough_m_per_rad": float(r.feedthrough[0])}


def preview_report(car, speed_kmh: float = 100.0, n_preview: int = N_PREVIEW, mus=None) -> dict:
    """JSON-ready Fig. 7.10: the car's TI-optimal preview (gains in deg of steering-wheel
    angle per m of road, preview distance) with all its modes and with its first k modes
    (k = 0 rigid), beside the chapter-3 model's (Appendix A vehicle, rigid and flexible, the
    same settings); with ``mus`` also the preview distance against each mode's stiffness
    multiplier."""
    from ..analytic._reports import preview_report as chapter3_preview
    from ..params import load_analytic_vehicle

    speed = speed_kmh / 3.6
    _check(speed, n_preview)
    if car.n_modes == 0:
        raise ParameterError("modes = 0: the preview report compares chassis modes; use car_preview for a rigid car")
    by_modes = preview_by_modes(car, speed, n_preview)
    analytic = load_analytic_vehicle()
    report = {
        "speed_kmh": speed_kmh, "n_preview": n_preview, "dt_s": DT, "q_weight": Q_WEIGHT, "r_weight": R_WEIGHT,
        "cutoff_hz": CUTOFF_HZ, "modes": car.n_modes,
        "flexible": _json(by_modes[-1]),
        "rigid": _json(by_modes[0]),
        "preview_distance_by_modes_m": [float(r.lp) for r in by_modes],
        "chapter_3": {name: chapter3_preview(analytic, speed_kmh=speed_kmh, rigid=name == "rigid", dt=DT,
                                             n_preview=n_preview, q_weight=Q_WEIGHT, r_weight=R_WEIGHT,
                                             cutoff_hz=CUTOFF_HZ) for name in ("rigid", "flexible")},
    }
    if mus is not None:
        report["mu"] = np.asarray(mus, float).tolist()
        report["preview_distance_vs_mu_m"] = preview_vs_mode_stiffness(car, mus, speed, n_preview).tolist()
    return report
