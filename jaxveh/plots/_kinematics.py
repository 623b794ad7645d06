"""Chapter-7 figures of the car: the chassis's effect on the suspension kinematics (thesis Figs
7.1, 7.3, 7.4), optimal preview (Fig. 7.10) and the simplifications of Table 7.2."""

import numpy as np

from ._chapter3 import figure

#: Colours of the wheel parameters in the projection-matrix map (Fig. 7.3b's legend).
_PARAMETER_COLOURS = {"wheelbase": "tab:blue", "half_track": "tab:green", "height": "black", "toe": "tab:red",
                      "camber": "tab:orange", "caster": "tab:purple"}


def plot_kinematic_gradients(report: dict, title: str = ""):
    """Fig. 7.4: front- and rear-left camber (inclination) and toe-in change due to the
    chassis against ay, the full model beside the linear approximation of Table 7.1 (a
    :func:`jaxveh.analysis.kinematic_gradients_report`)."""
    c = report["curve"]
    ay = np.asarray(c["ay_g"])
    fig, axes = figure(2, 2, figsize=(10, 7))
    for ax, (quantity, unit), (corner, k) in (
        (axes[0, 0], ("camber", "Δγ"), ("front left", 0)), (axes[0, 1], ("toe", "Δδ toe-in"), ("front left", 0)),
        (axes[1, 0], ("camber", "Δγ"), ("rear left", 2)), (axes[1, 1], ("toe", "Δδ toe-in"), ("rear left", 2)),
    ):
        ax.plot(ay, np.asarray(c[f"{quantity}_full_deg"])[:, k], "-", label="full model")
        ax.plot(ay, np.asarray(c[f"{quantity}_linear_deg"])[:, k], "--", label="linear approx.")
        ax.set_xlabel("ay [g]")
        ax.set_ylabel(f"{unit} [deg]")
        ax.set_title(f"{corner} {quantity}", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_modal_coordinates(ay_g, modes, masses=None, modes_by_mass=None, title: str = ""):
    """Fig. 7.1: the modal coordinates' magnitudes against ay (g) and, with ``masses`` (kg),
    against the sprung mass."""
    panels = 1 if masses is None else 2
    fig, axes = figure(1, panels, figsize=(6 * panels, 4.2), squeeze=False)
    modes = np.abs(np.asarray(modes))
    for k in range(modes.shape[1]):
        axes[0, 0].plot(ay_g, 1e3 * modes[:, k], label=f"mode {k + 1}")
    axes[0, 0].set_xlabel("ay [g]")
    if masses is not None:
        by_mass = np.abs(np.asarray(modes_by_mass))
        for k in range(by_mass.shape[1]):
            axes[0, 1].plot(masses, 1e3 * by_mass[:, k], "o-", label=f"mode {k + 1}")
        axes[0, 1].set_xlabel("sprung mass [kg]")
    for ax in axes[0]:
        ax.set_ylabel("|p_i| [1e-3]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_projection_matrices(pm, title: str = ""):
    """Fig. 7.3: non-zero entries of ``TR`` (a) and ``R`` (b) of a
    :class:`jaxveh.analysis.ProjectionMatrices` with the bodies' partitions; in ``R`` each
    corner's wheel-parameter rows as triangles (up positive, down negative) coloured by
    parameter, the other entries as dots."""
    fig, axes = figure(1, 2, figsize=(12, 8.5))
    for ax, matrix, name, coloured in ((axes[0], pm.tr, "(a) TR", False), (axes[1], pm.r, "(b) R", True)):
        m = np.asarray(matrix)
        rows, cols = np.nonzero(np.abs(m) > 1e-10 * np.max(np.abs(m)))
        for i, j in zip(rows, cols):
            parameter = pm.rows[i].split(".")[-1]
            if coloured and parameter in _PARAMETER_COLOURS:
                ax.plot(j + 1, i + 1, "^" if m[i, j] > 0 else "v", color=_PARAMETER_COLOURS[parameter], ms=5)
            else:
                ax.plot(j + 1, i + 1, ".", color="black", ms=4)
        for r in pm.row_groups[1:]:
            ax.axhline(r + 0.5, color="grey", lw=0.6)
        for c in pm.column_groups[1:]:
            ax.axvline(c + 0.5, color="grey", lw=0.6)
        ax.set_xlim(0.5, m.shape[1] + 0.5)
        ax.set_ylim(m.shape[0] + 0.5, 0.5)
        ax.set_xlabel("independent coordinate s_j")
        ax.set_ylabel("relative coordinate" if coloured else "absolute coordinate")
        ax.set_title(name, fontsize=10)
    for parameter, colour in _PARAMETER_COLOURS.items():
        axes[1].plot([], [], "^", color=colour, label=parameter.replace("_", " "))
    axes[1].legend(fontsize=8, loc="lower left")
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_car_preview(report: dict, title: str = ""):
    """Fig. 7.10: preview gains of the car, rigid and flexible, and of the chapter-3 model
    (a :func:`jaxveh.analysis.preview_report`); the preview distance against the number of
    modes and, when present, against each mode's stiffness multiplier."""
    has_mu = "preview_distance_vs_mu_m" in report
    fig, axes = figure(1, 3 if has_mu else 2, figsize=(16 if has_mu else 11, 4.5))
    for label, r, style in (("14 dof flexible", report["flexible"], "-"), ("14 dof rigid", report["rigid"], "--"),
                            ("chapter 3 flexible", report["chapter_3"]["flexible"], "-."),
                            ("chapter 3 rigid", report["chapter_3"]["rigid"], ":")):
        key = "gains_deg_per_m" if "gains_deg_per_m" in r else "gains"
        axes[0].plot(r["distance_m"], r[key], style, label=label)
    axes[0].set_xlabel("preview distance [m]")
    axes[0].set_ylabel("Kp [deg/m]")
    lp = report["preview_distance_by_modes_m"]
    axes[1].plot(range(len(lp)), lp, "o-")
    axes[1].set_xlabel("number of modes")
    axes[1].set_ylabel("Lp [m]")
    if has_mu:
        for k, row in enumerate(report["preview_distance_vs_mu_m"]):
            axes[2].semilogx(report["mu"], row, "o-", label=f"mode {k + 1}")
        axes[2].set_xlabel("µ")
        axes[2].set_ylabel("Lp [m]")
    for ax in axes:
        ax.grid(True, alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    fig.suptitle(title or f"TI-optimal preview at {report['speed_kmh']:g} km/h (Fig. 7.10)", fontsize=10)
    return fig


def plot_simplifications(report: dict, channels=("yaw_rate", "ay", "roll", "fz", "modes"), title: str = ""):
    """Table 7.2 as a figure: (a) wall time and steps per variant, (b) each variant's largest
    deviation from the complete flexible model relative to its largest value, per channel
    (log scale)."""
    rows = report["variants"]
    names = list(rows)
    fig, (ax_cost, ax_dev) = figure(1, 2, figsize=(12, 4.5))
    x = np.arange(len(names))
    ax_cost.bar(x, [rows[n]["wall_s"] for n in names], color="tab:blue")
    ax_cost.set(xticks=x, ylabel="wall time [s] (after compilation)")
    ax_cost.set_xticklabels(names, rotation=30, ha="right", fontsize=8)
    steps = ax_cost.twinx()
    steps.plot(x, [rows[n]["steps"] for n in names], "o", color="tab:red")
    steps.set_ylabel("steps", color="tab:red")
    simplified = [n for n in names if n not in ("complete", "rigid")]
    width = 0.8 / max(len(channels), 1)
    for k, ch in enumerate(channels):
        dev = [max(rows[n]["relative_deviation"][ch], 1e-16) for n in simplified]
        ax_dev.bar(np.arange(len(simplified)) + (k - (len(channels) - 1) / 2) * width, dev, width, label=ch)
    ax_dev.set(yscale="log", xticks=np.arange(len(simplified)), ylabel="max |deviation| / max |complete|")
    ax_dev.set_xticklabels(simplified, rotation=30, ha="right", fontsize=8)
    ax_dev.legend(fontsize=7)
    ax_dev.grid(True, axis="y", alpha=0.3)
    m = report["manoeuvre"]
    fig.suptitle(title or f"step steer {m['speed_kmh']:.0f} km/h, {m['steering_wheel_deg']:g} deg, "
                 f"{m['duration_s']:g} s; {report['modes']} modes, rtol {report['rtol']:g}")
    return fig
