"""Slip from wheel kinematics, and first-order relaxation-length lag on kappa and alpha.

Transient slip (thesis section 6.1: "a first order lag applied to the inputs of the Magic
Formula", relaxation lengths sigma_kappa, sigma_alpha) in Pacejka's deflection form, which
never divides by the speed. States are the contact deflections ``u`` and ``v`` [m]:

    du/dt = -Vsx - |Vx| u / sigma_kappa,        kappa' = u / sigma_kappa
    dv/dt =  Vsy - |Vx| v / sigma_alpha,        alpha' = atan(v / sigma_alpha)

At constant speed the lagged slips tend to the steady ISO-W slips ``kappa = -Vsx/|Vx|``,
``tan(alpha) = Vsy/|Vx|`` with time constant ``sigma/|Vx|``; at standstill the deflections
integrate the slip velocity (a spring-like tyre), so nothing is singular at Vx = 0.
"""

from typing import TYPE_CHECKING

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._trig import sin
from ..params import Range, check
from ._magic_formula import LIFTOFF_FRACTION

if TYPE_CHECKING:
    from ._model import MagicFormulaTyre

Scalar = Float[Array, ""]


def relaxation_lengths(tyre: "MagicFormulaTyre", fz: ArrayLike, gamma: ArrayLike) -> tuple[Scalar, Scalar]:
    """Relaxation lengths ``(sigma_kappa, sigma_alpha)`` [m].

    ``relaxation_model == "constant"``: ``SIGMA_KAPPA * LSGKP``, ``SIGMA_ALPHA * LSGAL``
    (Table B.4: 0.3 m each). ``"mf52"`` (the file defines PTX1 and PTY1):

        sigma_kappa = Fz (PTX1 + PTX2 dfz) exp(-PTX3 dfz) (R0 / Fz0) LSGKP
        sigma_alpha = PTY1 sin(2 atan(Fz / (PTY2 Fz0))) (1 - PKY3 |gamma|) R0 LFZO LSGAL

    with the load floored at ``LIFTOFF_FRACTION * Fz0``. The lengths must come out > 0 (the
    coefficients are checked, but ``PTX2`` or ``PKY3 |gamma|`` can still drive them to zero at
    some loads or cambers): ``ParameterError``, or ``eqx.error_if`` when traced.
    """
    t = tyre
    if t.relaxation_model == "constant":
        return t.sigma_kappa * t.lsgkp, t.sigma_alpha * t.lsgal
    fz0 = t.fnomin * t.lfzo
    fz = jnp.maximum(jnp.asarray(fz, dtype=jnp.float64), LIFTOFF_FRACTION * fz0)
    gamma = jnp.asarray(gamma, dtype=jnp.float64)
    dfz = (fz - fz0) / fz0
    r0 = t.unloaded_radius
    sk = fz * (t.ptx1 + t.ptx2 * dfz) * jnp.exp(-t.ptx3 * dfz) * (r0 / fz0) * t.lsgkp
    sa = t.pty1 * sin(2.0 * jnp.arctan(fz / (t.pty2 * fz0))) * (1.0 - t.pky3 * jnp.abs(gamma * t.lgay))
    sa = sa * r0 * t.lfzo * t.lsgal
    return check("sigma_kappa", sk, _LENGTH_KAPPA), check("sigma_alpha", sa, _LENGTH_ALPHA)


_LENGTH_KAPPA = Range(0.0, low_open=True, what="MF 5.2 longitudinal relaxation length at this load, m")
_LENGTH_ALPHA = Range(0.0, low_open=True, what="MF 5.2 lateral relaxation length at this load and camber, m")


def transient_slip_rhs(
    tyre: "MagicFormulaTyre",
    deflection: Float[Array, "2"],
    fz: ArrayLike,
    gamma: ArrayLike,
    vx: ArrayLike,
    vsx: ArrayLike,
    vsy: ArrayLike,
) -> Float[Array, "2"]:
    """Time derivative of the contact deflections ``[u, v]`` [m/s].

    Args:
        deflection: ``[u, v]`` longitudinal and lateral contact deflection [m].
        fz: normal load [N] (for load-dependent relaxation lengths).
        gamma: inclination angle [rad].
        vx: forward speed of the wheel centre along the wheel heading [m/s].
        vsx: longitudinal slip velocity ``vx - omega * Re`` [m/s].
        vsy: lateral slip velocity of the contact point, +y left [m/s].
    """
    sk, sa = relaxation_lengths(tyre, fz, gamma)
    speed = jnp.abs(jnp.asarray(vx, dtype=jnp.float64))
    du = -jnp.asarray(vsx, dtype=jnp.float64) - speed * deflection[0] / sk
    dv = jnp.asarray(vsy, dtype=jnp.float64) - speed * deflection[1] / sa
    return jnp.stack([du, dv])


def transient_slips(
    tyre: "MagicFormulaTyre", deflection: Float[Array, "2"], fz: ArrayLike, gamma: ArrayLike
) -> tuple[Scalar, Scalar]:
    """Lagged slips ``(kappa', alpha')`` to feed :func:`tyre_forces` (alpha in rad)."""
    sk, sa = relaxation_lengths(tyre, fz, gamma)
    return deflection[0] / sk, jnp.arctan(deflection[1] / sa)


def low_speed_denominator(vx: ArrayLike, vxlow: ArrayLike) -> Scalar:
    """``|vx|`` above ``vxlow``; below it the C1 blend ``vxlow/2 + vx**2/(2 vxlow)`` [m/s].

    ``vxlow`` must be > 0 (``ParameterError``; traced: ``eqx.error_if``).
    """
    vxlow = check("vxlow", vxlow, Range(0.0, low_open=True, what="low-speed threshold VXLOW, m/s"))
    vx = jnp.asarray(vx, dtype=jnp.float64)
    speed = jnp.abs(vx)
    return jnp.where(speed >= vxlow, speed, 0.5 * vxlow + vx**2 / (2.0 * vxlow))


def steady_slips(tyre: "MagicFormulaTyre", vx: ArrayLike, vsx: ArrayLike, vsy: ArrayLike) -> tuple[Scalar, Scalar]:
    """Steady-state ISO-W slips ``(kappa, alpha)`` from slip velocities.

    ``kappa = -vsx / V``, ``alpha = atan(vsy / V)`` with ``V = low_speed_denominator(vx,
    VXLOW)``: exact for ``|vx| >= VXLOW``, finite (and C1) down to and through zero speed.
    """
    den = low_speed_denominator(vx, tyre.vxlow)
    return -jnp.asarray(vsx, dtype=jnp.float64) / den, jnp.arctan(jnp.asarray(vsy, dtype=jnp.float64) / den)
