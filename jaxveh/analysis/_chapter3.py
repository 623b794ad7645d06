"""The chapter-6 car seen through the chapter-3 load-transfer model (section 3.1).

:func:`chapter3_parameters` maps the multibody car onto the parameters of eqs. (3.2)-(3.6)
(docs/analysis.md, "The mapping"); :func:`chapter3_load_transfer` and :func:`chapter3_chi`
evaluate eq. (3.4) (rigid chassis) and eq. (3.5) (torsional chassis spring kC) with the
car's own front and rear tracks; :func:`analytic_vehicle` packs the mapping into the
:class:`~jaxveh.params.AnalyticVehicle` of :mod:`jaxveh.analytic` (one track, their mean)
so that the library's closed form eq. (3.6) can be evaluated beside it.

Units: kg, m, N m/rad, N; heights are measured from the road with the car at rest.
"""

import equinox as eqx
import jax.numpy as jnp
from jaxtyping import Array, Float

from .. import fe
from .._core import ParameterError, is_concrete
from ..params import AnalyticVehicle, hard_points_vehicle_frame, load_analytic_vehicle
from ..vehicle import car_rates, sprung_cg, static_corner_loads, wheel_centres
from ..vehicle._car import _hard_point
from ..vehicle._corner import WHEEL_CENTRE_HEIGHT


class Chapter3Parameters(eqx.Module):
    """The parameters of eqs. (3.2)-(3.6) (Figs. 3.1, 3.2), SI units, every one a float leaf.

    ``ms`` sprung mass (kg); ``muF``, ``muR`` unsprung mass of the front and rear axle (kg,
    both corners); ``as_``, ``bs`` sprung c.g. to front and rear axle (m); ``tF``, ``tR``
    front and rear track (m); ``hs`` sprung c.g. height (m; the car's sprung body has one
    c.g., so hsF = hsR = hs); ``huF``, ``huR`` unsprung c.g. heights (m, the wheel
    centres); ``zF``, ``zR`` front and rear roll centre heights (m); ``kF``, ``kR`` front
    and rear roll stiffness (N m/rad); ``kC`` chassis torsional stiffness (N m/rad)."""

    ms: Float[Array, ""]
    muF: Float[Array, ""]
    muR: Float[Array, ""]
    as_: Float[Array, ""]
    bs: Float[Array, ""]
    tF: Float[Array, ""]
    tR: Float[Array, ""]
    hs: Float[Array, ""]
    huF: Float[Array, ""]
    huR: Float[Array, ""]
    zF: Float[Array, ""]
    zR: Float[Array, ""]
    kF: Float[Array, ""]
    kR: Float[Array, ""]
    kC: Float[Array, ""]

    @property
    def m(self) -> Float[Array, ""]:
        """Total mass ms + muF + muR (kg)."""
        return self.ms + self.muF + self.muR

    @property
    def lam(self) -> Float[Array, ""]:
        """Roll stiffness distribution λ = kF / (kF + kR)."""
        return self.kF / (self.kF + self.kR)

    @property
    def mu(self) -> Float[Array, ""]:
        """Normalised chassis torsional stiffness µ = kC / (kF + kR) (section 3.1.2)."""
        return self.kC / (self.kF + self.kR)


def static_sink(car) -> Float[Array, ""]:
    """How far the car at rest sits below its design position (m): the design wheel-centre
    height less the mean loaded tyre radius (unloaded radius less static load over the
    tyre's vertical stiffness), as the steady-state solver's starting guess has it."""
    v, t = car.params.vehicle, car.params.tyres
    return WHEEL_CENTRE_HEIGHT - jnp.mean(t.unloaded_radius - static_corner_loads(v) / t.vertical_stiffness)


def roll_centre_heights(car) -> tuple[Float[Array, ""], Float[Array, ""]]:
    """Kinematic roll centre heights (m, above the road at rest) of the front and rear axle.

    Front view of the left corner at its design position: the instant centre is where the
    lower wishbone line (midpoint of pivots A, B to ball joint C) meets the upper one
    (midpoint of E, F to H); the roll centre is where the line from the contact patch
    (below the wheel centre, on the road) through the instant centre crosses the centre
    plane. Equivalently ``z = (t/2) dy/dz`` with ``dy/dz`` the contact patch's lateral
    motion per unit bump, the height at which a lateral force produces no roll of a
    symmetric independent suspension (virtual work). The Appendix B wishbone pivots are
    parallel to x, so the front view is exact."""
    hp = hard_points_vehicle_frame(car.params.vehicle)
    w = wheel_centres(car.params.vehicle)
    sink = static_sink(car)
    out = []
    for corner, k in (("front_left", 0), ("rear_left", 2)):
        pts = hp[corner]

        def yz(name, pts=pts):
            return _hard_point(pts, name)[1:]

        lower_in = 0.5 * (yz("A") + yz("B"))
        upper_in = 0.5 * (yz("E") + yz("F"))
        d1, d2 = yz("C") - lower_in, yz("H") - upper_in
        # lower_in + s d1 = upper_in + r d2
        mat = jnp.stack([d1, -d2], axis=1)
        s = jnp.linalg.solve(mat, upper_in - lower_in)[0]
        ic = lower_in + s * d1
        # contact patch on the road at rest: the car sits `sink` lower than its design
        # position, so in the design frame the road is at z = +sink
        y_w, ground = w[k, 1], sink
        z_rc = ground + (ic[1] - ground) * (0.0 - y_w) / (ic[0] - y_w)
        out.append(z_rc - ground)
    return out[0], out[1]


def frame_torsional_stiffness() -> Float[Array, ""]:
    """Torsional stiffness (N m/rad) of the shipped chassis frame by the FE torsion test
    (section 6.2.2; :func:`jaxveh.fe.torsion_test`)."""
    return fe.torsion_test(fe.load_frame()).stiffness


def chapter3_parameters(car, torsional_stiffness=None, tyres_in_series: bool = False) -> Chapter3Parameters:
    """The chapter-3 parameters of the car (docs/analysis.md, "The mapping").

    Masses and heights from Appendix B as the car places them (sprung c.g. from
    :func:`jaxveh.vehicle.sprung_cg`, unsprung masses at the wheel centres); every height
    is raised by nothing and lowered by :func:`static_sink` so that it is measured from the
    road at rest. Roll stiffnesses ``kF``, ``kR`` (N m/rad) of the suspension at the design
    position from the springs, the push-rod/rocker motion ratios and the anti-roll bars
    (:func:`jaxveh.vehicle.car_rates`, rigid tyres, as Appendix A's 205 / 175 N m/deg);
    with ``tyres_in_series`` each axle's tyres (roll stiffness ``kz t^2 / 2``) are put in
    series with it. Roll centres from :func:`roll_centre_heights`. ``torsional_stiffness``
    (N m/rad): kC; default the FE torsion test of the shipped frame
    (:func:`frame_torsional_stiffness`). Differentiable in the car's parameters."""
    v = car.params.vehicle
    rates = car_rates(car)
    sink = static_sink(car)
    cg = sprung_cg(v)
    w = wheel_centres(v)
    kF, kR = rates["front"].roll_stiffness, rates["rear"].roll_stiffness
    if tyres_in_series:
        kz = car.params.tyres.vertical_stiffness
        ktF, ktR = kz[0] * v.track_front**2 / 2.0, kz[2] * v.track_rear**2 / 2.0
        kF, kR = kF * ktF / (kF + ktF), kR * ktR / (kR + ktR)
    zF, zR = roll_centre_heights(car)
    kC = frame_torsional_stiffness() if torsional_stiffness is None else jnp.asarray(torsional_stiffness, jnp.float64)
    if is_concrete(kC) and not float(kC) > 0.0:
        raise ParameterError(f"torsional_stiffness = {float(kC)!r} is out of range: allowed > 0 (N m/rad)")
    return Chapter3Parameters(
        ms=v.sprung.mass,
        muF=2.0 * v.unsprung_front.body.mass,
        muR=2.0 * v.unsprung_rear.body.mass,
        as_=v.a - cg[0],
        bs=v.b + cg[0],
        tF=v.track_front,
        tR=v.track_rear,
        hs=cg[2] - sink,
        huF=w[0, 2] - sink,
        huR=w[2, 2] - sink,
        zF=zF,
        zR=zR,
        kF=kF,
        kR=kR,
        kC=kC,
    )


def _moments(p: Chapter3Parameters):
    l_s = p.as_ + p.bs
    msF, msR = p.ms * p.bs / l_s, p.ms * p.as_ / l_s
    return msF, msR, msF * (p.hs - p.zF), msR * (p.hs - p.zR)


def chapter3_load_transfer(p: Chapter3Parameters, ay, flexible: bool = False):
    """Per-wheel lateral load transfer ``(ΔFzF, ΔFzR)`` (N) at lateral acceleration ``ay``
    (m/s^2): eq. (3.4) for a rigid chassis, eq. (3.5) with the chassis spring ``kC`` in
    series with the opposite axle when ``flexible``; each axle's moment over its own track
    (``tF``, ``tR``, as eq. (3.5) writes them)."""
    msF, msR, mF, mR = _moments(p)
    if flexible:
        kRs, kFs = p.kR * p.kC / (p.kR + p.kC), p.kF * p.kC / (p.kF + p.kC)
        front = p.kF * mF / (p.kF + kRs) + kFs * mR / (kFs + p.kR)
        rear = kRs * mF / (p.kF + kRs) + p.kR * mR / (kFs + p.kR)
    else:
        front, rear = p.lam * (mF + mR), (1.0 - p.lam) * (mF + mR)
    front = front + p.zF * msF + p.huF * p.muF
    rear = rear + p.zR * msR + p.huR * p.muR
    return front * ay / p.tF, rear * ay / p.tR


def chapter3_chi(p: Chapter3Parameters, flexible: bool = False) -> Float[Array, ""]:
    """χ = ΔFzF / (ΔFzF + ΔFzR) of :func:`chapter3_load_transfer` (ay cancels)."""
    front, rear = chapter3_load_transfer(p, 1.0, flexible)
    return front / (front + rear)


def with_lambda(p: Chapter3Parameters, lam, k_total=None) -> Chapter3Parameters:
    """``p`` with kF = λ K and kR = (1 - λ) K, K = ``k_total`` (N m/rad; default kF + kR)."""
    k_total = p.kF + p.kR if k_total is None else k_total
    return eqx.tree_at(lambda q: (q.kF, q.kR), p, (lam * k_total, (1.0 - lam) * k_total))


def analytic_vehicle(p: Chapter3Parameters) -> AnalyticVehicle:
    """The mapping as a :class:`~jaxveh.params.AnalyticVehicle` for :mod:`jaxveh.analytic`
    (eq. (3.6): :func:`jaxveh.analytic.chi`, :func:`jaxveh.analytic.chi_rigid`): the
    load-transfer fields from ``p`` with one track ``t = (tF + tR) / 2`` and hsF = hsR = hs;
    the fields eq. (3.6) does not use (tyre, damping, inertias, steering) stay Appendix A's."""
    base = load_analytic_vehicle()
    t = 0.5 * (p.tF + p.tR)
    return eqx.tree_at(
        lambda v: (v.ms, v.muF, v.muR, v.as_, v.bs, v.t, v.hsF, v.hsR, v.huF, v.huR, v.zF, v.zR, v.kF, v.kR, v.kC),
        base, (p.ms, p.muF, p.muR, p.as_, p.bs, t, p.hs, p.hs, p.huF, p.huR, p.zF, p.zR, p.kF, p.kR, p.kC))
