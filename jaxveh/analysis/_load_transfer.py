"""Lateral load transfer of the chapter-6 car (section 7.1.2, Fig. 7.2) by root finding.

The car's steady states on a circle of radius R (default 50 m, the thesis's skid-pad) are
solved at ``+ay`` (turning left) and ``-ay`` (turning right) with
:func:`jaxveh.manoeuvre.steady_state`'s core (conditions ``ay`` and ``yaw_rate =
±sqrt(ay / R)``, so the path radius is exactly R). The per-wheel lateral load transfer of an
axle is a quarter of the change of its right-less-left tyre load between the two turns,

    ΔFz_axle(ay) = [(Fz_right - Fz_left)(+ay) - (Fz_right - Fz_left)(-ay)] / 4      (N),

which removes the small static left/right differences that the tyres' asymmetric offsets
leave at ay = 0 (and every term even in ay). The secant χ = ΔFzF / (ΔFzF + ΔFzR) at one ay
still holds a term constant in ay on a circle of fixed radius: the front wheels are
steered by the kinematic angle l / R however small ay is, and the steering geometry
(caster, kingpin inclination) jacks the car diagonally by an amount odd in the steer angle,
lowering the front transfer and raising the rear by ~0.1 N on R = 50 m (χ then falls as
1/ay at low ay: 0.4936 at 0.05 g, 0.5015 at 0.1 g on the rigid car). "χ at low ay" is
therefore the incremental share between the first two lateral accelerations,

    χ = Δ(ΔFzF) / (Δ(ΔFzF) + Δ(ΔFzR))     between :data:`LOW_AY_PAIR_G` (0.05 and 0.1 g),

the slope ratio of Fig. 7.2a's straight lines, which the chapter-3 model describes (it has
no steering); it equals the secant χ at fixed speed and vanishing ay at high speed without
aero (0.5096 vs 0.5090 at 30 m/s, rigid car).

Every sweep over designs is one vmapped, compiled call (one program per chassis mode
count and batch size): the roll-stiffness distribution λ through the anti-roll bars
(:func:`arb_rates_for_distribution`), each mode's stiffness multiplier µ, and the number
of modes (one program per count: the structure changes). ``d χ / d µ`` by ``jax.grad``
through the root finding (implicit function theorem). Each entry point checks the car
eagerly (:func:`jaxveh.vehicle.check_car`) and traces without run-time checks, so JAX's
disk cache can keep the programs.
"""

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Bool, Float

from .._core import GRAVITY, ParameterError, check_x64, run_time_checks_off
from ..manoeuvre._steady import condition_kinds, steady_state_core
from ..vehicle import car_rates, check_car, installation_ratios, load_car

#: The skid-pad radius of Fig. 7.2 (m).
SKID_PAD_RADIUS = 50.0
#: The two "low" lateral accelerations (g) between which χ is reported (module docs).
LOW_AY_PAIR_G = (0.05, 0.1)
#: The lower of them (g).
LOW_AY_G = LOW_AY_PAIR_G[0]
#: Lateral accelerations (g) of the load-transfer curve (Fig. 7.2a); the first two are
#: :data:`LOW_AY_PAIR_G`.
AY_GRID_G = (0.05, 0.1, 0.2, 0.4, 0.6, 0.8, 1.0, 1.2)
#: λ of the roll-stiffness sweep (Fig. 7.2b).
LAMBDA_RANGE = (0.2, 0.8)
#: Modal stiffness multipliers µ of the single-mode sweep (Fig. 7.2d), log spaced.
MU_RANGE = (0.1, 10.0)
#: Newton steps per steady state.
MAX_STEPS = 64


class LoadTransfer(eqx.Module):
    """Load transfer of one car (or of a batch, with a leading axis on every field):
    ``ay`` (m/s^2, > 0), per-wheel transfers ``front`` and ``rear`` (N; module docs),
    ``chi`` = front / (front + rear) at each ay (the secant share), the right-less-left load differences
    ``diff_left`` (turning left, +ay) and ``diff_right`` (turning right, -ay), shape
    ``(n_ay, 2)`` (front, rear axle; N), and ``ok`` (both turns converged)."""

    ay: Float[Array, " n_ay"]
    front: Float[Array, " n_ay"]
    rear: Float[Array, " n_ay"]
    chi: Float[Array, " n_ay"]
    diff_left: Float[Array, "n_ay 2"]
    diff_right: Float[Array, "n_ay 2"]
    ok: Bool[Array, " n_ay"]

    @property
    def chi_low_ay(self) -> Float[Array, "..."]:
        """χ at low ay: the incremental share between the first two ay (module docs)."""
        return _incremental(self.front, self.rear)


def _transfers(car, ay, radius, max_steps: int = MAX_STEPS) -> LoadTransfer:
    """The pure core: left and right turns at every ``ay`` (m/s^2) on ``radius`` (m)."""
    yaw = jnp.sqrt(ay / radius)
    kinds = condition_kinds(("ay", "yaw_rate"))
    left = jnp.stack([ay, yaw], axis=-1)
    values = jnp.concatenate([left, -left])
    res = jax.vmap(lambda v: steady_state_core(car, kinds, v, max_steps=max_steps)[0])(values)
    fz = res.channels["fz"]
    diff = jnp.stack([fz[:, 1] - fz[:, 0], fz[:, 3] - fz[:, 2]], axis=-1)
    n = ay.shape[0]
    d_left, d_right = diff[:n], diff[n:]
    transfer = 0.25 * (d_left - d_right)
    front, rear = transfer[:, 0], transfer[:, 1]
    return LoadTransfer(ay=ay, front=front, rear=rear, chi=front / (front + rear), diff_left=d_left,
                        diff_right=d_right, ok=res.ok[:n] & res.ok[n:])


def load_transfer_core(car, ay, radius, max_steps: int = MAX_STEPS) -> LoadTransfer:
    """The pure core of :func:`load_transfer_batch` for one car (jit, vmap, grad; no checks):
    its :class:`LoadTransfer` from the left and right steady turns at every ``ay`` (m/s^2,
    an array, > 0) on ``radius`` (m), ``max_steps`` Newton steps each."""
    return _transfers(car, ay, radius, max_steps)


def _incremental(front, rear):
    d_front, d_rear = front[..., 1] - front[..., 0], rear[..., 1] - rear[..., 0]
    return d_front / (d_front + d_rear)


def _with(car, params):
    return eqx.tree_at(lambda c: c.params, car, params)


def _batched(car, params, ay, radius) -> LoadTransfer:
    """:func:`_transfers` of each of the stacked car parameters ``params`` (leading axis), one
    after the other inside the compiled call (``jax.lax.map``). Not ``jax.vmap``: batching the
    designs batches their steady states' LAPACK solves, and two such batched solves running
    at once deadlock jaxlib 0.10.2's CPU thread pool (seen in sweeps and in study (a),
    docs/optimise.md); batching gained under 15 % on the car."""
    return jax.lax.map(lambda p: _transfers(_with(car, p), ay, radius), params)


_compiled_batch = eqx.filter_jit(_batched)


def _chi_low(car, ay, radius):
    return _transfers(car, ay, radius).chi_low_ay


def _stack(params_list):
    return jax.tree.map(lambda *x: jnp.stack(x), *params_list)


def _check_ay(ay_g) -> np.ndarray:
    ay_g = np.atleast_1d(np.asarray(ay_g, float))
    if ay_g.ndim != 1 or ay_g.size < 2 or not np.all(np.isfinite(ay_g)) or not np.all(ay_g > 0.0):
        raise ParameterError(f"ay_g = {ay_g.tolist()!r} is out of range: allowed a sequence of at least two "
                             "lateral accelerations > 0 (g), the first two giving χ at low ay")
    return ay_g


def _check_radius(radius) -> float:
    if not float(radius) > 0.0:
        raise ParameterError(f"radius = {radius!r} is out of range: allowed > 0 (m)")
    return float(radius)


def load_transfer_batch(car, params, ay_g=AY_GRID_G, radius=SKID_PAD_RADIUS) -> LoadTransfer:
    """:class:`LoadTransfer` of the car with each of the stacked :class:`~jaxveh.vehicle.CarParams`
    ``params`` (leading axis: the designs) at the lateral accelerations ``ay_g`` (g) on
    ``radius`` (m): one compiled call (one program per mode count, number of designs and
    number of ay values; the designs one after the other, :func:`_batched`)."""
    check_x64()
    ay = jnp.asarray(_check_ay(ay_g) * GRAVITY)
    radius = jnp.asarray(_check_radius(radius))
    n = jax.tree.leaves(params)[0].shape[0]
    for i in range(n):  # the range checks of every design, by name, before compiling
        check_car(_with(car, jax.tree.map(lambda x, i=i: x[i], params)))
    with run_time_checks_off():
        return _compiled_batch(car, params, ay, radius)


def load_transfer(car, ay_g=AY_GRID_G, radius=SKID_PAD_RADIUS) -> LoadTransfer:
    """Per-wheel front and rear lateral load transfer (N) and χ of the car at the lateral
    accelerations ``ay_g`` (g, > 0) on a circle of ``radius`` m (Fig. 7.2a; module docs)."""
    batch = load_transfer_batch(car, _stack([car.params]), ay_g, radius)
    return jax.tree.map(lambda x: x[0], batch)


# ---- the designs of the sweeps --------------------------------------------------------------


def arb_rates_for_distribution(car, lam) -> Float[Array, "2"]:
    """Anti-roll-bar rates (N m/rad of bar twist, front and rear) that give the car the roll
    stiffness distribution λ = kF / (kF + kR) (``lam``, in (0, 1)).

    kF and kR are the suspension's roll stiffnesses of :func:`jaxveh.vehicle.car_rates`:
    springs through the push-rod/rocker motion ratios plus the bars, ``K = K_springs +
    k_arb (dθ/dz t)^2``. The car's total ``K0 = kF + kR`` is kept while both bars stay
    >= 0 (λ between ``K_springs,F / K0`` and ``1 - K_springs,R / K0``, 0.377-0.622 on the
    shipped car); beyond, the softer axle's bar is 0 and the other axle's bar is raised
    until λ is reached (the total then grows). Springs are never changed. Differentiable."""
    lam = jnp.asarray(lam, jnp.float64)
    if not np.all((np.asarray(lam) > 0.0) & (np.asarray(lam) < 1.0)):
        raise ParameterError(f"lam = {np.asarray(lam).tolist()!r} is out of range: allowed 0 < lam < 1 "
                             "(roll stiffness distribution kF / (kF + kR))")
    rates = car_rates(car)
    f, r = rates["front"], rates["rear"]
    sF, sR = f.roll_stiffness_springs, r.roll_stiffness_springs
    # bar roll stiffness per unit bar rate, (dθ/dz t)^2
    v = car.params.vehicle
    gF = (installation_ratios("front", v).rocker * v.track_front) ** 2
    gR = (installation_ratios("rear", v).rocker * v.track_rear) ** 2
    k0 = f.roll_stiffness + r.roll_stiffness
    kF = jnp.maximum(lam * k0, sF)
    kR = jnp.maximum((1.0 - lam) * k0, sR)
    # raise the stiffer side so that kF / (kF + kR) = lam exactly
    kF = jnp.maximum(kF, lam / (1.0 - lam) * kR)
    kR = jnp.maximum(kR, (1.0 - lam) / lam * kF)
    return jnp.stack([(kF - sF) / gF, (kR - sR) / gR], axis=-1)


def lambda_designs(car, lams):
    """Stacked car parameters, one per λ of ``lams`` (:func:`arb_rates_for_distribution`)."""
    rates = arb_rates_for_distribution(car, jnp.asarray(lams, jnp.float64))
    return _stack([eqx.tree_at(lambda p: p.arb_rates, car.params, r) for r in rates])


def _check_modal(car):
    if car.n_modes == 0:
        raise ParameterError("the car has a rigid chassis (modes = 0): a modal stiffness multiplier needs modes >= 1")


def _check_mu(mu):
    mu = np.atleast_1d(np.asarray(mu, float))
    if not np.all(np.isfinite(mu)) or not np.all(mu > 0.0):
        raise ParameterError(f"mu = {mu.tolist()!r} is out of range: allowed finite multipliers > 0 of a mode's "
                             "stiffness")
    return mu


def mode_stiffness_designs(car, mus):
    """Stacked car parameters: for each mode i (outer) and each µ of ``mus`` (inner), the car
    with mode i's stiffness multiplied by µ (``chassis.stiffness_scale[i]``; the others 1)."""
    _check_modal(car)
    mus = _check_mu(mus)
    scale = car.params.chassis.stiffness_scale
    out = []
    for i in range(car.n_modes):
        for mu in mus:
            out.append(eqx.tree_at(lambda p: p.chassis.stiffness_scale, car.params, scale.at[i].set(mu)))
    return _stack(out)


# ---- the analyses of Fig. 7.2 ---------------------------------------------------------------


def chi_vs_lambda(car, lams, radius=SKID_PAD_RADIUS, ay_g=LOW_AY_PAIR_G) -> Float[Array, " n"]:
    """χ between the two ``ay_g`` (g) against the roll stiffness distribution ``lams`` (Fig. 7.2b), one
    vmapped call; λ set through the anti-roll bars (:func:`arb_rates_for_distribution`)."""
    return load_transfer_batch(car, lambda_designs(car, lams), ay_g, radius).chi_low_ay


def chi_vs_mode_stiffness(car, mus, radius=SKID_PAD_RADIUS, ay_g=LOW_AY_PAIR_G) -> Float[Array, "n_modes n_mu"]:
    """χ between the two ``ay_g`` (g) with each single mode's stiffness multiplied by each µ of ``mus``
    (> 0; Fig. 7.2d), one vmapped call: row i is mode i (0-based)."""
    chi = load_transfer_batch(car, mode_stiffness_designs(car, mus), ay_g, radius).chi_low_ay
    return chi.reshape(car.n_modes, -1)


def _check_max_modes(max_modes, low: int) -> None:
    if isinstance(max_modes, bool) or not isinstance(max_modes, (int, np.integer)) or not low <= max_modes <= 20:
        raise ParameterError(f"max_modes = {max_modes!r} is out of range: allowed integers {low} to 20")


def chi_vs_modes(max_modes: int = 6, path=None, radius=SKID_PAD_RADIUS, ay_g=LOW_AY_PAIR_G) -> Float[Array, " n"]:
    """χ between the two ``ay_g`` (g) of the car file ``path`` (default: the shipped car) with 0 (rigid)
    to ``max_modes`` chassis modes (Fig. 7.2c). Each mode count is its own structure and so
    its own compiled program (about a minute or two each on two cores)."""
    _check_max_modes(max_modes, 0)
    return jnp.stack([load_transfer(load_car(path, modes=n), ay_g, radius).chi_low_ay
                      for n in range(max_modes + 1)])


#: Stiffness multiplier that freezes a mode in :func:`chi_by_modes` (its deflection and its
#: effect on χ fall as 1 / multiplier).
FREEZE = 1e8


def truncation_designs(car):
    """Stacked car parameters: for k = 0 ... ``car.n_modes``, the car with modes k+1 ... n
    frozen (stiffness multiplied by :data:`FREEZE`), i.e. with its first k modes only."""
    _check_modal(car)
    scale = car.params.chassis.stiffness_scale
    index = jnp.arange(car.n_modes)
    return _stack([eqx.tree_at(lambda p: p.chassis.stiffness_scale, car.params,
                               jnp.where(index < k, scale, scale * FREEZE)) for k in range(car.n_modes + 1)])


def chi_by_modes(max_modes: int = 10, path=None, radius=SKID_PAD_RADIUS, ay_g=LOW_AY_PAIR_G) -> Float[Array, " n"]:
    """χ between the two ``ay_g`` (g) of the car file ``path`` with its first k chassis modes,
    k = 0 ... ``max_modes`` (entry 0: rigid; Fig. 7.2c), as one vmapped call on the
    ``max_modes``-mode car with the other modes frozen (:func:`truncation_designs`): the
    modal truncation keeps the first modes' shapes, so the first k modes of the larger car
    are the k-mode car's, and a frozen mode's share of χ is below 1e-7 (tested against
    :func:`chi_vs_modes`, which compiles one program per mode count)."""
    _check_max_modes(max_modes, 1)
    car = load_car(path, modes=max_modes)
    return load_transfer_batch(car, truncation_designs(car), ay_g, radius).chi_low_ay


_grad_chi = eqx.filter_jit(eqx.filter_grad(lambda scale, car, ay, radius: _chi_low(
    eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, car, scale), ay, radius)))


def chi_mode_stiffness_gradient(car, radius=SKID_PAD_RADIUS, ay_g=LOW_AY_PAIR_G) -> Float[Array, " n_modes"]:
    """``d χ / d µ_i`` (per unit multiplier) of χ between the two ``ay_g`` (g) with respect to each
    mode's stiffness multiplier, at the car's own multipliers, by ``jax.grad`` through the
    root finding (implicit function theorem)."""
    check_x64()
    _check_modal(car)
    ay = jnp.asarray(_check_ay(ay_g)[:2] * GRAVITY)
    radius = jnp.asarray(_check_radius(radius))
    with run_time_checks_off():
        return _grad_chi(car.params.chassis.stiffness_scale, check_car(car), ay, radius)
