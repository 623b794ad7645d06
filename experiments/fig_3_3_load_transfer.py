"""Fig. 3.3: effect of chassis torsional stiffness on lateral load transfer distribution.

(a) χ vs λ for several µ; (b) χ vs µ for several λ; (c) |χ-χ0|/χ0 map; (d) |χλ-χλ0|/χλ0
map; plus the minimum µ for 2 % (load transfer) and 5 % (sensitivity) over λ = 0.3-0.7.
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


def compute(vehicle, n: int = 201, n_map: int = 101) -> dict:
    """Curves (a), (b) on ``n`` points and the maps (c), (d) on ``n_map`` x ``n_map``."""
    lam = np.linspace(0.0, 1.0, n)
    mu = np.geomspace(0.1, 10.0, n)
    return {
        "lam": lam,
        "mu_curves": MUS,
        "chi_vs_lam": np.asarray(design_map(vehicle, "chi", lam, MUS)),
        "mu": mu,
        "lam_curves": LAMS,
        "chi_vs_mu": np.asarray(design_map(vehicle, "chi", LAMS, mu)),
        "chi_error_map": map_report(vehicle, "chi_error", (0.0, 1.0), (0.1, 10.0), n_map, n_map),
        "chi_sensitivity_error_map": map_report(
            vehicle, "chi_sensitivity_error", (0.0, 1.0), (0.1, 10.0), n_map, n_map
        ),
    }


def figure(data: dict):
    """The four panels of Fig. 3.3 (constrained layout)."""
    fig, axes = plots.figure(2, 2, figsize=(11, 8))
    chi_lam, chi_mu = data["chi_vs_lam"], data["chi_vs_mu"]
    plot_design_curves(data["lam"], {f"µ = {m:g}": chi_lam[:, j] for j, m in enumerate(MUS)}, "λ", "χ", ax=axes[0, 0])
    plot_design_curves(data["mu"], {f"λ = {x:g}": chi_mu[i] for i, x in enumerate(LAMS)}, "µ", "χ", log_x=True,
                       ax=axes[0, 1])
    plot_map(data["chi_error_map"], "|χ-χ0|/χ0", ax=axes[1, 0], vmax=0.6)
    plot_map(data["chi_sensitivity_error_map"], "|χλ-χλ0|/χλ0", ax=axes[1, 1], vmax=2.0)
    for ax, tag in zip(axes.flat, "abcd"):
        ax.set_title(f"({tag})", fontsize=9)
    return fig


def main():
    out = output_dir("fig_3_3", __doc__)
    vehicle = load_analytic_vehicle()
    data = compute(vehicle)
    minimum = minimum_stiffness_report(vehicle)
    save(figure(data), out / "fig_3_3.png")
    write_json(data | {"minimum_stiffness": minimum}, out / "fig_3_3.json")
    for key in ("load_transfer_2pct", "sensitivity_5pct"):
        m = minimum[key]
        print(f"{key}: minimum µ = {m['mu']:.2f} (kC = {m['kC_Nm_per_deg']:.0f} Nm/deg); thesis µ ≈ {m['thesis_mu']:g}")
    print(f"max |χ-χ0|/χ0 on the map: {np.max(data['chi_error_map']['values']):.2f} (thesis: up to ~0.6)")


if __name__ == "__main__":
    main()
