"""Fig. 3.11: time-invariant optimal preview gains and preview distance versus µ.

Thesis section 3.3.6 (eqs. 3.38-3.46): the linear 4-DOF model of eq. (3.37) (Appendix A
data) discretised by ZOH at dt = 0.01 s, a 4th-order Butterworth road filter at 2 Hz, a
shift register of q = 200 preview points, Q = 1000, R = 1.

Panels: (a), (b) preview gains Kp (deg of steering-wheel angle per metre of road lateral
position) versus preview distance l = i u dt at 40 and 100 km/h, rigid chassis versus
flexible chassis at µ = kC/(kF + kR) = 1 (the Appendix A value used throughout chapter 3);
(c), (d) preview distance Lp (eq. 3.46, 98 % of the area under |Kp|) versus µ = 0.1-100
at 40 and 100 km/h, one ``jax.vmap`` over µ per speed. Also reported: the smallest µ for
which Lp at 100 km/h stays within 2 % of its asymptotic (rigid-chassis) value — the
thesis reads µ ≈ 8 — and dLp/dµ at µ = 1 by ``jax.grad``.

    .venv/bin/python experiments/fig_3_11_preview.py --out results/fig_3_11_preview
"""

import argparse
import csv
import json
import time
from pathlib import Path

import jax
import jax.numpy as jnp
import matplotlib.pyplot as plt
import numpy as np

import jaxveh  # noqa: F401  (float64)
from jaxveh import plots
from jaxveh.analytic import state_space, with_distribution
from jaxveh.control import preview_controller, preview_distance
from jaxveh.params import load_analytic_vehicle

DT = 0.01  # s, thesis section 3.3.6
N_PREVIEW = 200  # preview points q
SPEEDS_KMH = (40.0, 100.0)
MU_GAINS = 1.0  # µ of the flexible curves in panels (a), (b)
MU_RANGE = (0.1, 100.0)
THRESHOLD = 0.02  # "within 2 % of its asymptotic value"
THESIS = {
    "lp_40_m": [9.5, 11.0],
    "lp_100_m": [33.0, 43.0],
    "lp_100_low_mu_increase_pct": 30.0,
    "min_mu_2pct_100kmh": 8.0,
}
RAD_TO_DEG = 180.0 / np.pi


def lateral_position_row(n_states: int) -> jnp.ndarray:
    """Cd = [1 0 ... 0]: Y is the first state of :func:`jaxveh.analytic.state_space`."""
    return jnp.zeros(n_states).at[0].set(1.0)


def gains(vehicle, speed, rigid):
    """Preview controller of the vehicle at ``speed`` m/s (rigid or flexible chassis)."""
    a_c, b_c = state_space(vehicle, speed, rigid=rigid)
    return preview_controller(a_c, b_c, lateral_position_row(a_c.shape[0]), dt=DT, n_preview=N_PREVIEW)


def lp_of_mu(vehicle, speed, mu):
    """(Lp by eq. 3.46, Lp interpolated between samples) in m, flexible chassis at µ."""
    kp = gains(with_distribution(vehicle, mu=mu), speed, rigid=False).preview
    return jnp.stack(
        [preview_distance(kp, speed, DT), preview_distance(kp, speed, DT, interpolate=True)]
    )


def minimum_mu(lp_fn, asymptote, mu_grid, lp_grid, threshold=THRESHOLD, iterations=20):
    """Smallest µ with (Lp(µ') - Lp_inf)/Lp_inf <= threshold for every grid µ' >= µ.

    The grid fixes the bracket (last grid point above the threshold, next one below); the
    continuous (interpolated) Lp is then bisected in log µ inside it.
    """
    excess = lp_grid / asymptote - 1.0
    above = np.nonzero(excess > threshold)[0]
    if above.size == 0:
        return float(mu_grid[0]), "below threshold over the whole range"
    if above[-1] == len(mu_grid) - 1:
        return float("nan"), "above threshold over the whole range"
    lo, hi = np.log(mu_grid[above[-1]]), np.log(mu_grid[above[-1] + 1])
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        if float(lp_fn(np.exp(mid))) / asymptote - 1.0 > threshold:
            lo = mid
        else:
            hi = mid
    return float(np.exp(hi)), "bisection"


def run(out: Path, n_mu: int, vehicle_path: str | None) -> dict:
    """Compute, write the JSON, CSV files and the PNG into ``out``; return the report."""
    out.mkdir(parents=True, exist_ok=True)
    report, panels = compute(load_analytic_vehicle(vehicle_path), n_mu, out)
    (out / "fig_3_11_preview.json").write_text(json.dumps(report, indent=2))
    fig = figure(*panels)
    fig.savefig(out / "fig_3_11_preview.png", dpi=120)
    plt.close(fig)
    return report


def compute(vehicle, n_mu: int, out: Path | None = None, extras: bool = True) -> tuple[dict, tuple]:
    """The report and the panel data ``(panels_gains, panels_lp, mu_grid)`` of :func:`figure`;
    CSV files of the curves go into ``out`` when given. ``extras=False`` skips the minimum-µ
    bisection and dLp/dµ (NaN in the report), which the figure does not need."""
    mu_grid = np.geomspace(*MU_RANGE, n_mu)
    report = {"thesis": THESIS, "settings": {"dt_s": DT, "n_preview": N_PREVIEW, "q_weight": 1000.0,
                                             "r_weight": 1.0, "filter": "Butterworth 4th order, 2 Hz",
                                             "mu_gains": MU_GAINS}}
    panels_gains, panels_lp, diagnostics = {}, {}, []
    for kmh in SPEEDS_KMH:
        speed = jnp.asarray(kmh / 3.6)
        distance = np.arange(N_PREVIEW + 1) * float(speed) * DT
        curves = {}
        for label, rigid, v in (("rigid", True, vehicle), ("flex", False, with_distribution(vehicle, mu=MU_GAINS))):
            g = gains(v, speed, rigid)
            diagnostics.append((float(g.residual), float(g.spectral_radius)))
            curves[label] = np.asarray(g.preview) * RAD_TO_DEG
            curves[f"lp_{label}_m"] = float(preview_distance(g.preview, speed, DT))
            curves[f"lp_{label}_interp_m"] = float(preview_distance(g.preview, speed, DT, interpolate=True))
            curves[f"filter_gain_max_{label}"] = float(np.abs(np.asarray(g.filter)).max())
        panels_gains[kmh] = (distance, curves)

        t0 = time.perf_counter()
        sweep = jax.jit(jax.vmap(lambda mu, s=speed: lp_of_mu(vehicle, s, mu)))
        lp = np.asarray(sweep(jnp.asarray(mu_grid)))
        sweep_s = time.perf_counter() - t0
        asymptote, asymptote_interp = curves["lp_rigid_m"], curves["lp_rigid_interp_m"]
        single = jax.jit(lambda mu, s=speed: lp_of_mu(vehicle, s, mu)[1])
        mu_min, how = minimum_mu(single, asymptote_interp, mu_grid, lp[:, 1]) if extras else (float("nan"), "skipped")
        excess_step = lp[:, 0] / asymptote - 1.0
        bad = np.nonzero(excess_step > THRESHOLD)[0]
        mu_min_step = float(mu_grid[bad[-1] + 1]) if bad.size else float(mu_grid[0])
        dlp_dmu = float(jax.grad(single)(jnp.asarray(MU_GAINS))) if extras else float("nan")
        panels_lp[kmh] = (lp, asymptote, asymptote_interp)
        report[f"{kmh:g}_kmh"] = {
            "lp_rigid_m": asymptote,
            "lp_rigid_interp_m": asymptote_interp,
            "lp_flex_mu1_m": curves["lp_flex_m"],
            "lp_mu_min_range_m": float(lp[0, 0]),
            "lp_increase_at_mu_0.1_pct": 100.0 * (float(lp[0, 1]) / asymptote_interp - 1.0),
            "kp_min_deg_per_m": {"rigid": float(curves["rigid"].min()), "flex": float(curves["flex"].min())},
            "kp_min_at_m": {"rigid": float(distance[np.argmin(curves["rigid"])]),
                            "flex": float(distance[np.argmin(curves["flex"])])},
            "filter_gain_max": {"rigid": curves["filter_gain_max_rigid"], "flex": curves["filter_gain_max_flex"]},
            "min_mu_within_2pct_interp": mu_min,
            "min_mu_within_2pct_interp_method": how,
            "min_mu_within_2pct_grid_eq_3_46": mu_min_step,
            "dlp_dmu_at_mu1_m": dlp_dmu,
            "sweep_wall_s": sweep_s,
        }
        if out is not None:
            _write_csv(out / f"lp_vs_mu_{kmh:g}kmh.csv", ["mu", "lp_m", "lp_interp_m"],
                       zip(mu_grid, lp[:, 0], lp[:, 1]))
            _write_csv(out / f"gains_{kmh:g}kmh.csv", ["l_m", "kp_rigid_deg_per_m", "kp_flex_deg_per_m"],
                       zip(distance, curves["rigid"], curves["flex"]))
    report["max_riccati_residual"] = max(d[0] for d in diagnostics)
    report["max_closed_loop_spectral_radius"] = max(d[1] for d in diagnostics)
    report["mu_grid"] = mu_grid.tolist()
    return report, (panels_gains, panels_lp, mu_grid)


def _write_csv(path: Path, header, rows) -> None:
    with path.open("w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        writer.writerows([[f"{x:.10g}" for x in row] for row in rows])


def figure(panels_gains, panels_lp, mu_grid):
    """Fig. 3.11 (a)-(d) (constrained layout)."""
    fig, axes = plots.figure(2, 2, figsize=(10, 7.5))
    for col, kmh in enumerate(SPEEDS_KMH):
        distance, curves = panels_gains[kmh]
        ax = axes[0, col]
        ax.plot(distance, curves["rigid"], "k-", label="rigid")
        ax.plot(distance, curves["flex"], "k--", label=f"flex. (µ = {MU_GAINS:g})")
        ax.set_xlim(0.0, 20.0 if kmh < 50 else 50.0)
        ax.set_xlabel("l [m]")
        ax.set_ylabel("Kp [deg/m]")
        ax.legend()
        ax.grid(True, alpha=0.3)
        ax.set_title(f"({'ab'[col]}) {kmh:g} km/h")
        lp, _, asymptote_interp = panels_lp[kmh]
        ax = axes[1, col]
        ax.semilogx(mu_grid, lp[:, 0], "k.", label="Lp, eq. (3.46)")
        ax.semilogx(mu_grid, lp[:, 1], "k-", label="Lp, interpolated")
        ax.axhline(asymptote_interp, color="0.5", ls=":", label="rigid chassis")
        ax.set_xlabel("µ")
        ax.set_ylabel("Lp [m]")
        ax.legend()
        ax.grid(True, which="both", alpha=0.3)
        ax.set_title(f"({'cd'[col]}) {kmh:g} km/h")
    return fig


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("results/fig_3_11_preview"))
    parser.add_argument("--n-mu", type=int, default=31, help="µ grid points (log-spaced, 0.1-100)")
    parser.add_argument("--vehicle", default=None, help="Appendix-A-style vehicle TOML (default: shipped)")
    args = parser.parse_args()
    report = run(args.out, args.n_mu, args.vehicle)
    summary = {k: v for k, v in report.items() if k.endswith("kmh") or k.startswith("max") or k == "thesis"}
    print(json.dumps(summary, indent=2))


if __name__ == "__main__":
    main()
