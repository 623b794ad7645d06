"""Fig. B.1: tyre force characteristics of the FSAE 20.0x7.0-13 tyre (Appendix B).

Panels (a) Fx-kappa, (b) Fy-alpha, (c) Mz-alpha at Fz = 250/500/750/1000 N and zero camber,
(d) combined Fx-Fy at 750 N, for the shipped ``fsae_20x7_13.tir`` (or any ``--tir``).
Writes the PNGs, the curves (CSV), the peak table (CSV + JSON) beside the values read from
Fig. B.1 (the thesis prints no table: the figure's axes and the issue's reading of it).

    .venv/bin/python experiments/fig_b1_tyre.py --out results/fig_b1_tyre
"""

import argparse
import csv
import json
from pathlib import Path

import numpy as np

import jaxveh  # noqa: F401  (float64)
from jaxveh.tyre import load_fsae_tyre, peak_table, plot_fig_b1, pure_slip_curves, read_tir

#: What Fig. B.1 shows at Fz = 1000 N (read from the plotted curves and axis limits).
FIG_B1 = {
    "fy_peak_1000_N": "about 1500 (axis limit 1500)",
    "fx_peak_1000_N": "about 1300-1500 (axis limit 1500)",
    "mz_max_N_m": "20-35 (axis -20 to 40)",
    "kappa_range": "-0.3 to 0.3, peaks inside",
    "alpha_range_deg": "-15 to 15, peaks inside",
}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("results/fig_b1_tyre"))
    ap.add_argument("--tir", type=Path, default=None, help=".tir file (default: shipped FSAE tyre)")
    args = ap.parse_args()
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    tyre = load_fsae_tyre() if args.tir is None else read_tir(args.tir)

    plot_fig_b1(tyre, out, title="Fig. B.1 - FSAE 20.0x7.0-13 (jaxveh MF 5.2)")
    c = pure_slip_curves(tyre, n=301)
    with (out / "curves.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        loads = [f"{fz:.0f}" for fz in np.asarray(c.loads)]
        columns = ["kappa", *[f"fx_{f}N" for f in loads], "alpha_deg"]
        w.writerow(columns + [f"fy_{f}N" for f in loads] + [f"mz_{f}N" for f in loads])
        for j in range(c.kappa.shape[0]):
            w.writerow([float(c.kappa[j]), *np.asarray(c.fx[:, j]).tolist(), float(np.rad2deg(c.alpha[j])),
                        *np.asarray(c.fy[:, j]).tolist(), *np.asarray(c.mz[:, j]).tolist()])
    rows = peak_table(tyre)
    with (out / "peaks.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    (out / "peaks.json").write_text(json.dumps({"jaxveh": rows, "fig_b1": FIG_B1}, indent=2))
    print(f"{'Fz':>6} {'Fx max':>8} {'kappa':>6} {'|Fy| max':>9} {'alpha':>6} {'Mz max':>7} {'alpha':>6} "
          f"{'Mz min':>7} {'alpha':>6}")
    for r in rows:
        print(f"{r['fz']:6.0f} {r['fx_peak']:8.0f} {r['kappa_peak']:6.3f} {r['fy_peak']:9.0f} "
              f"{r['alpha_peak_deg']:6.2f} "
              f"{r['mz_max']:7.1f} {r['alpha_mz_max_deg']:6.2f} {r['mz_min']:7.1f} {r['alpha_mz_min_deg']:6.2f}")
    print("Fig. B.1:", FIG_B1)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
