"""Design maps over (λ, µ) by ``jax.vmap`` (Figs. 3.3, 3.4) and minimum chassis stiffness.

λ = kF/(kF + kR) is the roll stiffness proportion and µ = kC/(kF + kR) the normalised
chassis torsional stiffness; the total roll stiffness kF + kR is held at the vehicle's value.
"""

from collections.abc import Callable

import equinox as eqx
import jax
import jax.numpy as jnp
import numpy as np
from jaxtyping import Array, Float

from ..params import AnalyticVehicle, ParameterError, Range, check, check_analytic_vehicle, check_int, check_static
from ._checks import LAM, MU
from ._load_transfer import chi, chi_rigid, chi_sensitivity
from ._quantities import with_distribution
from ._roll_steer import RAD_PER_MS2_TO_DEG_PER_G, understeer_gradient, understeer_gradient_rigid


def _rel_error(value, reference):
    return jnp.abs(value - reference) / jnp.abs(reference)


def _chi(v):
    return chi(v)


def _chi_error(v):
    return _rel_error(chi(v), chi_rigid(v))


def _chi_sensitivity_error(v):
    return _rel_error(chi_sensitivity(v), chi_sensitivity(v, rigid=True))


def _ku(v):
    return understeer_gradient(v) * RAD_PER_MS2_TO_DEG_PER_G


def _ku_error(v):
    return _rel_error(understeer_gradient(v), understeer_gradient_rigid(v))


#: Map quantities by name: each a function of a vehicle returning a scalar.
MAP_QUANTITIES: dict[str, Callable[[AnalyticVehicle], Float[Array, ""]]] = {
    "chi": _chi,
    "chi_error": _chi_error,
    "chi_sensitivity_error": _chi_sensitivity_error,
    "ku_deg_per_g": _ku,
    "ku_error": _ku_error,
}


def get_quantity(name: str) -> Callable[[AnalyticVehicle], Float[Array, ""]]:
    """Map quantity by name; ``ValueError`` lists the allowed names."""
    if name not in MAP_QUANTITIES:
        raise ValueError(f"quantity must be one of {sorted(MAP_QUANTITIES)}, got {name!r}")
    return MAP_QUANTITIES[name]


def design_map(vehicle: AnalyticVehicle, quantity: str, lam_values, mu_values) -> Float[Array, "n_lam n_mu"]:
    """``quantity`` on the grid λ x µ (rows λ, columns µ), one nested-vmap call.

    λ values must lie in [0, 1] and µ values be > 0 (``ParameterError``).
    """
    fn = get_quantity(quantity)
    vehicle = check_analytic_vehicle(vehicle)

    def at(lam, mu):
        return fn(with_distribution(vehicle, lam=lam, mu=mu))

    lam_values = check("lam_values", lam_values, LAM)
    mu_values = check("mu_values", mu_values, MU)
    return jax.vmap(lambda lam: jax.vmap(lambda mu: at(lam, mu))(mu_values))(lam_values)


@eqx.filter_jit
def _worst_error(vehicle: AnalyticVehicle, quantity: str, lam_values, mu) -> Float[Array, ""]:
    fn = get_quantity(quantity)
    return jnp.max(jax.vmap(lambda lam: fn(with_distribution(vehicle, lam=lam, mu=mu)))(lam_values))


def _interval(name: str, bounds, rng: Range) -> tuple[float, float]:
    """``(low, high)`` inside ``rng`` with low < high (``ParameterError`` otherwise)."""
    low, high = (check_static(name, x, rng) for x in bounds)
    if not low < high:
        raise ParameterError(f"{name} must satisfy low < high; got ({low:g}, {high:g})")
    return low, high


def minimum_stiffness(
    vehicle: AnalyticVehicle,
    quantity: str,
    threshold: float,
    lam_range=(0.3, 0.7),
    n_lam: int = 401,
    mu_bounds=(1e-2, 1e3),
    rtol: float = 1e-6,
) -> dict[str, float]:
    """Smallest µ for which the worst relative error over λ in ``lam_range`` is <= ``threshold``.

    ``quantity`` is one of the ``*_error`` map quantities. The worst error over a fine λ
    grid is decreasing in µ (checked on a log grid first; ``ValueError`` otherwise), so the
    answer is found by bisection in log µ to relative tolerance ``rtol``. Returns µ, the
    corresponding kC (Nm/deg) and the worst error there.
    """
    if not quantity.endswith("error"):
        errors = [q for q in MAP_QUANTITIES if q.endswith("error")]
        raise ValueError(f"quantity must be an error map ({errors}), got {quantity!r}")
    if not 0.0 < threshold < 1.0:
        raise ValueError(f"threshold must be a relative error in (0, 1), got {threshold}")
    vehicle = check_analytic_vehicle(vehicle)
    lam_range = _interval("lam_range", lam_range, LAM)
    mu_bounds = _interval("mu_bounds", mu_bounds, MU)
    n_lam = check_int("n_lam", n_lam, 2)
    check_static("rtol", rtol, Range(0.0, low_open=True, what="relative tolerance on µ"))
    lam_values = jnp.linspace(lam_range[0], lam_range[1], n_lam)

    def worst(mu):
        return float(_worst_error(vehicle, quantity, lam_values, jnp.asarray(mu, dtype=jnp.float64)))

    probe = np.geomspace(*mu_bounds, 60)
    errors = np.array([worst(m) for m in probe])
    if np.any(np.diff(errors) > 1e-12):
        raise ValueError(f"worst-case {quantity} is not decreasing in µ over {mu_bounds}; bisection is not valid")
    if errors[-1] > threshold:
        raise ValueError(f"{quantity} stays above {threshold} up to µ = {mu_bounds[1]}")
    if errors[0] <= threshold:
        return {"mu": float(mu_bounds[0]), "worst_error": float(errors[0])}
    i = int(np.nonzero(errors <= threshold)[0][0])
    lo, hi = np.log(probe[i - 1]), np.log(probe[i])
    while hi - lo > rtol:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if worst(np.exp(mid)) > threshold else (lo, mid)
    mu = float(np.exp(hi))
    k_total = float(vehicle.kF + vehicle.kR)
    return {"mu": mu, "kC_Nm_per_deg": mu * k_total * np.pi / 180.0, "worst_error": worst(mu)}
