"""Fig. 3.9: root locus (a) versus µ = 0.1...10 at 50 km/h, (b) versus speed 5...120 km/h (µ = 1)."""

import numpy as np
from _util import output_dir, write_json

from jaxveh import plots
from jaxveh.analytic import with_distribution
from jaxveh.analytic._reports import eig_report, root_locus
from jaxveh.params import load_analytic_vehicle
from jaxveh.plots import plot_root_locus, save


def _labels(vehicle, speed_kmh):
    """(label, eigenvalue) of each mode, for annotating the loci."""
    return [(m["label"], complex(m["real"], m["imag"])) for m in eig_report(vehicle, speed_kmh)["modes"]]


def compute(vehicle, n: int = 80) -> dict:
    """Loci versus µ = 0.1...10 at 50 km/h and versus speed 5...120 km/h at µ = 1, ``n`` points."""
    mus = np.geomspace(0.1, 10.0, n)
    speeds_kmh = np.linspace(5.0, 120.0, n)
    return {"mu": mus, "by_mu": root_locus(vehicle, 50.0, mus), "speed_kmh": speeds_kmh,
            "by_speed": root_locus(vehicle, speeds_kmh)}


def figure(vehicle, data: dict):
    """Fig. 3.9 (a), (b) with the modes labelled at the end of each locus (constrained layout)."""
    fig, axes = plots.figure(1, 2, figsize=(12, 5))
    plot_root_locus({"eigenvalues": data["by_mu"]}, ax=axes[0], title="(a) µ = 0.1 (□) ... 10 (○), 50 km/h",
                    mode_labels=_labels(with_distribution(vehicle, mu=float(data["mu"][-1])), 50.0))
    plot_root_locus({"eigenvalues": data["by_speed"]}, ax=axes[1], title="(b) 5 (□) ... 120 km/h (○), µ = 1",
                    mode_labels=_labels(vehicle, float(data["speed_kmh"][-1])))
    return fig


def main():
    out = output_dir("fig_3_9", __doc__)
    vehicle = load_analytic_vehicle()
    data = compute(vehicle)
    save(figure(vehicle, data), out / "fig_3_9.png")
    by_mu, by_speed = data["by_mu"], data["by_speed"]
    modes = {m: eig_report(with_distribution(vehicle, mu=m), 50.0)["modes"] for m in (0.1, 1.0, 10.0)}
    write_json({"mu": data["mu"], "eig_by_mu_real": by_mu.real, "eig_by_mu_imag": by_mu.imag,
                "speed_kmh": data["speed_kmh"], "eig_by_speed_real": by_speed.real,
                "eig_by_speed_imag": by_speed.imag, "modes_50kmh": modes}, out / "fig_3_9.json")
    for m, ms in modes.items():
        print(f"µ = {m:g}: " + ", ".join(f"{x['label']} {x['freq_hz']:.2f} Hz ζ={x['damping_ratio']:.2f}" for x in ms))


if __name__ == "__main__":
    main()
