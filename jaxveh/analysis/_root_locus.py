"""Root loci of the linearised fast car (thesis section 7.3, Fig. 7.7): the eigenvalues of
:func:`jaxveh.analysis.linearise`'s state matrix along a sweep of the chassis coupling
factor (0 -> 1), the speed, or the first chassis mode's free-free frequency (through its
stiffness multiplier, f proportional to sqrt(µ)), each mode followed along the sweep.

Tracking: the eigenvectors of neighbouring points are matched by the assignment that
maximises their MAC (``|v_a^H v_b|^2 / (|v_a|^2 |v_b|^2)``, SciPy's linear sum
assignment); wherever the worst match of an interval falls below ``min_mac`` the interval
is halved (up to ``max_refine`` times), so modes that cross or veer keep their identity.

Labels (at the sweep's last point): the coordinate group holding most of the mode's
kinetic energy, estimated from the velocity part of its eigenvector with the car's
lumped masses and inertias (the chassis's rigid motions: longitudinal, yaw/sideslip,
heave, roll, pitch; each corner pair's parallel and opposite wheel travel: front/rear
parallel and opposite bump, the wheel-hop modes; the wheels' spins; each chassis mode:
modal mass 1), with the chassis mode holding the most appended when it holds 20 % or more
("front opposite bump / chassis mode 2"); modes with no velocity (tyre relaxation, the
speed controller) are "lag". Lumped masses ignore the coupling terms of the mass matrix:
the labels name where a mode mostly lives, not an exact decomposition.
"""

import equinox as eqx
import jax.numpy as jnp
import numpy as np
from scipy.optimize import linear_sum_assignment

from .._core import ParameterError
from ._linear import DEFAULT_OUTPUTS, CarLinearisation, linearise

SWEEPS = ("coupling", "speed", "first-mode")
#: Default sweep values and their unit.
DEFAULT_VALUES = {
    "coupling": (np.linspace(0.0, 1.0, 11), "1"),
    "speed": (np.linspace(5.0, 120.0, 24), "km/h"),
    "first-mode": (np.geomspace(12.0, 120.0, 21), "Hz"),
}


class RootLocus(eqx.Module):
    """A root locus: the ``sweep``, its ``values`` (unit ``unit``; refinement points
    included), ``eigenvalues[point, mode]`` (1/s, complex, each column one tracked mode with
    a non-negative imaginary part), ``labels`` (one per column), ``min_mac`` (per column,
    the worst MAC between neighbouring points) and the ``speed`` (m/s; the swept one for
    the speed sweep)."""

    sweep: str = eqx.field(static=True)
    unit: str = eqx.field(static=True)
    values: np.ndarray
    eigenvalues: np.ndarray
    labels: tuple = eqx.field(static=True)
    min_mac: np.ndarray
    speed: float

    @property
    def frequency_hz(self) -> np.ndarray:
        """Damped frequencies ``Im(lambda) / 2 pi`` (Hz)."""
        return self.eigenvalues.imag / (2.0 * np.pi)

    @property
    def damping_ratio(self) -> np.ndarray:
        """``-Re(lambda) / |lambda|``."""
        return -self.eigenvalues.real / np.abs(self.eigenvalues)


def _car_at(car, sweep, value):
    """``(car, speed)`` at one sweep value (the speed in m/s is None unless swept)."""
    if sweep == "coupling":
        return eqx.tree_at(lambda c: c.params.coupling, car, jnp.asarray(value, jnp.float64)), None
    if sweep == "speed":
        return car, value / 3.6
    f1 = float(car.params.chassis.frequencies_hz[0]) / float(np.sqrt(car.params.chassis.stiffness_scale[0]))
    scale = car.params.chassis.stiffness_scale.at[0].set((value / f1) ** 2)
    return eqx.tree_at(lambda c: c.params.chassis.stiffness_scale, car, scale), None


def _eigen(lin: CarLinearisation):
    lam, vec = np.linalg.eig(np.asarray(lin.a))
    return lam, vec / np.linalg.norm(vec, axis=0)


def _mac(a, b):
    return np.abs(a.conj().T @ b) ** 2


def _match(prev_vec, vec):
    """Permutation of ``vec``'s columns following ``prev_vec``'s, and each match's MAC."""
    mac = _mac(prev_vec, vec)
    rows, cols = linear_sum_assignment(-mac)
    order = cols[np.argsort(rows)]
    return order, mac[np.arange(mac.shape[0]), order]


def _check(car, sweep, values):
    if sweep not in SWEEPS:
        raise ParameterError(f"sweep = {sweep!r}: allowed {', '.join(map(repr, SWEEPS))}")
    if car.n_modes == 0 and sweep in ("coupling", "first-mode"):
        raise ParameterError(f"sweep = {sweep!r} needs a flexible chassis: the car has no chassis modes")
    values = np.asarray(DEFAULT_VALUES[sweep][0] if values is None else values, float)
    if values.ndim != 1 or values.size < 2 or np.any(np.diff(values) <= 0.0):
        raise ParameterError("values must be at least 2 increasing numbers")
    low, high = {"coupling": (0.0, 1.0), "speed": (1.0, 360.0), "first-mode": (1.0, 1000.0)}[sweep]
    if values[0] < low or values[-1] > high:
        raise ParameterError(f"values of the {sweep} sweep are out of range: allowed [{low:g}, {high:g}] "
                             f"({DEFAULT_VALUES[sweep][1]})")
    return values


def root_locus(car, sweep: str, values=None, speed: float = 50.0 / 3.6, min_mac: float = 0.9,
               max_refine: int = 5) -> RootLocus:
    """The root locus of ``car`` (fast form) along ``sweep`` ("coupling", "speed" in km/h,
    "first-mode" in Hz; ``values`` default :data:`DEFAULT_VALUES`), linearised about
    straight running at ``speed`` (m/s; unless swept). Every point reuses one compiled
    linearisation (the swept quantity is a traced leaf), so a locus costs a fraction of a
    second per point after the first."""
    values = _check(car, sweep, values)
    if not 0.0 < min_mac < 1.0:
        raise ParameterError(f"min_mac = {min_mac!r} is out of range: allowed (0, 1)")
    outputs = DEFAULT_OUTPUTS  # the program every default linearisation uses

    def point(value):
        c, s = _car_at(car, sweep, value)
        return _eigen(linearise(c, speed if s is None else s, outputs=outputs))

    points = [(v, *point(v)) for v in values]
    lam0, vec0 = points[0][1], points[0][2]
    tracked_values, tracked_lam, tracked_vec, macs = [values[0]], [lam0], [vec0], []
    for v, lam, vec in points[1:]:
        stack = [(v, lam, vec, 0)]
        while stack:  # depth-first: halve an interval whose worst match is poor
            v1, lam1, vec1, depth = stack.pop()
            order, mac = _match(tracked_vec[-1], vec1)
            if mac.min() < min_mac and depth < max_refine:
                mid = 0.5 * (tracked_values[-1] + v1)
                stack += [(v1, lam1, vec1, depth + 1), (mid, *point(mid), depth + 1)]
                continue
            tracked_values.append(v1)
            tracked_lam.append(lam1[order])
            tracked_vec.append(vec1[:, order])
            macs.append(mac)
    lam = np.stack(tracked_lam)
    keep = (lam.imag.mean(axis=0) >= -1e-12) & (np.abs(lam).min(axis=0) >= 2.0 * np.pi * 1e-3)
    labels = tuple(mode_label(car, tracked_vec[-1][:, j]) for j in np.flatnonzero(keep))
    order = np.argsort(np.abs(lam[-1, keep]))
    return RootLocus(sweep=sweep, unit=DEFAULT_VALUES[sweep][1], values=np.asarray(tracked_values),
                     eigenvalues=lam[:, keep][:, order], labels=tuple(labels[k] for k in order),
                     min_mac=np.stack(macs).min(axis=0)[keep][order],
                     speed=float(speed if sweep != "speed" else np.nan))


def kinetic_energy_shares(car, vector) -> dict:
    """Shares of a mode's kinetic energy (lumped masses, see the module docs) by group;
    ``vector`` an eigenvector of the fast car's state ``[q, u, aux]``."""
    n_q = 14 + car.n_modes
    v = vector[n_q : 2 * n_q]
    p = car.params.vehicle
    m = float(np.asarray(p.sprung.mass))
    inertia = np.diag(np.asarray(p.sprung.inertia))
    unsprung = [float(np.asarray(p.unsprung_front.body.mass)), float(np.asarray(p.unsprung_rear.body.mass))]
    spin_inertia = np.repeat([float(np.asarray(p.unsprung_front.wheel_spin_inertia)),
                              float(np.asarray(p.unsprung_rear.wheel_spin_inertia))], 2)
    n = car.n_modes
    travel, spin = v[6 + n : 10 + n], v[10 + n : 14 + n]
    e = {
        "longitudinal": m * abs(v[0]) ** 2,
        "yaw/sideslip": m * abs(v[1]) ** 2 + inertia[2] * abs(v[5]) ** 2,
        "heave": m * abs(v[2]) ** 2,
        "roll": inertia[0] * abs(v[3]) ** 2,
        "pitch": inertia[1] * abs(v[4]) ** 2,
        "front parallel bump": unsprung[0] * abs(travel[0] + travel[1]) ** 2 / 2,
        "front opposite bump": unsprung[0] * abs(travel[0] - travel[1]) ** 2 / 2,
        "rear parallel bump": unsprung[1] * abs(travel[2] + travel[3]) ** 2 / 2,
        "rear opposite bump": unsprung[1] * abs(travel[2] - travel[3]) ** 2 / 2,
        "wheel spin": float(np.sum(spin_inertia * np.abs(spin) ** 2)),
    }
    e |= {f"chassis mode {k + 1}": abs(v[6 + k]) ** 2 for k in range(n)}
    total = sum(e.values())
    return {k: x / total for k, x in e.items()} if total > 0.0 else {}


def mode_label(car, vector) -> str:
    """The label of one mode of the fast car (its eigenvector; see the module docs)."""
    shares = kinetic_energy_shares(car, vector)
    n_q = 14 + car.n_modes
    velocity = np.linalg.norm(vector[n_q : 2 * n_q])
    if not shares or velocity < 1e-3 * np.linalg.norm(vector):
        return "lag"
    top = max(shares, key=shares.get)
    chassis = {k: x for k, x in shares.items() if k.startswith("chassis")}
    if chassis and not top.startswith("chassis"):
        k = max(chassis, key=chassis.get)
        if chassis[k] >= 0.2:  # a suspension or wheel mode the chassis takes a good part in
            return f"{top} / {k}"
    return top


def first_chassis_mode(locus: RootLocus, car) -> int:
    """Column of ``locus`` that is the first chassis mode: at the coupling sweep's start
    (coupling 0) the mode whose frequency is nearest the free-free first mode's."""
    if locus.sweep != "coupling" or locus.values[0] != 0.0:
        raise ParameterError("the first chassis mode is identified on a coupling sweep starting at 0")
    f1 = float(car.params.chassis.frequencies_hz[0])
    return int(np.argmin(np.abs(np.abs(locus.eigenvalues[0]) / (2.0 * np.pi) - f1)))


def root_locus_report(car, sweep: str, values=None, speed: float = 50.0 / 3.6) -> dict:
    """:func:`root_locus` ready for JSON: ``sweep``, ``unit``, ``values``, ``speed_kmh``
    (None when swept), ``modes`` (per tracked mode: ``label``, ``frequency_hz`` (damped),
    ``damping_ratio``, ``real_per_s``, ``min_neighbour_mac``) and, on a coupling sweep from 0
    to 1, ``first_chassis_mode_hz`` (``uncoupled``, ``coupled``, the coupled mode's
    ``label``)."""
    locus = root_locus(car, sweep, values, speed)
    report = {
        "sweep": sweep,
        "unit": locus.unit,
        "values": locus.values.tolist(),
        "speed_kmh": None if sweep == "speed" else float(speed) * 3.6,
        "modes": [{"label": label, "frequency_hz": locus.frequency_hz[:, j].tolist(),
                   "damping_ratio": locus.damping_ratio[:, j].tolist(),
                   "real_per_s": locus.eigenvalues[:, j].real.tolist(),
                   "min_neighbour_mac": float(locus.min_mac[j])} for j, label in enumerate(locus.labels)],
    }
    if sweep == "coupling" and locus.values[0] == 0.0 and locus.values[-1] == 1.0:
        j = first_chassis_mode(locus, car)
        report["first_chassis_mode_hz"] = {"uncoupled": float(locus.frequency_hz[0, j]),
                                           "coupled": float(locus.frequency_hz[-1, j]),
                                           "label": locus.labels[j]}
    return report
