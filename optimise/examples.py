"""Worked examples of chapter 3 design questions, solved with :mod:`optimise`.

(a) The smallest chassis torsional stiffness µ = kC/(kF + kR) that keeps the lateral load
    transfer error |χ - χ0|/χ0 under 2 % for every λ in [0.3, 0.7] (Fig. 3.3c).
(b) The roll stiffness distribution λ that gives a target understeer gradient (deg/g) on a
    flexible chassis (eq. 3.16, Fig. 3.4a).

Run ``python -m optimise.examples`` to print both answers.
"""

import jax
import jax.numpy as jnp
import optax

import jaxveh.analytic as analytic
from jaxveh.params import load_analytic_vehicle

from ._problem import Problem, Variable, solve, target


def worst_load_transfer_error(vehicle, lam_range=(0.3, 0.7), n_lam=201):
    """max over λ in ``lam_range`` of |χ - χ0|/χ0 at the vehicle's µ."""
    lams = jnp.linspace(lam_range[0], lam_range[1], n_lam)

    def error(lam):
        v = analytic.with_distribution(vehicle, lam=lam)
        return jnp.abs(analytic.chi(v) - analytic.chi_rigid(v)) / analytic.chi_rigid(v)

    return jnp.max(jax.vmap(error)(lams))


def minimum_chassis_stiffness(vehicle=None, max_error=0.02, lam_range=(0.3, 0.7)):
    """Example (a): minimise µ subject to the worst load-transfer error <= ``max_error``."""
    vehicle = load_analytic_vehicle() if vehicle is None else vehicle
    k_total = vehicle.kF + vehicle.kR
    problem = Problem(
        params=vehicle,
        variables=(Variable("kC", 0.05 * float(k_total), 100.0 * float(k_total), log=True),),
        objective=lambda v: v.kC / k_total,
        constraints=(lambda v: worst_load_transfer_error(v, lam_range) / max_error - 1.0,),
    )
    result = solve(problem, {"kC": 10.0 * float(k_total)}, optax.adam(0.05), inner_steps=400, outer_steps=12)
    kc = result.values["kC"]
    return {"mu": kc / float(k_total), "kC_Nm_per_deg": kc * jnp.pi / 180.0, "result": result}


def roll_distribution_for_understeer(target_deg_per_g, vehicle=None, mu=1.0):
    """Example (b): λ giving understeer gradient ``target_deg_per_g`` at chassis stiffness µ."""
    vehicle = analytic.with_distribution(load_analytic_vehicle() if vehicle is None else vehicle, mu=mu)

    def ku(v):
        return analytic.understeer_gradient(v) * analytic.RAD_PER_MS2_TO_DEG_PER_G

    problem = Problem(
        params=vehicle,
        variables=(Variable("lam", 0.05, 0.95),),
        objective=target(ku, target_deg_per_g, scale=0.01),
        apply=lambda v, values: analytic.with_distribution(v, lam=values["lam"]),
    )
    result = solve(problem, {"lam": 0.5}, optax.adam(0.05), inner_steps=600)
    return {"lam": result.values["lam"], "ku_deg_per_g": float(ku(result.params)), "result": result}


if __name__ == "__main__":
    a = minimum_chassis_stiffness()
    print(
        f"(a) minimum µ for 2 % load-transfer error over λ = 0.3-0.7: {a['mu']:.3f} "
        f"(kC = {float(a['kC_Nm_per_deg']):.0f} Nm/deg); thesis ≈ 3"
    )
    b = roll_distribution_for_understeer(0.80)
    print(f"(b) λ for ku = 0.80 deg/g at µ = 1: {b['lam']:.4f} (ku = {b['ku_deg_per_g']:.4f} deg/g)")
