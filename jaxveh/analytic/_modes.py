"""Eigen-analysis (root locus, Fig. 3.9) and frequency response (Fig. 3.10) of the linear model."""

import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Complex

from ..params import AnalyticVehicle, Range, check
from ._checks import check_speed
from ._linear import dynamic_subsystem, state_space
from ._quantities import GRAVITY

MODE_LABELS = ("yaw/sideslip", "roll", "torsion")


def _velocity_indices(rigid: bool) -> tuple[int, int]:
    """Indices of v and r in the dynamic subsystem [phiF, phiR, v, r, pF, pR] / [phi, v, r, p]."""
    return (1, 2) if rigid else (2, 3)


def eigenvalues(vehicle: AnalyticVehicle, speed, rigid: bool = False) -> Complex[Array, " n"]:
    """Eigenvalues (1/s) of the dynamic subsystem (Y and ψ removed), eq. (3.37)."""
    a, _ = dynamic_subsystem(*state_space(vehicle, speed, rigid))
    return jnp.linalg.eigvals(a)


def _energy_shares(vehicle: AnalyticVehicle, vec: np.ndarray, rigid: bool) -> np.ndarray:
    """Kinetic-energy shares of yaw/sideslip, in-phase roll and torsion in an eigenvector."""
    m, jz = float(vehicle.m), float(vehicle.Jz)
    jf, jr = float(vehicle.JrF), float(vehicle.JrR)
    i_v, i_r = _velocity_indices(rigid)
    v, r = vec[i_v], vec[i_r]
    if rigid:
        p = vec[3]
        return np.array([m * abs(v) ** 2 + jz * abs(r) ** 2, (jf + jr) * abs(p) ** 2, 0.0])
    pf, pr = vec[4], vec[5]
    in_phase, twist = 0.5 * (pf + pr), 0.5 * (pf - pr)
    return np.array([m * abs(v) ** 2 + jz * abs(r) ** 2, (jf + jr) * abs(in_phase) ** 2, (jf + jr) * abs(twist) ** 2])


def vehicle_modes(vehicle: AnalyticVehicle, speed, rigid: bool = False) -> list[dict]:
    """Modes of motion: natural frequency (Hz), damping ratio, eigenvalue and label.

    One entry per complex-conjugate pair (the one with positive imaginary part) and per
    real eigenvalue. The label is the motion (yaw/sideslip, roll, torsion) holding most of
    the mode's kinetic energy; torsion is the out-of-phase roll of the chassis halves.
    Sorted by frequency. Not differentiable (NumPy); use :func:`eigenvalues` for gradients.
    """
    a, _ = dynamic_subsystem(*state_space(vehicle, speed, rigid))
    vals, vecs = np.linalg.eig(np.asarray(a))
    modes = []
    for lam, vec in zip(vals, vecs.T):
        if lam.imag < -1e-9 * max(1.0, abs(lam)):
            continue
        wn = abs(lam)
        shares = _energy_shares(vehicle, vec, rigid)
        modes.append(
            {
                "freq_hz": wn / (2 * np.pi),
                "damped_freq_hz": abs(lam.imag) / (2 * np.pi),
                "damping_ratio": -lam.real / wn if wn > 0 else 1.0,
                "real": lam.real,
                "imag": lam.imag,
                "label": MODE_LABELS[int(np.argmax(shares))],
            }
        )
    return sorted(modes, key=lambda mode: mode["freq_hz"])


def frequency_response(vehicle: AnalyticVehicle, speed, freqs_hz, rigid: bool = False, per_road_wheel: bool = True):
    """Yaw-rate and lateral-acceleration frequency responses to steering (Fig. 3.10).

    Returns complex arrays ``yaw_rate`` (1/s, i.e. rad/s per rad) and ``ay`` (g per deg),
    per road-wheel angle (``per_road_wheel=True``, the scale of Fig. 3.10) or per
    steering-wheel angle. ``speed`` u > 0 (m/s) and ``freqs_hz`` >= 0 (Hz) are checked.
    """
    speed = check_speed(speed)
    freqs_hz = check("freqs_hz", freqs_hz, Range(0.0, what="frequency, Hz"))
    a, b = dynamic_subsystem(*state_space(vehicle, speed, rigid))
    if per_road_wheel:
        b = b * vehicle.k_stw
    n = a.shape[0]
    i_v, i_r = _velocity_indices(rigid)
    c_yaw = jnp.zeros(n).at[i_r].set(1.0)
    c_ay = a[i_v] + speed * c_yaw  # ay = dv/dt + u r
    d_ay = b[i_v, 0]
    s = 2j * jnp.pi * freqs_hz.astype(jnp.complex128)
    a_c, b_c = a.astype(jnp.complex128), b[:, 0].astype(jnp.complex128)
    c_yaw_c, c_ay_c = c_yaw.astype(jnp.complex128), c_ay.astype(jnp.complex128)

    def response(si):
        x = jnp.linalg.solve(si * jnp.eye(n, dtype=jnp.complex128) - a_c, b_c)
        return c_yaw_c @ x, c_ay_c @ x + d_ay.astype(jnp.complex128)

    yaw, ay = jax.vmap(response)(s)
    return {"yaw_rate": yaw, "ay": ay / GRAVITY * (jnp.pi / 180.0)}
