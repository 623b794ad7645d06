"""Aerodynamic loads on the sprung mass (thesis section 6.1.5, "Aerodynamics"): drag and
downforce as look-up tables of the forward airspeed (still air), the downforce split
between a front and a rear chassis point (equivalent to the thesis's downforce plus
pitching moment). Tables continue linearly beyond their last speed (:func:`._springs.interpolate`).

Axes: drag acts along the chassis x axis against the forward speed ``u`` (the chassis
velocity at the reference point along its x axis), downforce along the chassis's -z axis.
The numbers are data (the car's TOML), not code; :func:`aero_map_from_coefficients` fills the
tables from ``C_d A`` and ``C_l A`` with ``F = rho C A u^2 / 2``.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from .._core import ParameterError, check_range, float_field, is_concrete
from ..multibody import AbstractForceElement, ElementForces, zero_forces
from ._springs import interpolate


class AeroMap(eqx.Module):
    """``speed`` (m/s, increasing from 0) -> ``drag``, ``downforce_front``,
    ``downforce_rear`` (N)."""

    speed: Float[Array, " n"] = float_field()
    drag: Float[Array, " n"] = float_field()
    downforce_front: Float[Array, " n"] = float_field()
    downforce_rear: Float[Array, " n"] = float_field()

    def __check_init__(self):
        n = self.speed.shape
        if self.speed.ndim != 1 or n[0] < 2 or any(x.shape != n for x in (self.drag, self.downforce_front,
                                                                       self.downforce_rear)):
            raise ParameterError("aero map: speed, drag, downforce_front and downforce_rear must be 1-D tables of "
                                 f"one length >= 2, got {[x.shape for x in (self.speed, self.drag)]}")
        if is_concrete(self.speed):
            s = np.asarray(self.speed)
            if s[0] != 0.0 or not np.all(np.diff(s) > 0):
                raise ParameterError(f"aero map: speed must start at 0 m/s and increase strictly, got {s}")

    def loads(self, speed):
        """``(drag, downforce front, downforce rear)`` (N) at ``speed`` (m/s, >= 0)."""
        return tuple(interpolate(speed, self.speed, y) for y in (self.drag, self.downforce_front, self.downforce_rear))


def aero_map_from_coefficients(cda, cla, front_share, density=1.2, max_speed=40.0, n=41) -> AeroMap:
    """Tables of ``rho C A u^2 / 2`` on ``n`` speeds up to ``max_speed`` (m/s): drag area
    ``cda`` and downforce area ``cla`` (m², >= 0), ``front_share`` of the downforce (0..1),
    air density (kg/m³). Between the table's points the law is piecewise linear (1 m/s apart by
    default: within 0.2 % of the quadratic law above 10 m/s)."""
    cda = check_range("cda", cda, low=0.0, what="m^2")
    cla = check_range("cla", cla, low=0.0, what="m^2")
    front_share = check_range("front_share", front_share, low=0.0, high=1.0)
    density = check_range("density", density, low=0.0, low_open=True, what="kg/m^3")
    speed = jnp.linspace(0.0, max_speed, n)
    q = 0.5 * density * speed**2
    return AeroMap(speed=speed, drag=q * cda, downforce_front=q * cla * front_share,
                   downforce_rear=q * cla * (1.0 - front_share))


class AeroLoads(AbstractForceElement):
    """Drag at the chassis point ``reference`` and downforce at the chassis points ``front``
    and ``rear`` (static point indices; ``body`` the chassis's body index), from ``aero``."""

    body: int = eqx.field(static=True)
    reference: int = eqx.field(static=True)
    front: int = eqx.field(static=True)
    rear: int = eqx.field(static=True)
    aero: AeroMap
    aux_names: tuple[str, ...] = eqx.field(static=True, default=())

    @classmethod
    def on(cls, system, body: str, reference: str, front: str, rear: str, aero: AeroMap) -> "AeroLoads":
        """Build from names (the chassis body and three of its points)."""
        idx = [system.point_index(p) for p in (reference, front, rear)]
        if any(system.point_body[k] != system.body_names.index(body) for k in idx):
            raise ValueError(f"aero points {reference!r}, {front!r}, {rear!r} must all be on body {body!r}")
        return cls(system.body_names.index(body), *idx, aero)

    def __call__(self, kin, aux, system):
        axes = kin.rotations[self.body]
        u = jnp.dot(axes[:, 0], kin.xd[self.reference])  # forward speed (m/s)
        drag, front, rear = self.aero.loads(jnp.abs(u))
        forces = (zero_forces(kin).forces.at[self.reference].add(-jnp.sign(u) * drag * axes[:, 0])
                  .at[self.front].add(-front * axes[:, 2]).at[self.rear].add(-rear * axes[:, 2]))
        return ElementForces(forces=forces, torques=jnp.zeros_like(forces), aux_dot=jnp.zeros((0,), forces.dtype))
