"""JSON-ready reports of the load-transfer analyses (plain floats and lists, units in the
key names) for the CLI (``jaxveh vehicle lltd``) and the experiments."""

import time

import numpy as np

from .. import analytic
from .._core import GRAVITY
from ._chapter3 import analytic_vehicle, chapter3_chi, chapter3_load_transfer, chapter3_parameters
from ._load_transfer import AY_GRID_G, LOW_AY_PAIR_G, SKID_PAD_RADIUS, load_transfer


def lltd_report(car, radius: float = SKID_PAD_RADIUS, torsional_stiffness=None) -> dict:
    """χ at low ay (the incremental share between :data:`LOW_AY_PAIR_G`) of the car on a
    circle of ``radius`` m beside the chapter-3 values for the car's own parameters
    (:func:`chapter3_parameters`; kC the FE frame's unless ``torsional_stiffness`` N m/rad
    is given), and the curves against ay (:data:`AY_GRID_G`): the car's per-wheel front
    and rear load transfer (N) and the secant χ, and eq. (3.4)'s (rigid) and eq. (3.5)'s
    (flexible) front and rear load transfer. The car's column is "rigid" or "flexible"
    after its mode count; both chapter-3 variants are given."""
    start = time.perf_counter()
    lt = load_transfer(car, AY_GRID_G, radius)
    wall = time.perf_counter() - start
    p = chapter3_parameters(car, torsional_stiffness)
    v = analytic_vehicle(p)
    ay = np.asarray(AY_GRID_G) * GRAVITY
    rigid = [np.asarray(x) for x in chapter3_load_transfer(p, ay)]
    flex = [np.asarray(x) for x in chapter3_load_transfer(p, ay, flexible=True)]
    ok = np.asarray(lt.ok)
    return {
        "chassis": "rigid" if car.n_modes == 0 else f"flexible, {car.n_modes} modes",
        "modes": car.n_modes,
        "radius_m": float(radius),
        "low_ay_g": list(LOW_AY_PAIR_G),
        "chi_low_ay": float(lt.chi_low_ay),
        "chi_eq_3_4_rigid": float(chapter3_chi(p)),
        "chi_eq_3_5_flexible": float(chapter3_chi(p, flexible=True)),
        "chi_eq_3_6_rigid_mean_track": float(analytic.chi_rigid(v)),
        "chi_eq_3_6_flexible_mean_track": float(analytic.chi(v)),
        "lam": float(p.lam),
        "mu": float(p.mu),
        "chapter3_parameters": {k: float(getattr(p, k)) for k in p.__dataclass_fields__},
        "all_converged": bool(ok.all()),
        "wall_time_s": wall,
        "curve": {
            "ay_g": list(AY_GRID_G),
            "front_n": np.asarray(lt.front).tolist(),
            "rear_n": np.asarray(lt.rear).tolist(),
            "chi": np.asarray(lt.chi).tolist(),
            "ok": ok.tolist(),
            "eq_3_4_front_n": rigid[0].tolist(),
            "eq_3_4_rear_n": rigid[1].tolist(),
            "eq_3_5_front_n": flex[0].tolist(),
            "eq_3_5_rear_n": flex[1].tolist(),
        },
    }
