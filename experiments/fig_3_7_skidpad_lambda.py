"""Fig. 3.7: skid-pad δd and 1/ku vs ay for λ = 0.4 and 0.6, rigid and flexible (µ = 1)."""

from _util import output_dir, write_json

from jaxveh.analytic._reports import configure, skidpad_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_skidpad, save


def main():
    out = output_dir("fig_3_7", __doc__)
    base = load_analytic_vehicle()
    combined = {"radius_m": 50.0, "variants": {}}
    for lam in (0.4, 0.6):
        report = skidpad_report(configure(base, lam=lam, mu=1.0), variants=("rigid", "flexible"), ay_max_g=1.3, n=53)
        for name, data in report["variants"].items():
            combined["variants"][f"λ = {lam} - {'rigid' if name == 'rigid' else 'flex.'}"] = data
    save(plot_skidpad(combined, labels={}), out / "fig_3_7.png")
    write_json(combined, out / "fig_3_7.json")
    for name, data in combined["variants"].items():
        sens = data["steering_sensitivity_g_per_deg"][0]
        print(f"{name:>18}: 1/ku at low ay {sens:.3f} g/deg, limit {data['ay_limit_g']:.3f} g")


if __name__ == "__main__":
    main()
