"""Magic Formula 5.2 (PAC2002) steady-state force and moment equations, pure JAX.

Sign convention: ISO-W (TYDEX W-axis), as MF-Tyre and ``.tir`` files use. Axes at the
contact point: x forward along the wheel heading in the road plane, z up (road normal), y
left. Inputs:

- ``kappa``: longitudinal slip, ``-Vsx / |Vx|`` (positive when driving, Fx > 0);
- ``alpha``: slip angle [rad], ``tan(alpha) = Vsy / |Vx|`` (contact point sliding left is
  positive; a positive slip angle gives a *negative* Fy when PKY1 < 0, as in every MF 5.2
  file);
- ``gamma``: inclination angle [rad], a right-handed rotation about x: positive when the
  wheel top leans towards -y (right); camber thrust pushes towards the lean;
- ``fz``: normal load [N], positive in compression (as MF-Tyre takes it).

Outputs act on the tyre at the contact point in the same axes: Fx, Fy [N], overturning
moment Mx, rolling resistance moment My, aligning moment Mz [Nm].

Numerical treatment (all documented in ``docs/tyre.md``):

- lift-off: the formula is evaluated at ``max(fz, F_floor)`` with ``F_floor =
  LIFTOFF_FRACTION * FNOMIN * LFZO`` and every output is scaled by ``s(x) = x^2 (2 - x)``,
  ``x = clip(fz / F_floor, 0, 1)``: exactly zero for ``fz <= 0``, exact MF 5.2 above
  ``F_floor``; continuously differentiable at lift-off (zero slope), and at the floor the
  slope ``F(F_floor)/F_floor`` is the secant of the nearly linear low-load MF; finite
  gradients everywhere;
- slips, camber and load are clipped to wide finite bands (``SLIP_CLIP``, ``CAMBER_CLIP``,
  ``LOAD_CLIP_FACTOR``) only so that no finite input produces inf - inf;
- speed only enters the rolling resistance moment, whose sign follows
  ``tanh(vx / VXLOW)`` so it vanishes smoothly at standstill;
- the equivalent slip angles of combined Mz enter only even functions, so their sign is
  dropped and the square root uses a safe double-``where`` at zero slip;
- sines, cosines and tangents are :mod:`jaxveh._trig`'s fused arithmetic; the arctangents
  stay ``jnp``'s, whose fused form split the nested formulas into twice the kernels
  (docs/manoeuvre.md, "Speed", thirtieth measurement).
"""

from typing import TYPE_CHECKING

import jax.numpy as jnp
from jaxtyping import Array, ArrayLike, Float

from .._trig import cos, sin, tan
from ._base import TyreForces

if TYPE_CHECKING:
    from ._model import MagicFormulaTyre

#: Below this fraction of the nominal load the forces scale linearly with load to zero.
LIFTOFF_FRACTION = 0.01
#: |kappa| and |alpha| [rad] are clipped here so the formula stays finite for any input.
SLIP_CLIP = 1.0e6
#: |gamma| [rad] is clipped to a right angle (a larger inclination has no meaning).
CAMBER_CLIP = 0.5 * jnp.pi
#: Loads above this multiple of FNOMIN are clipped (keeps dfz**2 finite).
LOAD_CLIP_FACTOR = 1.0e3
#: |vx| [m/s] is clipped here in the rolling resistance polynomial.
SPEED_CLIP = 1.0e3

Scalar = Float[Array, ""]


def _safe_div(num, den):
    """``num / den`` with 0 where ``den == 0`` (double where: finite gradients)."""
    zero = den == 0.0
    return jnp.where(zero, 0.0, num / jnp.where(zero, 1.0, den))


def _mf(b, c, d, e, x):
    """The Magic Formula sine form ``D sin(C atan(Bx - E(Bx - atan Bx)))``."""
    bx = b * x
    return d * sin(c * jnp.arctan(bx - e * (bx - jnp.arctan(bx))))


def _mf_cos(b, c, e, x):
    """The cosine weighting ``cos(C atan(Bx - E(Bx - atan Bx)))`` (value 1 at x = 0)."""
    bx = b * x
    return cos(c * jnp.arctan(bx - e * (bx - jnp.arctan(bx))))


def _weight(b, c, e, x, shift):
    """Combined-slip weighting function ``G = cos(..x + shift..) / cos(..shift..)``."""
    return _mf_cos(b, c, e, x + shift) / _mf_cos(b, c, e, shift)


def _longitudinal(t: "MagicFormulaTyre", fz, dfz, kappa, gamma):
    """Pure-slip Fx0 and the longitudinal slip stiffness Kx [N]."""
    gx = gamma * t.lgax
    shx = (t.phx1 + t.phx2 * dfz) * t.lhx
    kx_ = kappa + shx
    cx = t.pcx1 * t.lcx
    mux = (t.pdx1 + t.pdx2 * dfz) * (1.0 - t.pdx3 * gx**2) * t.lmux
    dx = mux * fz
    ex = (t.pex1 + t.pex2 * dfz + t.pex3 * dfz**2) * (1.0 - t.pex4 * jnp.sign(kx_)) * t.lex
    ex = jnp.minimum(ex, 1.0)
    kxk = fz * (t.pkx1 + t.pkx2 * dfz) * jnp.exp(t.pkx3 * dfz) * t.lkx
    bx = _safe_div(kxk, cx * dx)
    svx = fz * (t.pvx1 + t.pvx2 * dfz) * t.lvx * t.lmux
    return _mf(bx, cx, dx, ex, kx_) + svx, kxk


def _lateral(t: "MagicFormulaTyre", fz, fz0, dfz, alpha, gamma):
    """Pure-slip Fy0 and the quantities Mz and combined Fy need."""
    gy = gamma * t.lgay
    shy = (t.phy1 + t.phy2 * dfz) * t.lhy + t.phy3 * gy
    ay = alpha + shy
    cy = t.pcy1 * t.lcy
    muy = (t.pdy1 + t.pdy2 * dfz) * (1.0 - t.pdy3 * gy**2) * t.lmuy
    dy = muy * fz
    ey = (t.pey1 + t.pey2 * dfz) * (1.0 - (t.pey3 + t.pey4 * gy) * jnp.sign(ay)) * t.ley
    ey = jnp.minimum(ey, 1.0)
    ky = t.pky1 * fz0 * sin(2.0 * jnp.arctan(fz / (t.pky2 * fz0))) * (1.0 - t.pky3 * jnp.abs(gy)) * t.lky
    by = _safe_div(ky, cy * dy)
    svy = fz * ((t.pvy1 + t.pvy2 * dfz) * t.lvy + (t.pvy3 + t.pvy4 * dfz) * gy) * t.lmuy
    fy0 = _mf(by, cy, dy, ey, ay) + svy
    return fy0, muy, ky, by, cy, shy, svy


def _safe_sqrt(q):
    """``sqrt(q)`` for ``q >= 0`` with a zero (not NaN) gradient at ``q = 0``."""
    pos = q > 0.0
    return jnp.where(pos, jnp.sqrt(jnp.where(pos, q, 1.0)), 0.0)


def tyre_forces(
    tyre: "MagicFormulaTyre",
    fz: ArrayLike,
    kappa: ArrayLike,
    alpha: ArrayLike,
    gamma: ArrayLike,
    vx: ArrayLike | None = None,
) -> TyreForces:
    """MF 5.2 combined-slip forces and moments of one tyre at one operating point.

    Args:
        tyre: the coefficients.
        fz: normal load [N], positive in compression; ``fz <= 0`` (lift-off) gives zero.
        kappa: longitudinal slip [-] (ISO-W, positive driving).
        alpha: slip angle [rad] (ISO-W, ``tan(alpha) = Vsy/|Vx|``).
        gamma: inclination angle [rad] (ISO-W, top of wheel towards -y positive).
        vx: forward speed of the wheel centre [m/s]; only the rolling resistance moment
            depends on it. Default: the measurement speed ``LONGVL``.

    Returns:
        :class:`TyreForces` (fx, fy, mx, my, mz) in N and Nm, ISO-W contact-point axes.

    Scalars in, scalars out: ``jax.vmap`` for batches.
    """
    t = tyre
    vx = t.longvl if vx is None else jnp.asarray(vx, dtype=jnp.float64)
    fz = jnp.asarray(fz, dtype=jnp.float64)
    kappa = jnp.clip(jnp.asarray(kappa, dtype=jnp.float64), -SLIP_CLIP, SLIP_CLIP)
    alpha = jnp.clip(jnp.asarray(alpha, dtype=jnp.float64), -SLIP_CLIP, SLIP_CLIP)
    gamma = jnp.clip(jnp.asarray(gamma, dtype=jnp.float64), -CAMBER_CLIP, CAMBER_CLIP)
    r0 = t.unloaded_radius
    fz0 = t.fnomin * t.lfzo

    # lift-off: evaluate at a positive load, scale to zero below the floor
    floor = LIFTOFF_FRACTION * fz0
    fz_eval = jnp.clip(fz, floor, LOAD_CLIP_FACTOR * fz0)
    x = jnp.clip(fz / floor, 0.0, 1.0)
    scale = x * x * (2.0 - x)  # 0 at lift-off with zero slope, 1 (slope 1/floor) at the floor
    fz = fz_eval
    dfz = (fz - fz0) / fz0

    fx0, kxk = _longitudinal(t, fz, dfz, kappa, gamma)
    fy0, muy, ky, by, cy, shy, svy = _lateral(t, fz, fz0, dfz, alpha, gamma)

    # combined Fx
    bxa = t.rbx1 * cos(jnp.arctan(t.rbx2 * kappa)) * t.lxal
    gxa = _weight(bxa, t.rcx1, jnp.minimum(t.rex1 + t.rex2 * dfz, 1.0), alpha, t.rhx1)
    fx = gxa * fx0

    # combined Fy with kappa-induced side force
    byk = t.rby1 * cos(jnp.arctan(t.rby2 * (alpha - t.rby3))) * t.lyka
    gyk = _weight(byk, t.rcy1, jnp.minimum(t.rey1 + t.rey2 * dfz, 1.0), kappa, t.rhy1 + t.rhy2 * dfz)
    dvyk = muy * fz * (t.rvy1 + t.rvy2 * dfz + t.rvy3 * gamma) * cos(jnp.arctan(t.rvy4 * alpha))
    svyk = dvyk * sin(t.rvy5 * jnp.arctan(t.rvy6 * kappa)) * t.lvyka
    fy = gyk * fy0 + svyk

    # aligning moment: pneumatic trail and residual torque at equivalent slip angles
    gz = gamma * t.lgaz
    sht = t.qhz1 + t.qhz2 * dfz + (t.qhz3 + t.qhz4 * dfz) * gz
    at = alpha + sht
    ar = alpha + shy + _safe_div(svy, ky)
    bt = (t.qbz1 + t.qbz2 * dfz + t.qbz3 * dfz**2) * (1.0 + t.qbz4 * gz + t.qbz5 * jnp.abs(gz)) * t.lky / t.lmuy
    ct = t.qcz1
    dt = fz * (t.qdz1 + t.qdz2 * dfz) * (1.0 + t.qdz3 * gz + t.qdz4 * gz**2) * (r0 / fz0) * t.ltr
    et = (t.qez1 + t.qez2 * dfz + t.qez3 * dfz**2) * (
        1.0 + (t.qez4 + t.qez5 * gz) * (2.0 / jnp.pi) * jnp.arctan(bt * ct * at)
    )
    et = jnp.minimum(et, 1.0)
    br = t.qbz9 * t.lky / t.lmuy + t.qbz10 * by * cy
    dr = fz * ((t.qdz6 + t.qdz7 * dfz) * t.lres + (t.qdz8 + t.qdz9 * dfz) * gz) * r0 * t.lmuy
    kratio2 = _safe_div(kxk, ky) ** 2 * kappa**2
    at_eq = jnp.arctan(_safe_sqrt(tan(at) ** 2 + kratio2))  # sign dropped: even functions
    ar_eq = jnp.arctan(_safe_sqrt(tan(ar) ** 2 + kratio2))
    cos_a = cos(alpha)
    trail = dt * _mf_cos(bt, ct, et, at_eq) * cos_a
    mzr = dr * cos(jnp.arctan(br * ar_eq)) * cos_a
    s = r0 * (t.ssz1 + t.ssz2 * (fy / fz0) + (t.ssz3 + t.ssz4 * dfz) * gamma) * t.ls
    mz = -trail * (fy - svyk) + mzr + s * fx

    # overturning and rolling resistance moments
    mx = r0 * fz * (t.qsx1 * t.lvmx - t.qsx2 * gamma + t.qsx3 * fy / fz0) * t.lmx
    vr = jnp.clip(vx, -SPEED_CLIP, SPEED_CLIP) / t.longvl
    my = (
        -r0 * fz * (t.qsy1 + t.qsy2 * fx / fz0 + t.qsy3 * jnp.abs(vr) + t.qsy4 * vr**4) * t.lmy
        * jnp.tanh(vx / t.vxlow)
    )
    return TyreForces(fx=scale * fx, fy=scale * fy, mx=scale * mx, my=scale * my, mz=scale * mz)
