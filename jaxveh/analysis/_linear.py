"""Exact linearisation of the fast car about straight running (thesis sections 7.3-7.4: root
loci and frequency responses), by forward-mode autodiff of its vector field.

The state is the fast car's ``x = [q, u, aux]`` (:class:`jaxveh.vehicle.FastState`
flattened). The inputs ``w`` are the four post heights under the wheels (m; FL, FR, RL,
RR) and the steering-wheel angle (rad, positive left), each entering with its first and
second time derivatives (the tyres' vertical damping reads the post rate, the corner
kinematics the rack's acceleration). About the straight-running trim ``x0`` at a speed,

    x_dot = A dx + B0 w + B1 w_dot + B2 w_ddot,      y = C dx + D0 w + D1 w_dot + D2 w_ddot,

with ``y`` the chosen channels of :data:`jaxveh.manoeuvre.UNITS` (the same function the
time runs save). A sinusoid ``w = W exp(i 2 pi f t)`` then gives the exact transfer
function ``H(s) = C (s I - A)^-1 (B0 + s B1 + s^2 B2) + D0 + s D1 + s^2 D2`` at
``s = i 2 pi f``, and the eigenvalues of ``A`` the car's modes (the chassis's position and
heading, and the wheels' spin angles, are neutral: zero eigenvalues).
"""

import equinox as eqx
import jax
import jax.flatten_util
import jax.numpy as jnp
import numpy as np
import scipy.linalg
from jaxtyping import Array, Float

from .._core import ParameterError, run_time_checks_off
from ..manoeuvre import UNITS, car_channels, straight_trim
from ..manoeuvre._road import POST_PATTERNS
from ..manoeuvre._simulate import _compiled_trim
from ..multibody import TimeInputs
from ..vehicle import (
    CORNERS,
    AbstractRoad,
    ConstantSpeed,
    car_elements,
    check_car,
    fast_dynamics,
    fast_model,
    steering_rack as _steering_rack,
)

#: Inputs, in order: the post heights under the wheels (m) and the steering-wheel angle (rad).
INPUTS = tuple(f"road.{c}" for c in CORNERS) + ("steering",)
#: Channels linearised by default (per-corner channels expand to ``name.corner``, the modal
#: coordinates to ``modes.1`` ...).
DEFAULT_OUTPUTS = ("yaw_rate", "ay", "sideslip", "roll", "twist", "fz", "travel", "modes")


class _PolynomialRoad(AbstractRoad):
    """Post heights ``h0 + h1 t + h2 t^2 / 2`` under the wheels (m)."""

    coefficients: Float[Array, "3 4"]

    def height(self, x, y, t, wheel):
        c = self.coefficients[:, wheel]
        return c[0] + c[1] * t + 0.5 * c[2] * t * t + jnp.zeros_like(x + y)


class CarLinearisation(eqx.Module):
    """The fast car linearised about straight running at ``speed`` (m/s; see the module
    docs): ``a`` (n x n), ``b`` (3 x n x 5: the input and its first and second derivatives),
    ``c`` (ny x n), ``d`` (3 x ny x 5), the trim state ``x0`` and its derivative ``x_dot0``
    (what the trim leaves: the chassis's forward motion and the wheels' spin), ``outputs``
    (the names of the rows of ``c``; units of :data:`jaxveh.manoeuvre.UNITS`) and the state
    layout ``n_q`` (coordinates), ``n_modes`` (chassis modes: ``q[6:6 + n_modes]``)."""

    a: Float[Array, "n n"]
    b: Float[Array, "3 n 5"]
    c: Float[Array, "ny n"]
    d: Float[Array, "3 ny 5"]
    x0: Float[Array, " n"]
    x_dot0: Float[Array, " n"]
    speed: Float[Array, ""]
    outputs: tuple[str, ...] = eqx.field(static=True)
    n_q: int = eqx.field(static=True)
    n_modes: int = eqx.field(static=True)


def output_names(car, channels=DEFAULT_OUTPUTS) -> tuple[str, ...]:
    """Row names of the linearised outputs ``channels`` (see :data:`DEFAULT_OUTPUTS`)."""
    names = []
    for name in channels:
        if name in ("fz", "fx", "fy", "slip_angle", "slip_ratio", "camber", "travel", "road_wheel_angle",
                    "spring_length", "spring_force", "road_height"):
            names += [f"{name}.{c}" for c in CORNERS]
        elif name == "modes":
            names += [f"modes.{k + 1}" for k in range(car.n_modes)]
        else:
            names.append(name)
    return tuple(names)


#: Channels that cannot be linearised: the distance run (it grows along the trim) and the input.
_NOT_LINEARISED = ("x", "steering_wheel_angle")


def _check_outputs(channels):
    bad = [c for c in channels if c not in UNITS or c in _NOT_LINEARISED]
    if bad or not channels:
        allowed = [c for c in UNITS if c not in _NOT_LINEARISED]
        raise ParameterError(f"outputs = {tuple(channels)!r}: allowed one or more of {', '.join(allowed)}")
    return tuple(channels)


def linear_field(car, trim, speed, channels):
    """``(field, x0)``: ``field(x, w) -> (x_dot, y)``, the fast car's vector field and the
    ``channels`` at the flat state ``x`` and inputs ``w`` (15: the 5 inputs of
    :data:`INPUTS`, then their first and second derivatives), about the straight-running
    ``trim`` (a :class:`jaxveh.manoeuvre.StraightTrim`, or a steady state with a ``state``
    and a ``rack``) at ``speed`` (m/s); ``x0`` the trim's flat state."""
    model = fast_model(car)
    x0, unravel = jax.flatten_util.ravel_pytree(trim.state)

    @jax.jit  # one trace serves the value and both Jacobians
    def field(x, w):
        w = jnp.reshape(w, (3, 5))
        road = _PolynomialRoad(w[:, :4])
        elements = car_elements(car, ConstantSpeed(speed), road=road)
        angle = lambda t: w[0, 4] + w[1, 4] * t + 0.5 * w[2, 4] * t * t  # noqa: E731
        law = TimeInputs(lambda t: trim.rack + _steering_rack(car, angle(t)))
        s = unravel(x)
        d = fast_dynamics(car, model, s.q, s.u, s.aux, 0.0, law, elements)
        x_dot = jax.flatten_util.ravel_pytree(type(trim.state)(d.q_dot, d.u_dot, d.aux_dot))[0]
        ch = car_channels(car, elements, d.kinematics, s.aux, s.u[:6], d.u_dot[:6], angle(0.0))
        y = jnp.concatenate([jnp.ravel(ch[name]) for name in channels])
        return x_dot, y

    return field, x0


def _jacobians(car, trim, speed, channels):
    """``(a, b, c, d, x0, x_dot0)`` about the straight-running ``trim`` at ``speed`` (m/s)."""
    field, x0 = linear_field(car, trim, speed, channels)
    w0 = jnp.zeros(15)
    x_dot0 = field(x0, w0)[0]
    (a, c) = jax.jacfwd(field, argnums=0)(x0, w0)
    (bw, dw) = jax.jacfwd(field, argnums=1)(x0, w0)
    b = jnp.moveaxis(jnp.reshape(bw, (x0.size, 3, 5)), 1, 0)
    d = jnp.moveaxis(jnp.reshape(dw, (c.shape[0], 3, 5)), 1, 0)
    return a, b, c, d, x0, x_dot0


def linearise_core(car, speed, channels):
    """The pure core of :func:`linearise` (jit, vmap, grad): ``(a, b, c, d, x0, x_dot0, ok)``."""
    trim = straight_trim(car, speed, "fast")
    return _jacobians(car, trim, speed, channels) + (trim.ok,)


_compiled = eqx.filter_jit(_jacobians)


def linearise(car, speed: float = 50.0 / 3.6, outputs=DEFAULT_OUTPUTS) -> CarLinearisation:
    """The fast car ``car`` linearised about straight running at ``speed`` (m/s), with the
    channels ``outputs`` (:data:`DEFAULT_OUTPUTS`). Compiled once per car structure and
    output list (``speed`` and every leaf of the car are traced); the pure core is
    :func:`linearise_core` (jit, vmap, grad)."""
    channels = _check_outputs(outputs)
    if not 0.0 < float(speed) <= 100.0:
        raise ParameterError(f"speed = {speed!r} is out of range: allowed (0, 100] m/s")
    check_car(car)
    speed = jnp.asarray(speed, jnp.float64)
    with run_time_checks_off():
        trim, ok = _compiled_trim(car, speed, "fast")  # the program every manoeuvre's trim uses
        if not bool(ok):
            raise RuntimeError(f"straight running at {float(speed):g} m/s was not found: nothing to linearise about")
        a, b, c, d, x0, x_dot0 = _compiled(car, trim, speed, channels)
    return CarLinearisation(a=a, b=b, c=c, d=d, x0=x0, x_dot0=x_dot0, speed=speed,
                            outputs=output_names(car, channels), n_q=14 + car.n_modes, n_modes=car.n_modes)


def input_direction(input) -> np.ndarray:
    """The 5 input weights of ``input``: "steering" (per rad of steering-wheel angle),
    "heave" or "warp" (the posts of :data:`jaxveh.manoeuvre.POST_PATTERNS`, per m at the
    front-left post), or 5 weights in :data:`INPUTS` order."""
    if isinstance(input, str):
        if input == "steering":
            return np.eye(5)[4]
        if input in POST_PATTERNS:
            return np.concatenate([POST_PATTERNS[input], [0.0]])
        raise ParameterError(f"input = {input!r}: allowed 'steering', {', '.join(map(repr, POST_PATTERNS))} "
                             "or 5 weights (FL, FR, RL, RR posts, steering)")
    w = np.asarray(input, float)
    if w.shape != (5,):
        raise ParameterError(f"input has shape {w.shape}: allowed 5 weights (FL, FR, RL, RR posts, steering)")
    return w


def transfer_function(lin: CarLinearisation, frequency_hz, input="steering") -> np.ndarray:
    """``H[f, output]`` (complex) of every output of ``lin`` per unit of ``input``
    (:func:`input_direction`; per rad of steering-wheel angle or per m of post motion) at
    the frequencies ``frequency_hz`` (> 0, Hz). NumPy, exact up to round-off."""
    f = np.atleast_1d(np.asarray(frequency_hz, float))
    if not np.all(f > 0.0):
        raise ParameterError("frequency_hz must be > 0 (the car's neutral coordinates make H infinite at 0)")
    w = input_direction(input)
    a, b, c, d = (np.asarray(x) for x in (lin.a, lin.b, lin.c, lin.d))
    out = np.empty((f.size, c.shape[0]), complex)
    eye = np.eye(a.shape[0])
    for k, s in enumerate(2j * np.pi * f):
        weights = np.asarray([1.0, s, s * s])
        bs = np.einsum("k,knm,m->n", weights, b, w)
        ds = np.einsum("k,knm,m->n", weights, d, w)
        out[k] = c @ np.linalg.solve(s * eye - a, bs) + ds
    return out


def output_index(lin: CarLinearisation, name: str) -> int:
    """Row of the output ``name`` (e.g. ``"fz.front_left"``, ``"modes.1"``) in ``lin``."""
    if name not in lin.outputs:
        raise ParameterError(f"output {name!r} is not linearised: allowed {', '.join(lin.outputs)}")
    return lin.outputs.index(name)


def modes(lin: CarLinearisation, min_hz: float = 1e-3):
    """``(eigenvalues, vectors)`` of ``lin.a`` with positive imaginary part or real and
    negative (the car's vibration modes and its non-oscillating ones), leaving out the
    neutral ones (``|lambda| < 2 pi min_hz``), by rising natural frequency. NumPy."""
    lam, vec = np.linalg.eig(np.asarray(lin.a))
    order = _mode_order(lam, min_hz)
    return lam[order], vec[:, order]


def _mode_order(lam, min_hz: float = 1e-3) -> np.ndarray:
    """Indices of the eigenvalues ``lam`` that :func:`modes` keeps, by rising modulus."""
    keep = np.flatnonzero((np.abs(lam) >= 2.0 * np.pi * min_hz) & (lam.imag >= 0.0))
    return keep[np.argsort(np.abs(lam[keep]))]


def _lateral_matrices(params, car, speed):
    """``(a, b, c)`` of the car with ``params``, the output the c.g.'s lateral position."""
    car = eqx.tree_at(lambda c: c.params, car, params)
    return linearise_core(car, speed, ("y",))[:3]


#: ``((a, b, c), (da, db, dc))`` along a direction in the car's parameters (one program per
#: car structure serves the eigenvalue derivatives and the preview distance's).
_compiled_tangent = eqx.filter_jit(lambda car, tangent, speed: jax.jvp(
    lambda p: _lateral_matrices(p, car, speed), (car.params,), (tangent,)))


def _check_tangent(car, tangent):
    check_car(car)
    if jax.tree.structure(tangent) != jax.tree.structure(car.params):
        raise ParameterError("tangent must have the structure of car.params (a CarParams of tangents)")


def linear_tangent(car, tangent, speed: float = 50.0 / 3.6):
    """``((a, b, c), (da, db, dc))``: the linearisation about straight running at ``speed``
    (m/s) with the c.g.'s lateral position ``y`` as output, and its derivative along
    ``tangent`` (a :class:`jaxveh.vehicle.CarParams` of tangents), by forward-mode autodiff
    through the trim (implicit function theorem) and the Jacobians."""
    _check_tangent(car, tangent)
    # Traced with the run-time checks on, on purpose: their host callbacks keep this program
    # (an 18 MB module) out of JAX's persistent cache, because loading it back from the
    # cache segfaults (jax 0.10.2, CPU, reproducible); it compiles once per process instead.
    return _compiled_tangent(car, tangent, jnp.asarray(speed, jnp.float64))


def eigenvalue_sensitivities(car, tangent, speed: float = 50.0 / 3.6):
    """``(eigenvalues, derivatives)``: the modes of :func:`modes` (same order) and the
    derivative of each eigenvalue (1/s per unit of the direction) along ``tangent``, a
    direction in ``car.params`` (a :class:`jaxveh.vehicle.CarParams` of tangents, e.g. 1 on
    ``chassis.stiffness_scale[0]`` and 0 elsewhere), by forward-mode autodiff through the
    straight-running trim (implicit function theorem) and the Jacobian, and the first-order
    eigenvalue perturbation ``d lambda = w^H dA v / (w^H v)`` (left and right eigenvectors;
    simple eigenvalues)."""
    (a, _, _), (da, _, _) = linear_tangent(car, tangent, speed)
    lam, left, right = scipy.linalg.eig(np.asarray(a), left=True, right=True)
    order = _mode_order(lam)
    lam, left, right = lam[order], left[:, order], right[:, order]
    da = np.asarray(da)
    d = np.einsum("ik,ij,jk->k", left.conj(), da, right) / np.einsum("ik,ik->k", left.conj(), right)
    return lam, d


def stiffness_direction(car, mode: int):
    """A tangent of ``car.params``: 1 on ``chassis.stiffness_scale[mode]`` (0-based), 0 elsewhere."""
    if car.n_modes == 0 or not 0 <= mode < car.n_modes:
        raise ParameterError(f"mode = {mode!r} is out of range: allowed 0 to {car.n_modes - 1} (the car's modes)")
    zero = jax.tree.map(jnp.zeros_like, car.params)
    return eqx.tree_at(lambda p: p.chassis.stiffness_scale, zero, jnp.zeros(car.n_modes).at[mode].set(1.0))


#: Outputs of :func:`linear_frequency_response` by default, per input kind.
FRF_OUTPUTS = {"steering": ("yaw_rate", "ay", "sideslip", "roll", "twist"),
               "road": ("fz.front_left", "twist", "roll", "travel.front_left")}


def linear_frequency_response(lin: CarLinearisation, frequency_hz, input="steering", outputs=None) -> dict:
    """The exact frequency responses of :func:`transfer_function` in the form of
    :func:`jaxveh.manoeuvre.frequency_response` and
    :func:`jaxveh.manoeuvre.four_post_metrics` (``fz.front_left`` becomes
    ``fz_front_left``, ``modes.1`` ``mode_1``): ``frequency_hz`` and per output
    ``{name}_gain`` (output units per degree of steering-wheel angle, or per mm at the
    front-left post for "heave"/"warp"), ``{name}_gain_db`` and ``{name}_phase_deg``
    (unwrapped from the lowest frequency). ``outputs``: rows of ``lin`` (default
    :data:`FRF_OUTPUTS` of the input's kind, those present, and every modal coordinate for a
    road input)."""
    if outputs is None:
        kind = "steering" if isinstance(input, str) and input == "steering" else "road"
        outputs = [o for o in FRF_OUTPUTS[kind] if o in lin.outputs]
        if kind == "road":
            outputs += [o for o in lin.outputs if o.startswith("modes.")]
    rows = [output_index(lin, o) for o in outputs]
    f = np.atleast_1d(np.asarray(frequency_hz, float))
    per_unit = np.pi / 180.0 if isinstance(input, str) and input == "steering" else 1e-3
    h = transfer_function(lin, f, input)[:, rows] * per_unit
    out = {"frequency_hz": f.tolist()}
    for output, column in zip(outputs, h.T, strict=True):
        name = output.replace("modes.", "mode_").replace(".", "_")  # the keys of the time runs' responses
        gain = np.abs(column)
        out[f"{name}_gain"] = gain.tolist()
        out[f"{name}_gain_db"] = (20.0 * np.log10(np.maximum(gain, 1e-300))).tolist()
        out[f"{name}_phase_deg"] = np.degrees(np.unwrap(np.angle(column))).tolist()
    return out
