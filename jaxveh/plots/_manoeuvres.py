"""Time histories of the car's manoeuvres (Fig. 7.6 style): runs overlaid by label."""

import numpy as np

from ._chapter3 import figure

#: Panels: channel, axis label, which element of a per-corner channel (None: scalar).
_PANELS = (
    ("steering_wheel_angle", "δsw [deg]", None),
    ("ay", "ay [g]", None),
    ("yaw_rate", "r [deg/s]", None),
    ("roll", "roll [deg]", None),
    ("sideslip", "β [deg]", None),
    ("modes", "modal coordinates [-]", "all"),
)
#: Panels of straight-line acceleration and braking (per corner: FL, FR, RL, RR).
STRAIGHT_LINE_PANELS = (
    ("speed", "speed [m/s]", None),
    ("ax", "ax [g]", None),
    ("pitch", "pitch [deg] (nose down +)", None),
    ("fz", "tyre load Fz [N]", "corners"),
    ("wheel_torque", "wheel torque [N m] (brake -)", "corners"),
    ("modes", "modal coordinates [-]", "all"),
)
#: Panels of braking in a turn.
BRAKE_IN_TURN_PANELS = (
    ("yaw_rate", "yaw rate [deg/s]", None),
    ("ay", "ay [g]", None),
    ("ax", "ax [g]", None),
    ("sideslip", "sideslip [deg]", None),
    ("fz", "tyre load Fz [N]", "corners"),
    ("wheel_torque", "wheel torque [N m] (brake -)", "corners"),
)
_CORNERS = ("FL", "FR", "RL", "RR")


def plot_manoeuvre(runs: dict, title: str = "", t_max: float | None = None, panels=_PANELS):
    """Six panels of one or more runs (``{label: {"t_s": ..., channel: ...}}``, channels as
    from :func:`jaxveh.manoeuvre.simulate`): by default steering, ay, yaw rate, roll,
    sideslip and the modal coordinates; ``panels``: ``(channel, axis label, which)`` with
    ``which`` None, "corners" or "all" (the modal coordinates), e.g.
    :data:`STRAIGHT_LINE_PANELS`."""
    fig, axes = figure(3, 2, figsize=(10, 9))
    styles = ("-", "--", "-.", ":")
    for ax, (key, ylabel, which) in zip(axes.flat, panels):
        for (label, run), style in zip(runs.items(), styles):
            y = np.asarray(run[key])
            if which == "all":
                for k in range(y.shape[1] if y.ndim == 2 else 0):
                    ax.plot(run["t_s"], y[:, k], style, label=f"{label} mode {k + 1}")
            elif which == "corners":
                for k, corner in enumerate(_CORNERS):
                    ax.plot(run["t_s"], y[:, k], style, label=f"{label} {corner}")
            else:
                ax.plot(run["t_s"], y, style, label=label)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylabel)
        if t_max is not None:
            ax.set_xlim(0, t_max)
        ax.grid(True, alpha=0.3)
        if ax.lines and which == "all":
            # one entry per mode: room above the curves for a legend in up to three rows
            low, high = ax.get_ylim()
            ax.set_ylim(low, high + 0.6 * (high - low))
            ax.legend(fontsize=7, ncols=2, loc="upper center")
        elif ax.lines:
            ax.legend(fontsize=7)
        else:
            ax.text(0.5, 0.5, "rigid chassis: no modal coordinates", ha="center", va="center", transform=ax.transAxes)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


#: Skid-pad panels (Fig. 7.5): curve key, axis label.
_SKID_PAD_PANELS = (
    ("delta_dynamic_deg", "δd [deg]"),
    ("understeer_gradient_deg_per_g", "ku [deg/g]"),
    ("sideslip_deg", "β [deg]"),
    ("roll_deg", "ϕ [deg]"),
)


def plot_skid_pad(curves: dict, title: str = ""):
    """Dynamic steer angle, understeer gradient (Fig. 7.5b plots its inverse, which diverges
    where a car passes through neutral steer), sideslip and roll against ay (Fig. 7.5) of
    one or more skid-pad curves (``{label: curve}``, the ``curve`` of
    :func:`jaxveh.manoeuvre.skid_pad_report`)."""
    fig, axes = figure(2, 2, figsize=(10, 7))
    styles = ("-", "--", "-.", ":")
    for ax, (key, ylabel) in zip(axes.flat, _SKID_PAD_PANELS):
        for (label, curve), style in zip(curves.items(), styles):
            ax.plot(curve["ay_g"], curve[key], style, marker=".", label=label)
        ax.set_xlabel("ay [g]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_frequency_response(responses: dict, title: str = ""):
    """Yaw-rate and lateral-acceleration frequency responses per steering-wheel angle,
    magnitude (dB) and phase against frequency on a log axis (Fig. 6.15), of one or more
    swept-sine runs (``{label: response}``, as :func:`jaxveh.manoeuvre.frequency_response`
    returns)."""
    fig, axes = figure(2, 2, figsize=(10, 7), sharex=True)
    styles = ("-", "--", "-.", ":")
    for col, (name, unit) in enumerate((("yaw_rate", "(deg/s)/deg"), ("ay", "g/deg"))):
        for (label, r), style in zip(responses.items(), styles):
            axes[0, col].semilogx(r["frequency_hz"], r[f"{name}_gain_db"], style, label=label)
            axes[1, col].semilogx(r["frequency_hz"], r[f"{name}_phase_deg"], style, label=label)
        axes[0, col].set_ylabel(f"{'r' if name == 'yaw_rate' else 'ay'} magnitude [dB {unit}]")
        axes[1, col].set_ylabel("phase [deg]")
        axes[1, col].set_xlabel("f [Hz]")
        for ax in axes[:, col]:
            ax.grid(True, which="both", alpha=0.3)
            ax.legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig


def plot_four_post(responses: dict, title: str = ""):
    """Four-post frequency responses per front-left post displacement (Fig. 7.9 (c), (d)):
    the front-left contact-patch load (N/mm) and the chassis twist (deg/mm) of one or more
    runs (``{label: response}``, the ``frequency_response`` of
    :func:`jaxveh.manoeuvre.four_post_metrics`), and each modal coordinate (1/mm) of the
    first run, on log-log axes."""
    fig, axes = figure(1, 3, figsize=(14, 4.2))
    styles = ("-", "--", "-.", ":")
    for (label, r), style in zip(responses.items(), styles):
        f = np.asarray(r["frequency_hz"])
        axes[0].loglog(f, r["fz_front_left_gain"], style, label=label)
        if "twist_gain" in r:  # flexible chassis only
            axes[1].loglog(f, r["twist_gain"], style, label=label)
    first = next(iter(responses.values()))
    modes = sorted(k for k in first if k.startswith("mode_") and k.endswith("_gain"))
    for name in modes:
        axes[2].loglog(first["frequency_hz"], first[name], label=name.removesuffix("_gain").replace("_", " "))
    for ax, label in zip(axes, ("front-left load [N/mm]", "chassis twist [deg/mm]", "modal coordinates [1/mm]"),
                         strict=True):
        ax.set_xlabel("f [Hz]")
        ax.set_ylabel(label)
        ax.grid(True, which="both", alpha=0.3)
        if ax.get_legend_handles_labels()[0]:
            ax.legend(fontsize=8)
    if title:
        fig.suptitle(title, fontsize=10)
    return fig
