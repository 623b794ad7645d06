"""Fig. 3.6: skid-pad (R = 50 m) δd and 1/ku vs ay for the four model variants, λ = 0.54, µ = 1."""

from _util import output_dir, write_json

from jaxveh.analytic._reports import configure, skidpad_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_skidpad, save


def main():
    out = output_dir("fig_3_6", __doc__)
    vehicle = configure(load_analytic_vehicle(), lam=0.54, mu=1.0)
    report = skidpad_report(vehicle, ay_max_g=1.3, n=53)
    save(plot_skidpad(report), out / "fig_3_6.png")
    write_json(report, out / "fig_3_6.json")
    for name, data in report["variants"].items():
        sens = data["steering_sensitivity_g_per_deg"][0]
        print(f"{name:>24}: 1/ku at low ay {sens:.3f} g/deg, limit {data['ay_limit_g']:.3f} g, "
              f"δd at 1.0 g {next(d for a, d in zip(data['ay_g'], data['delta_dynamic_deg']) if a >= 0.999):.3f} deg")


if __name__ == "__main__":
    main()
