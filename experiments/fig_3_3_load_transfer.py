"""Fig. 3.3: effect of chassis torsional stiffness on lateral load transfer distribution.

(a) χ vs λ for several µ; (b) χ vs µ for several λ; (c) |χ-χ0|/χ0 map; (d) |χλ-χλ0|/χλ0
map; plus the minimum µ for 2 % (load transfer) and 5 % (sensitivity) over λ = 0.3-0.7.
"""

import matplotlib.pyplot as plt
import numpy as np
from _util import output_dir, write_json

from jaxveh.analytic._maps import design_map
from jaxveh.analytic._reports import map_report, minimum_stiffness_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_design_curves, plot_map, save

MUS = (0.1, 0.2, 0.5, 1, 2, 5, 10)
LAMS = (0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)


def main():
    out = output_dir("fig_3_3", __doc__)
    vehicle = load_analytic_vehicle()
    lam = np.linspace(0.0, 1.0, 201)
    mu = np.geomspace(0.1, 10.0, 201)
    chi_lam = np.asarray(design_map(vehicle, "chi", lam, MUS))
    chi_mu = np.asarray(design_map(vehicle, "chi", LAMS, mu))
    err = map_report(vehicle, "chi_error", (0.0, 1.0), (0.1, 10.0), 101, 101)
    sens = map_report(vehicle, "chi_sensitivity_error", (0.0, 1.0), (0.1, 10.0), 101, 101)
    minimum = minimum_stiffness_report(vehicle)
    fig, axes = plt.subplots(2, 2, figsize=(11, 8))
    plot_design_curves(lam, {f"µ = {m:g}": chi_lam[:, j] for j, m in enumerate(MUS)}, "λ", "χ", ax=axes[0, 0])
    plot_design_curves(mu, {f"λ = {x:g}": chi_mu[i] for i, x in enumerate(LAMS)}, "µ", "χ", log_x=True, ax=axes[0, 1])
    plot_map(err, "|χ-χ0|/χ0", ax=axes[1, 0], vmax=0.6)
    plot_map(sens, "|χλ-χλ0|/χλ0", ax=axes[1, 1], vmax=2.0)
    for ax, tag in zip(axes.flat, "abcd"):
        ax.set_title(f"({tag})", fontsize=9)
    save(fig, out / "fig_3_3.png")
    write_json({"lam": lam, "mu_curves": MUS, "chi_vs_lam": chi_lam, "mu": mu, "lam_curves": LAMS, "chi_vs_mu": chi_mu,
                "chi_error_map": err, "chi_sensitivity_error_map": sens, "minimum_stiffness": minimum}, out / "fig_3_3.json")
    for key in ("load_transfer_2pct", "sensitivity_5pct"):
        m = minimum[key]
        print(f"{key}: minimum µ = {m['mu']:.2f} (kC = {m['kC_Nm_per_deg']:.0f} Nm/deg); thesis µ ≈ {m['thesis_mu']:g}")
    print(f"max |χ-χ0|/χ0 on the map: {np.max(err['values']):.2f} (thesis: up to ~0.6)")


if __name__ == "__main__":
    main()
