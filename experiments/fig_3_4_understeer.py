"""Fig. 3.4: effect of chassis torsional stiffness on the understeer gradient via roll steer.

(a) ku vs λ for several µ; (b) ku vs µ for several λ; (c) |ku-ku0|/ku0 map; plus the
minimum µ for a 2 % understeer-gradient error over λ = 0.3-0.7.
"""

import numpy as np
from _util import output_dir, write_json

from jaxveh import plots
from jaxveh.analytic._maps import design_map
from jaxveh.analytic._reports import map_report, minimum_stiffness_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_design_curves, plot_map, save

MUS = (0.1, 0.2, 0.5, 1, 2, 5, 10)
LAMS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)


def compute(vehicle, n: int = 121, n_map: int = 101) -> dict:
    """Curves (a), (b) on ``n`` points and the map (c) on ``n_map`` x ``n_map``."""
    lam = np.linspace(0.2, 0.8, n)
    mu = np.geomspace(0.1, 10.0, n)
    return {
        "lam": lam,
        "mu_curves": MUS,
        "ku_vs_lam": np.asarray(design_map(vehicle, "ku_deg_per_g", lam, MUS)),
        "mu": mu,
        "lam_curves": LAMS,
        "ku_vs_mu": np.asarray(design_map(vehicle, "ku_deg_per_g", LAMS, mu)),
        "ku_error_map": map_report(vehicle, "ku_error", (0.2, 0.8), (0.1, 10.0), n_map, n_map),
    }


def figure(data: dict):
    """The three panels of Fig. 3.4 (constrained layout)."""
    fig, axes = plots.figure(1, 3, figsize=(15, 4.5))
    ku_lam, ku_mu = data["ku_vs_lam"], data["ku_vs_mu"]
    plot_design_curves(data["lam"], {f"µ = {m:g}": ku_lam[:, j] for j, m in enumerate(MUS)}, "λ", "ku [deg/g]",
                       ax=axes[0])
    plot_design_curves(data["mu"], {f"λ = {x:g}": ku_mu[i] for i, x in enumerate(LAMS)}, "µ", "ku [deg/g]",
                       log_x=True, ax=axes[1])
    plot_map(data["ku_error_map"], "|ku-ku0|/ku0", ax=axes[2], vmax=0.3)
    for ax, tag in zip(axes, "abc"):
        ax.set_title(f"({tag})", fontsize=9)
    return fig


def main():
    out = output_dir("fig_3_4", __doc__)
    vehicle = load_analytic_vehicle()
    data = compute(vehicle)
    minimum = minimum_stiffness_report(vehicle)["understeer_2pct"]
    save(figure(data), out / "fig_3_4.png")
    write_json(data | {"minimum_stiffness": minimum}, out / "fig_3_4.json")
    ku_lam = data["ku_vs_lam"]
    print(f"ku range on (a): {ku_lam.min():.3f}-{ku_lam.max():.3f} deg/g (thesis axis 0.6-1.0)")
    print(f"max |ku-ku0|/ku0 on the map: {np.max(data['ku_error_map']['values']):.2f} (thesis: up to ~0.3-0.5)")
    print(f"minimum µ for 2 % ku error over λ = 0.3-0.7: {minimum['mu']:.2f}; thesis µ ≈ {minimum['thesis_mu']:g}")


if __name__ == "__main__":
    main()
