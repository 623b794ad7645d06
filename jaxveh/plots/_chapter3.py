"""Figures of chapter 3 drawn from the plain-data reports of :mod:`jaxveh.analytic`.

Every figure made here uses matplotlib's constrained layout (``layout="constrained"``), so
titles, axis labels, tick labels and colour bars never overlap; callers that pass their own
``ax`` should create the figure the same way (:func:`figure`).
"""

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

VARIANT_LABELS = {
    "rigid": "rigid",
    "flexible_load_transfer": "flex. - l.l.t. only",
    "flexible_roll_steer": "flex. - r.s. only",
    "flexible": "flex.",
}


def figure(nrows: int = 1, ncols: int = 1, **kwargs):
    """``plt.subplots`` with constrained layout: the way every figure of jaxveh is made."""
    return plt.subplots(nrows, ncols, layout="constrained", **kwargs)


def save(fig, path) -> Path:
    """Save ``fig`` as PNG at ``path`` (parents created) and close it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130, bbox_inches="tight")
    plt.close(fig)
    return path


def plot_design_curves(x, curves: dict, xlabel: str, ylabel: str, log_x: bool = False, ax=None):
    """Family of curves ``{label: y}`` over ``x`` (Figs. 3.3a-b, 3.4a-b)."""
    fig = None
    if ax is None:
        fig, ax = figure(figsize=(5, 4))
    for label, y in curves.items():
        ax.plot(x, y, label=label)
    if log_x:
        ax.set_xscale("log")
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return fig if fig is not None else ax.figure


def plot_map(report: dict, label: str, ax=None, vmax: float | None = None):
    """Filled contour of a λ x µ map report (Figs. 3.3c-d, 3.4c), µ on a log axis.

    ``vmax`` clips the colour scale (the thesis uses 0.6, 2 and 0.3 for Figs. 3.3c, 3.3d, 3.4c).
    """
    fig = None
    if ax is None:
        fig, ax = figure(figsize=(5, 4))
    mu, lam, values = np.asarray(report["mu"]), np.asarray(report["lam"]), np.asarray(report["values"])
    vmax = float(values.max()) if vmax is None else vmax
    cs = ax.contourf(mu, lam, np.minimum(values, vmax), levels=np.linspace(0.0, vmax, 21), cmap="viridis")
    ax.contour(mu, lam, values, levels=[0.02, 0.05], colors="w", linewidths=0.8)
    ax.set_xscale("log")
    ax.set_xlabel("µ")
    ax.set_ylabel("λ")
    (fig if fig is not None else ax.figure).colorbar(cs, ax=ax, label=label)
    return fig if fig is not None else ax.figure


def plot_skidpad(report: dict, labels: dict | None = None):
    """δd and 1/ku versus ay (Figs. 3.6, 3.7) from one or more skid-pad reports' variants."""
    labels = labels or VARIANT_LABELS
    fig, (ax1, ax2) = figure(1, 2, figsize=(10, 4))
    for name, data in report["variants"].items():
        ax1.plot(data["ay_g"], data["delta_dynamic_deg"], label=labels.get(name, name))
        ax2.plot(data["ay_g"], data["steering_sensitivity_g_per_deg"], label=labels.get(name, name))
    ax1.set_xlabel("ay [g]")
    ax1.set_ylabel("δd [deg]")
    ax2.set_xlabel("ay [g]")
    ax2.set_ylabel("1/ku [g/deg]")
    # 1/ku diverges where δd peaks (neutral steer); keep the thesis's scale, data stay in the JSON.
    ax2.set_ylim(-0.5, 1.6)
    for ax, tag in ((ax1, "(a)"), (ax2, "(b)")):
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(tag, fontsize=9)
    return fig


def plot_step_steer(report: dict):
    """Steer, ay, yaw rate and chassis twist histories, rigid vs flexible (Fig. 3.8)."""
    fig, axes = figure(2, 2, figsize=(10, 7))
    keys = (("steer_deg", "δ [deg]"), ("ay_g", "ay [g]"), ("yaw_rate_deg_s", "r [deg/s]"), ("twist_deg", "ϕC [deg]"))
    for ax, (key, ylabel), tag in zip(axes.flat, keys, "abcd"):
        for name, style in (("rigid", "-"), ("flexible", "--")):
            h = report[name]["history"]
            ax.plot(h["t_s"], h[key], style, label="rigid" if name == "rigid" else "flex.")
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylabel)
        ax.set_xlim(0, min(2.0, report["rigid"]["history"]["t_s"][-1]))
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
        ax.set_title(f"({tag})", fontsize=9)
    return fig


def plot_root_locus(loci: dict, ax=None, title: str = "", mode_labels=()):
    """Eigenvalue loci ``{label: complex array (n_param, n_modes)}`` with ζ and ωn grid (Fig. 3.9).

    ``mode_labels``: (text, complex eigenvalue) pairs written beside the loci.
    """
    fig = None
    if ax is None:
        fig, ax = figure(figsize=(5.5, 4.5))
    for k, (label, eig) in enumerate(loci.items()):
        eig = np.asarray(eig)
        ax.plot(eig.real, eig.imag, ".", ms=3, color=f"C{k}")
        ax.plot([], [], ".", color=f"C{k}", label=label)
        ax.plot(eig[0].real, eig[0].imag, "s", mfc="none", color="k", ms=5)
        ax.plot(eig[-1].real, eig[-1].imag, "o", mfc="none", color="k", ms=5)
    xmin, xmax = ax.get_xlim()
    ymax = ax.get_ylim()[1]
    radius = max(abs(xmin), ymax)
    for zeta in (0.05, 0.1, 0.15, 0.2, 0.3, 0.5, 0.8):
        ang = np.arccos(zeta)
        ax.plot([0, -radius * np.cos(ang)], [0, radius * np.sin(ang)], ":", color="grey", lw=0.6)
    for wn in np.arange(20, radius + 1, 20):
        th = np.linspace(np.pi / 2, np.pi, 100)
        ax.plot(wn * np.cos(th), wn * np.sin(th), ":", color="grey", lw=0.6)
    for text, point in mode_labels:
        ax.annotate(text, (point.real, point.imag), textcoords="offset points", xytext=(6, 4), fontsize=8)
    ax.set_xlim(xmin, max(xmax, 0.0))
    ax.set_ylim(0, ymax)
    ax.set_xlabel("Re [1/s]")
    ax.set_ylabel("Im [rad/s]")
    ax.set_title(title, fontsize=9)
    ax.legend(fontsize=7)
    return fig if fig is not None else ax.figure


def plot_bode(report: dict):
    """Magnitude and phase of yaw rate and ay per steer angle, rigid vs flexible (Fig. 3.10)."""
    fig, axes = figure(2, 2, figsize=(10, 7), sharex=True)
    f = report["freq_hz"]
    cols = (
        ("yaw_rate_db_per_s", "yaw_rate_phase_deg", "dB mag [1/s]"),
        ("ay_db_g_per_deg", "ay_phase_deg", "dB mag [g/deg]"),
    )
    for j, (mag, phase, ylabel) in enumerate(cols):
        for name, style in (("rigid", "-"), ("flexible", "--")):
            label = "rigid" if name == "rigid" else "flex."
            axes[0, j].semilogx(f, report[name][mag], style, label=label)
            axes[1, j].semilogx(f, report[name][phase], style, label=label)
        axes[0, j].set_ylabel(ylabel)
        axes[1, j].set_ylabel("phase [deg]")
        axes[1, j].set_xlabel("f [Hz]")
        for ax in axes[:, j]:
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
    axes[0, 0].set_title("(a) yaw rate / steer", fontsize=9)
    axes[0, 1].set_title("(b) lateral acceleration / steer", fontsize=9)
    return fig


def plot_preview(reports: dict, ax=None):
    """Preview gains Kp (deg/m) versus distance ahead l (m) for labelled reports (Fig. 3.11a-b)."""
    fig = None
    if ax is None:
        fig, ax = figure(figsize=(5, 4))
    for label, report in reports.items():
        ax.plot(report["distance_m"], report["gains"], label=f"{label} (Lp = {report['preview_distance_m']:.1f} m)")
    ax.set_xlabel("l [m]")
    ax.set_ylabel("Kp [deg/m]")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    return fig if fig is not None else ax.figure
