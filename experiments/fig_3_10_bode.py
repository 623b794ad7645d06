"""Fig. 3.10: yaw-rate and ay frequency response to steering at 50 km/h, rigid vs flexible (µ = 1)."""

from _util import output_dir, write_json

from jaxveh.analytic._reports import bode_report
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_bode, save


def main():
    out = output_dir("fig_3_10", __doc__)
    report = bode_report(load_analytic_vehicle(), speed_kmh=50.0, f_min=0.1, f_max=5.0, n=300)
    save(plot_bode(report), out / "fig_3_10.png")
    write_json(report, out / "fig_3_10.json")
    for name in ("rigid", "flexible"):
        r = report[name]
        print(f"{name:>8}: yaw rate {r['yaw_rate_db_per_s'][0]:.1f} -> {r['yaw_rate_db_per_s'][-1]:.1f} dB, "
              f"ay {r['ay_db_g_per_deg'][0]:.1f} -> {r['ay_db_g_per_deg'][-1]:.1f} dB (0.1 -> 5 Hz)")


if __name__ == "__main__":
    main()
