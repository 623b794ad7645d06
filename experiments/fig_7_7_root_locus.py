"""Fig. 7.7: root loci of the linearised 6-mode car about straight running (section 7.3):
against the chassis coupling factor 0 -> 1 at 50 km/h (the first chassis mode's uncoupled
and coupled frequencies; thesis 38 -> about 17 Hz), against speed 5-120 km/h, and against
the first chassis mode's free-free frequency 12-120 Hz at 50 km/h; each mode tracked by
MAC and labelled by where its kinetic energy sits."""

import numpy as np
from _util import output_dir, write_json

from jaxveh.analysis import SWEEPS, root_locus_report
from jaxveh.plots import figure, plot_root_locus, save
from jaxveh.vehicle import load_car


def main():
    out = output_dir("fig_7_7", __doc__)
    car = load_car(modes=6)
    fig, axes = figure(1, 3, figsize=(17, 5.5))
    report = {}
    for ax, sweep in zip(axes, SWEEPS, strict=True):
        r = root_locus_report(car, sweep)
        report[sweep] = r
        loci = {f"{k + 1}: {m['label']}": (np.asarray(m["real_per_s"]) + 2j * np.pi * np.asarray(m["frequency_hz"]))
                [:, None] for k, m in enumerate(r["modes"]) if max(m["frequency_hz"]) > 0.0}
        unit = "" if r["unit"] == "1" else f" {r['unit']}"
        plot_root_locus(loci, ax=ax, title=f"{sweep} {r['values'][0]:g} -> {r['values'][-1]:g}{unit} "
                        "(square: start, circle: end)")
        ax.legend(fontsize=5, ncol=2)
    save(fig, out / "fig_7_7.png")
    write_json(report, out / "fig_7_7.json")
    c = report["coupling"]["first_chassis_mode_hz"]
    print(f"first chassis mode: {c['uncoupled']:.2f} Hz uncoupled -> {c['coupled']:.2f} Hz coupled ({c['label']}); "
          "thesis: 38 -> about 17 Hz")
    for m in report["coupling"]["modes"]:
        f = m["frequency_hz"]
        if f[-1] > 5.0:
            print(f"  {m['label']:>30}: {f[0]:6.2f} -> {f[-1]:6.2f} Hz (coupling 0 -> 1)")


if __name__ == "__main__":
    main()
