"""Tyres at the contact patch (thesis section 6.1.5, "Tyres"): a force element that puts MF
5.2 tyres (:mod:`jaxveh.tyre`) under the wheels of a multibody system on a road.

The road (:class:`FlatRoad` by default, :class:`PostRoad` for a four-post rig, or any
:class:`AbstractRoad`) gives a height under each wheel as a function of the wheel centre's
``(x, y)`` and time; the tyre sees the local tangent plane there. Per wheel, from the
library's kinematics pass (global axes, z up):

- spin axis ``a`` (the wheel body's y axis), road normal ``n``; ISO-W axes at the contact
  point ``e_x = unit(a × n)`` (heading), ``e_y = n × e_x``; inclination
  ``γ = asin(a · n)`` (positive with the top leaning to -y: the ISO-W sign, the same formula
  for left and right wheels because every wheel axis points to the left);
- the wheel plane meets the road plane at ``h = d / cos γ`` from the centre along the
  plane's downward radial direction (``d`` the centre's height above the road plane):
  contact point ``C``, deflection ``ρ = R0 - h`` and its rate (a ``jvp`` with the centre's
  velocity, the axis's rate ``ω × a`` and the road's own motion), normal load
  ``tyre.vertical_force(ρ, ρ_dot)`` (lift-off at zero);
- slip velocities of the contact point carried by the upright: ``v_x``, ``v_sy`` along
  ``e_x``, ``e_y``, and ``v_sx = v_x - Ω R_e(F_z)`` with the spin ``Ω`` of the wheel relative
  to the upright;
- two relaxation states per wheel (the contact deflections ``[u, v]``, m;
  ``tyre.transient_slip_rhs``) give the lagged slips ``κ'``, ``α'`` of ``tyre_forces``;
- the road's force ``F_x e_x + F_y e_y + F_z n`` and moment ``M_x e_x + M_y e_y + M_z n`` act
  at ``C`` on the wheel body: at its centre point with the moment ``(C - W) × F + M``.

The tyre's own mass, spin inertia and rolling radius belong to the bodies and the tyre file.
"""

import abc
import functools

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np

from .._trig import arcsin
from ..multibody import AbstractForceElement, ElementForces, zero_forces
from ..tyre import (
    effective_rolling_radius,
    transient_slip_rhs,
    transient_slips,
    tyre_forces,
    vertical_force,
)

#: Auxiliary states of one wheel: longitudinal and lateral contact deflection (m).
WHEEL_STATES = ("u", "v")


def _unit(v):
    return v / jnp.linalg.norm(v)


class AbstractRoad(eqx.Module):
    """A road: ``height(x, y, t, wheel)`` (m) under the point ``(x, y)`` (m) at time ``t``
    (s) for wheel number ``wheel`` (a traced integer). Smooth in ``x``, ``y``, ``t``: the
    tyre uses its gradient (the road normal) and its rate."""

    @abc.abstractmethod
    def height(self, x, y, t, wheel):
        """Road height (m)."""

    def kinks(self) -> tuple:
        """Times (s) where a derivative of the road's motion jumps, where the integrator
        ends its steps (none by default)."""
        return ()


class FlatRoad(AbstractRoad):
    """The plane ``z = 0``."""

    def height(self, x, y, t, wheel):
        return jnp.zeros_like(x + y + t)


class PostRoad(AbstractRoad):
    """A four-post (or n-post) rig: each wheel stands on a flat post whose height follows
    ``height_fn(t) -> [n_wheels]`` (m), e.g. a sine sweep; static callable, so a new law
    recompiles (put its numbers in an Equinox module to vary them without)."""

    height_fn: object

    def height(self, x, y, t, wheel):
        return self.height_fn(t)[wheel] + jnp.zeros_like(x + y)


def contact_geometry(centre, axis, road_height=0.0, road_slope=(0.0, 0.0)):
    """``(e_x, e_y, γ, h, C, n)``: ISO-W heading and lateral axes, inclination (rad),
    distance from the wheel centre to the road along the wheel plane (m), the contact point
    (m) and the road normal, for the road plane through ``(x_W, y_W, road_height)`` with
    slopes ``(dz/dx, dz/dy)``."""
    normal = _unit(jnp.stack([-road_slope[0], -road_slope[1], jnp.ones_like(road_slope[0])]))
    e_x = _unit(jnp.cross(axis, normal))
    e_y = jnp.cross(normal, e_x)
    sin_gamma = jnp.dot(axis, normal)
    radial = normal - sin_gamma * axis  # in the wheel plane, towards the top
    cos_gamma = jnp.linalg.norm(radial)
    height = (centre[2] - road_height) * normal[2]  # above the road plane, along its normal
    h = height / cos_gamma
    contact = centre - h * radial / cos_gamma
    return e_x, e_y, arcsin(jnp.clip(sin_gamma, -1.0, 1.0)), h, contact, normal


def wheel_contact(tyre, centre, centre_velocity, axis, omega_wheel, omega_upright, deflection,
                  road: AbstractRoad = FlatRoad(), t=0.0, wheel=0, horizontal: bool = True):
    """One wheel: ``(force, moment about the centre, deflection rates, outputs)`` (global
    axes, N and N m; outputs: ``fz``, ``kappa``, ``alpha``, ``gamma``, ``fx``, ``fy``,
    ``road_height``). ``horizontal=False`` keeps only the normal load (the wheel on a
    frictionless plate, as on corner-weight scales with slip plates)."""
    axis_rate = jnp.cross(omega_upright, axis)
    t = jnp.asarray(t, centre.dtype)

    def geometry(c, a, tt):
        z_road, slope = jax.value_and_grad(road.height, argnums=(0, 1))(c[0], c[1], tt, wheel)
        return contact_geometry(c, a, z_road, slope) + (z_road,)

    (e_x, e_y, gamma, h, contact, normal, z_road), (_, _, _, h_dot, _, _, _) = jax.jvp(
        geometry, (centre, axis, t), (centre_velocity, axis_rate, jnp.ones_like(t))
    )
    fz = vertical_force(tyre, tyre.unloaded_radius - h, -h_dot)
    contact_velocity = centre_velocity + jnp.cross(omega_upright, contact - centre)
    vx, vsy = jnp.dot(contact_velocity, e_x), jnp.dot(contact_velocity, e_y)
    spin = jnp.dot(omega_wheel - omega_upright, axis)
    vsx = vx - spin * effective_rolling_radius(tyre, fz)
    rates = transient_slip_rhs(tyre, deflection, fz, gamma, vx, vsx, vsy)
    kappa, alpha = transient_slips(tyre, deflection, fz, gamma)
    f = tyre_forces(tyre, fz, kappa, alpha, gamma, vx)
    if not horizontal:
        f = jax.tree.map(jnp.zeros_like, f)
        rates = jnp.zeros_like(rates)
    force = f.fx * e_x + f.fy * e_y + jnp.maximum(fz, 0.0) * normal
    moment = f.mx * e_x + f.my * e_y + f.mz * normal + jnp.cross(contact - centre, force)
    outputs = {"fz": fz, "kappa": kappa, "alpha": alpha, "gamma": gamma, "fx": f.fx, "fy": f.fy,
               "road_height": z_road}
    return force, moment, rates, outputs


class TyreContact(AbstractForceElement):
    """MF 5.2 tyres under wheels on a flat road (see module). Static per wheel: ``wheel``
    (a point on the wheel body at its centre) and ``upright`` (a point on the upright);
    ``tyres`` the tyre of each wheel stacked on a leading axis (``jaxveh.tyre.stack_tyres``);
    ``aux_names``: ``<name>.u``, ``<name>.v`` per wheel; ``horizontal`` (static): False
    keeps only the normal loads (static set-up on frictionless plates)."""

    wheel: tuple[int, ...] = eqx.field(static=True)
    upright: tuple[int, ...] = eqx.field(static=True)
    tyres: object
    aux_names: tuple[str, ...] = eqx.field(static=True)
    road: AbstractRoad = FlatRoad()
    horizontal: bool = eqx.field(static=True, default=True)

    @classmethod
    def on(cls, system, wheels: dict, tyres, road: AbstractRoad = FlatRoad(), horizontal: bool = True) -> "TyreContact":
        """``wheels``: ``{name: (wheel-centre point on the wheel body, a point on the
        upright)}``; ``tyres``: one stacked tyre per wheel, in the same order; ``road``."""
        names = list(wheels)
        return cls(
            wheel=tuple(system.point_index(wheels[n][0]) for n in names),
            upright=tuple(system.point_index(wheels[n][1]) for n in names),
            tyres=tyres,
            aux_names=tuple(f"{n}.{s}" for n in names for s in WHEEL_STATES),
            road=road,
            horizontal=horizontal,
        )

    def evaluate(self, kin, aux):
        """Per-wheel ``(force, moment, deflection rates, outputs)`` (leading axis: wheels)."""
        w, u = np.asarray(self.wheel, int), np.asarray(self.upright, int)
        axes = kin.point_rotations[w][:, :, 1]
        n = len(self.wheel)
        contact = functools.partial(wheel_contact, horizontal=self.horizontal)
        return jax.vmap(contact, in_axes=(0, 0, 0, 0, 0, 0, 0, None, None, 0))(
            self.tyres, kin.x[w], kin.xd[w], axes, kin.point_omega[w], kin.point_omega[u],
            jnp.reshape(aux, (n, 2)), self.road, kin.t, jnp.arange(n))

    def __call__(self, kin, aux, system):
        force, moment, rates, _ = self.evaluate(kin, aux)
        w = np.asarray(self.wheel, int)
        out = zero_forces(kin)
        return ElementForces(forces=out.forces.at[w].add(force), torques=out.torques.at[w].add(moment),
                             aux_dot=jnp.reshape(rates, (-1,)))
