"""Analyses of chapter 3 as plain-data reports (dicts of floats and lists), shared by the
CLI, the main job and the experiments. Inputs in user units (km/h, deg); outputs state
their units in the key names."""

import jax
import jax.numpy as jnp
import numpy as np

from ..control import preview_controller, preview_distance
from ..params import AnalyticVehicle, check_analytic_vehicle
from ._inputs import SmoothStep
from ._linear import state_space
from ._load_transfer import load_transfer_summary
from ._maps import design_map, minimum_stiffness
from ._model import PHIF, PHIR, VARIANTS, R
from ._modes import eigenvalues, frequency_response, vehicle_modes
from ._quantities import GRAVITY, normalised_torsional_stiffness, roll_stiffness_proportion, with_distribution
from ._roll_steer import understeer_summary
from ._steady import skidpad_sweep
from ._transient import simulate, step_steer_metrics

KMH = 1.0 / 3.6


def configure(vehicle: AnalyticVehicle, lam=None, mu=None) -> AnalyticVehicle:
    """Vehicle with λ and/or µ set (``None`` keeps the file's value); validates ranges."""
    if lam is not None and not 0.0 < lam < 1.0:
        raise ValueError(f"lam (roll stiffness proportion kF/(kF+kR)) must be in (0, 1), got {lam}")
    if mu is not None and not mu > 0.0:
        raise ValueError(f"mu (normalised chassis torsional stiffness kC/(kF+kR)) must be > 0, got {mu}")
    return with_distribution(check_analytic_vehicle(vehicle), lam=lam, mu=mu)


def _positive(name: str, value: float) -> None:
    if not value > 0.0:
        raise ValueError(f"{name} must be > 0, got {value}")


def lltd_report(vehicle: AnalyticVehicle) -> dict:
    """χ, χ0, ζ, ∂χ/∂λ at the vehicle's λ and µ (section 3.1)."""
    vehicle = check_analytic_vehicle(vehicle)
    return {k: float(v) for k, v in load_transfer_summary(vehicle).items()}


def understeer_report(vehicle: AnalyticVehicle) -> dict:
    """ku, ku0 (deg/g), roll and twist gradients (deg/g) (section 3.2)."""
    vehicle = check_analytic_vehicle(vehicle)
    out = {k: float(v) for k, v in understeer_summary(vehicle).items()}
    out["lam"] = float(roll_stiffness_proportion(vehicle))
    out["mu"] = float(normalised_torsional_stiffness(vehicle))
    return out


def skidpad_report(vehicle: AnalyticVehicle, variants=tuple(VARIANTS), radius=50.0, ay_max_g=1.3, n=27) -> dict:
    """δd (deg) and 1/ku (g/deg) versus ay (g) on a circle of ``radius`` m (Figs. 3.6, 3.7).

    Only converged, stable steady states are reported; ``ay_limit_g`` is the highest one.
    """
    vehicle = check_analytic_vehicle(vehicle)
    _positive("radius", radius)
    _positive("ay_max_g", ay_max_g)
    ay = np.linspace(ay_max_g / n, ay_max_g, n) * GRAVITY
    out = {"radius_m": radius, "variants": {}}
    for name in variants:
        state, sens = skidpad_sweep(vehicle, ay, VARIANTS[name], radius)
        ok = np.asarray(state.converged) & np.asarray(state.stable)
        out["variants"][name] = {
            "ay_g": (ay[ok] / GRAVITY).tolist(),
            "delta_dynamic_deg": np.degrees(np.asarray(state.delta_dynamic)[ok]).tolist(),
            "delta_deg": np.degrees(np.asarray(state.delta)[ok]).tolist(),
            "steering_sensitivity_g_per_deg": (np.asarray(sens)[ok] / GRAVITY * np.pi / 180.0).tolist(),
            "phi_front_deg": np.degrees(np.asarray(state.phi_front)[ok]).tolist(),
            "phi_rear_deg": np.degrees(np.asarray(state.phi_rear)[ok]).tolist(),
            "ay_limit_g": float(ay[ok].max() / GRAVITY) if ok.any() else None,
        }
    return out


def step_steer_report(
    vehicle: AnalyticVehicle, speed_kmh=90.0, steer_deg=1.5, rise_s=0.1, t_end=4.0, n_save=4001
) -> dict:
    """Step steer (section 3.3.3) for the rigid and flexible chassis: metrics and histories."""
    vehicle = check_analytic_vehicle(vehicle)
    _positive("speed_kmh", speed_kmh)
    _positive("rise_s", rise_s)
    _positive("t_end", t_end)
    steer = SmoothStep(np.radians(steer_deg), 0.0, rise_s)
    out = {"speed_kmh": speed_kmh, "steer_deg": steer_deg, "rise_s": rise_s}
    for name in ("rigid", "flexible"):
        traj = simulate(vehicle, steer, VARIANTS[name], speed_kmh * KMH, t_end, n_save=n_save)
        metrics = step_steer_metrics(traj, steer)
        metrics = {k: (None if v is None else float(v)) for k, v in metrics.items()}
        states = np.asarray(traj.states)
        metrics["history"] = {
            "t_s": np.asarray(traj.ts).tolist(),
            "steer_deg": np.degrees(np.asarray(traj.steer)).tolist(),
            "ay_g": (np.asarray(traj.ay) / GRAVITY).tolist(),
            "yaw_rate_deg_s": np.degrees(states[:, R]).tolist(),
            "twist_deg": np.degrees(states[:, PHIF] - states[:, PHIR]).tolist(),
            "roll_deg": np.degrees(0.5 * (states[:, PHIF] + states[:, PHIR])).tolist(),
        }
        out[name] = metrics
    return out


def eig_report(vehicle: AnalyticVehicle, speed_kmh=50.0, rigid=False) -> dict:
    """Modes of the linear model (section 3.3.4): frequency (Hz), damping ratio, label."""
    vehicle = check_analytic_vehicle(vehicle)
    _positive("speed_kmh", speed_kmh)
    modes = vehicle_modes(vehicle, speed_kmh * KMH, rigid)
    modes = [{k: float(v) if k != "label" else v for k, v in m.items()} for m in modes]
    return {"speed_kmh": speed_kmh, "rigid": rigid, "modes": modes}


def root_locus(vehicle: AnalyticVehicle, speed_kmh, mu_values=None) -> np.ndarray:
    """Eigenvalues (1/s) versus µ at one speed, or versus speed (km/h array) at the vehicle's
    µ when ``mu_values`` is None: one vmapped call. Entries with Im < 0 are NaN (the upper
    half-plane is plotted, Fig. 3.9)."""
    vehicle = check_analytic_vehicle(vehicle)
    if mu_values is not None:
        mu_values = jnp.asarray(mu_values, dtype=jnp.float64)
        eig = jax.vmap(lambda m: eigenvalues(with_distribution(vehicle, mu=m), speed_kmh * KMH))(mu_values)
    else:
        eig = jax.vmap(lambda u: eigenvalues(vehicle, u))(jnp.asarray(speed_kmh, dtype=jnp.float64) * KMH)
    eig = np.asarray(eig)
    return np.where(eig.imag >= 0, eig, np.nan)


def bode_report(vehicle: AnalyticVehicle, speed_kmh=50.0, f_min=0.1, f_max=5.0, n=200, per_road_wheel=True) -> dict:
    """Yaw-rate and ay responses to steering (section 3.3.5), rigid and flexible."""
    vehicle = check_analytic_vehicle(vehicle)
    _positive("speed_kmh", speed_kmh)
    if not 0.0 < f_min < f_max:
        raise ValueError(f"need 0 < f_min < f_max, got f_min={f_min}, f_max={f_max}")
    freqs = np.geomspace(f_min, f_max, n)
    out = {
        "speed_kmh": speed_kmh,
        "freq_hz": freqs.tolist(),
        "input": "road-wheel angle" if per_road_wheel else "steering-wheel angle",
    }
    for name, rigid in (("rigid", True), ("flexible", False)):
        fr = frequency_response(vehicle, speed_kmh * KMH, freqs, rigid, per_road_wheel)
        yaw, ay = np.asarray(fr["yaw_rate"]), np.asarray(fr["ay"])
        out[name] = {
            "yaw_rate_db_per_s": (20 * np.log10(np.abs(yaw))).tolist(),
            "yaw_rate_phase_deg": np.degrees(np.unwrap(np.angle(yaw))).tolist(),
            "ay_db_g_per_deg": (20 * np.log10(np.abs(ay))).tolist(),
            "ay_phase_deg": np.degrees(np.unwrap(np.angle(ay))).tolist(),
        }
    return out


#: The chapter-3 "minimum stiffness" questions: (quantity, threshold, λ range, thesis µ).
MINIMUM_STIFFNESS_QUESTIONS = {
    "load_transfer_2pct": ("chi_error", 0.02, (0.3, 0.7), 3.0),
    "sensitivity_5pct": ("chi_sensitivity_error", 0.05, (0.3, 0.7), 5.0),
    "understeer_2pct": ("ku_error", 0.02, (0.3, 0.7), 8.0),
}


def minimum_stiffness_report(vehicle: AnalyticVehicle) -> dict:
    """Smallest µ meeting each chapter-3 error target, beside the thesis's reading."""
    out = {}
    for key, (quantity, threshold, lam_range, thesis_mu) in MINIMUM_STIFFNESS_QUESTIONS.items():
        result = minimum_stiffness(vehicle, quantity, threshold, lam_range)
        out[key] = {
            "quantity": quantity, "threshold": threshold, "lam_range": list(lam_range), "thesis_mu": thesis_mu, **result
        }
    return out


def map_report(
    vehicle: AnalyticVehicle, quantity: str, lam_range=(0.0, 1.0), mu_range=(0.1, 10.0), n_lam=101, n_mu=101
) -> dict:
    """``quantity`` on a λ (linear) x µ (log) grid, rows λ, columns µ (Figs. 3.3c-d, 3.4c)."""
    if not (0.0 <= lam_range[0] < lam_range[1] <= 1.0):
        raise ValueError(f"lam range must satisfy 0 <= min < max <= 1, got {lam_range}")
    if not (0.0 < mu_range[0] < mu_range[1]):
        raise ValueError(f"mu range must satisfy 0 < min < max, got {mu_range}")
    lam = np.linspace(*lam_range, n_lam)
    mu = np.geomspace(*mu_range, n_mu)
    values = np.asarray(design_map(vehicle, quantity, lam, mu))
    return {"quantity": quantity, "lam": lam.tolist(), "mu": mu.tolist(), "values": values.tolist()}


def preview_report(
    vehicle: AnalyticVehicle,
    speed_kmh=100.0,
    rigid=False,
    dt=0.01,
    n_preview=200,
    q_weight=1000.0,
    r_weight=1.0,
    cutoff_hz=2.0,
) -> dict:
    """Time-invariant optimal preview control (section 3.3.6): preview gains Kp (deg of
    steering-wheel angle per m of road lateral position) at distances l = i u dt (m) and
    the preview distance Lp (eq. 3.46, 98 % of the area under |Kp|)."""
    vehicle = check_analytic_vehicle(vehicle)
    _positive("speed_kmh", speed_kmh)
    _positive("dt", dt)
    if n_preview < 2:
        raise ValueError(f"n_preview must be >= 2, got {n_preview}")
    speed = speed_kmh * KMH
    a_c, b_c = state_space(vehicle, speed, rigid=rigid)
    c_y = jnp.zeros(a_c.shape[0]).at[0].set(1.0)
    gains = preview_controller(
        a_c, b_c, c_y, dt=dt, n_preview=n_preview, q_weight=q_weight, r_weight=r_weight, cutoff_hz=cutoff_hz
    )
    kp = np.degrees(np.asarray(gains.preview))
    return {
        "speed_kmh": speed_kmh,
        "rigid": rigid,
        "mu": float(normalised_torsional_stiffness(vehicle)),
        "preview_distance_m": float(preview_distance(gains.preview, speed, dt)),
        "distance_m": (np.arange(kp.size) * speed * dt).tolist(),
        "gains": kp.tolist(),
        "riccati_residual": float(gains.residual),
        "closed_loop_spectral_radius": float(gains.spectral_radius),
    }
