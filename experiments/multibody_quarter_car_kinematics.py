"""Quarter-car suspension kinematics from the Appendix B hard points (thesis Figs. 6.11-6.12)
and projection-matrix kinematic gradients (section 7.1.3, Table 7.1 style).

Bump test: wheel-centre travel -25..+25 mm (chassis fixed), camber, toe and track change.
Steering test: rack travel -20..+20 mm at design height: steer (toe) angle, camber, track.
Gradients: columns of ``B T R`` (bump) and ``B T S b`` (unit rack rate) at the design
position, beside central finite differences of the assembled curves.

    .venv/bin/python experiments/multibody_quarter_car_kinematics.py --out results/multibody_qc
"""

import argparse
import csv
import json
from pathlib import Path

import jax
import jax.numpy as jnp
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import jaxveh  # noqa: E402,F401  (float64)
from jaxveh import (
    multibody as mb,  # noqa: E402
    vehicle,
)

DEG = 180.0 / np.pi


def sweeps(system, params):
    kin = jax.jit(jax.vmap(lambda b, r: vehicle.quarter_car_kinematics(system, params, b, r)[1]))
    bump = np.linspace(-0.025, 0.025, 51)
    rack = np.linspace(-0.02, 0.02, 41)
    b_out = kin(jnp.asarray(bump), jnp.zeros_like(jnp.asarray(bump)))
    r_out = kin(jnp.zeros_like(jnp.asarray(rack)), jnp.asarray(rack))
    return bump, _masked(b_out), rack, _masked(r_out)


def _masked(out):
    """Outputs as NumPy with points that failed to assemble (``ok`` False) set to NaN, so
    they are neither plotted nor reported as results."""
    ok = np.asarray(out["ok"])
    if not ok.all():
        print(f"warning: {int((~ok).sum())} sweep point(s) could not be assembled; left out")
    return {k: np.where(ok.reshape(ok.shape + (1,) * (np.ndim(v) - 1)), np.asarray(v), np.nan)
            for k, v in out.items() if k != "ok"}


def gradients(system, params):
    """Kinematic gradients at design from R and S b, and by finite differences."""
    q, _ = vehicle.quarter_car_kinematics(system, params, 0.0, 0.0)
    inputs = lambda t: jnp.reshape(t, (1,))  # noqa: E731  unit rack rate at rack = 0
    proj = mb.projection(system, params, q, 0.0, inputs)
    bt = mb.velocity_matrix(system, params, q)

    def outputs(qq):
        camber, toe = vehicle.wheel_angles(system, params, qq)
        return jnp.stack([camber * DEG, toe * DEG, 2.0 * qq[1] * 1e3, qq[0] * 1e3])

    bump_col = bt @ proj.R[:, 0]
    g_bump = np.asarray(jax.jvp(outputs, (q,), (bump_col,))[1]) / float(bump_col[2]) * 1e-3  # per mm
    g_rack = np.asarray(jax.jvp(outputs, (q,), (bt @ proj.Sb,))[1]) * 1e-3

    kin = jax.jit(lambda b, r: outputs(vehicle.quarter_car_kinematics(system, params, b, r)[0]))
    h = 1e-5
    fd_bump = np.asarray(kin(h, 0.0) - kin(-h, 0.0)) / (2 * h) * 1e-3
    fd_rack = np.asarray(kin(0.0, h) - kin(0.0, -h)) / (2 * h) * 1e-3
    names = ["camber [deg/mm]", "toe-in [deg/mm]", "track [mm/mm]", "wheel-centre x [mm/mm]"]
    return [
        {"quantity": n, "bump_R": float(a), "bump_fd": float(b), "rack_Sb": float(c), "rack_fd": float(d)}
        for n, a, b, c, d in zip(names, g_bump, fd_bump, g_rack, fd_rack)
    ]


def plot(bump, b_out, rack, r_out, path):
    fig, ax = plt.subplots(2, 3, figsize=(12, 7))
    bmm = bump * 1e3
    ax[0, 0].plot(bmm, b_out["camber"] * DEG)
    ax[0, 0].set(xlabel="wheel-centre travel [mm]", ylabel="camber [deg]", title="(a) camber, bump")
    ax[0, 1].plot(bmm, b_out["toe"] * DEG)
    ax[0, 1].set(xlabel="wheel-centre travel [mm]", ylabel="toe-in [deg]", title="(b) toe, bump")
    ax[0, 2].plot(bmm, (b_out["track"] - 1.26) * 1e3)
    ax[0, 2].set(
        xlabel="wheel-centre travel [mm]", ylabel="track change (2 x half track) [mm]", title="(c) track, bump"
    )
    rmm = rack * 1e3
    ax[1, 0].plot(rmm, r_out["toe"] * DEG)
    ax[1, 0].set(xlabel="rack travel [mm]", ylabel="toe-in (steer) [deg]", title="(d) steer angle, steering")
    ax[1, 1].plot(rmm, r_out["camber"] * DEG)
    ax[1, 1].set(xlabel="rack travel [mm]", ylabel="camber [deg]", title="(e) camber, steering")
    ax[1, 2].plot(rmm, (r_out["track"] - 1.26) * 1e3)
    ax[1, 2].set(xlabel="rack travel [mm]", ylabel="track change [mm]", title="(f) track, steering")
    for a in ax.flat:
        a.grid(True, alpha=0.3)
    fig.suptitle("Front-left quarter car, Appendix B hard points (cf. thesis Figs. 6.11-6.12)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results/multibody_quarter_car"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    system, params = vehicle.quarter_car()
    bump, b_out, rack, r_out = sweeps(system, params)
    with open(args.out / "bump.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["bump_mm", "camber_deg", "toe_in_deg", "track_mm", "wc_x_mm", "residual_m"])
        for k in range(bump.size):
            w.writerow([bump[k] * 1e3, b_out["camber"][k] * DEG, b_out["toe"][k] * DEG, b_out["track"][k] * 1e3,
                        b_out["wheel_centre"][k, 0] * 1e3, b_out["residual"][k]])
    with open(args.out / "steer.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["rack_mm", "camber_deg", "toe_in_deg", "track_mm", "residual_m"])
        for k in range(rack.size):
            w.writerow([rack[k] * 1e3, r_out["camber"][k] * DEG, r_out["toe"][k] * DEG, r_out["track"][k] * 1e3,
                        r_out["residual"][k]])
    grads = gradients(system, params)
    summary = {
        "max_assembly_residual_m": float(max(b_out["residual"].max(), r_out["residual"].max())),
        "gradients_at_design": grads,
        "camber_range_deg": [float(b_out["camber"].min() * DEG), float(b_out["camber"].max() * DEG)],
        "toe_range_deg_bump": [float(b_out["toe"].min() * DEG), float(b_out["toe"].max() * DEG)],
        "steer_range_deg": [float(r_out["toe"].min() * DEG), float(r_out["toe"].max() * DEG)],
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2))
    plot(bump, b_out, rack, r_out, args.out / "quarter_car_kinematics.png")
    for g in grads:
        print(f"{g['quantity']:>24}: bump R {g['bump_R']:+.6f} (FD {g['bump_fd']:+.6f}); "
              f"rack Sb {g['rack_Sb']:+.5f} (FD {g['rack_fd']:+.5f})")
    print(f"max assembly residual {summary['max_assembly_residual_m']:.2e} m; wrote {args.out}")


if __name__ == "__main__":
    main()
