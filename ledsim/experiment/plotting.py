"""Every figure of the package, in one place (matplotlib, Agg backend, imported lazily).

Each function takes plain arrays or the runners' results, writes one PNG atomically and
returns its path.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ledsim.files.outputs import atomic_write_bytes


def _subplots(nrows: int, ncols: int, figsize, **kw):
    """``plt.subplots`` without pyplot: a bare ``matplotlib.figure.Figure`` saves to PNG
    through Agg on its own (no backend to select, nothing to close), and skipping
    pyplot's import saves a short run about half a second."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    return fig, fig.subplots(nrows, ncols, **kw)


def _save(fig, path: Path) -> Path:
    path = Path(path)
    atomic_write_bytes(path, lambda tmp: fig.savefig(tmp, dpi=110, format="png"))
    return path


def _shade(ax, t, flags, label: str) -> None:
    """Grey bands where ``flags`` is true (blocked line of sight, lost link)."""
    if np.any(flags):
        ax.fill_between(t, 0, 1, where=flags, transform=ax.get_xaxis_transform(), color="k",
                        alpha=0.12, label=label)


def plot_estimates(traces: dict, Te: float, title: str, path: Path) -> Path:
    """True vs estimated state of every estimator (paper Figs. 5-8 style)."""
    ref = traces.get("kkl") or next(iter(traces.values()))
    t = np.arange(len(ref.x)) * Te
    fig, axes = _subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, (ax, label) in enumerate(zip(axes, ["phi [rad]", "phidot [rad/s]"], strict=True)):
        ax.plot(t, ref.x[:, i], "k", lw=2, label="true")
        for name, tr in traces.items():
            ax.plot(t, tr.xhat[:, i], lw=1, alpha=0.9 if name == "kkl" else 0.6, label=name)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend(ncol=3, fontsize=8)
    axes[0].set_title(f"true vs estimated state — {title}")
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    return _save(fig, path)


def plot_powers(traces: dict, Te: float, title: str, path: Path) -> Path:
    """Measured, true and predicted photodiode powers (paper Figs. 9-11 style)."""
    ref = traces.get("kkl") or next(iter(traces.values()))
    t = np.arange(len(ref.x)) * Te
    fig, axes = _subplots(2, 1, figsize=(8, 6), sharex=True)
    for i, ax in enumerate(axes):
        ax.plot(t, ref.y[:, i], color="0.75", lw=0.5, label="measured")
        ax.plot(t, ref.y_clean[:, i], "k", lw=2, label="true")
        ax.plot(t, ref.yhat[:, i], "C0", lw=1, label="predicted h(x_hat), KKL")
        ax.set_ylabel(f"P{i + 1} [W]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[0].set_title(f"photodiode powers — {title}")
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    return _save(fig, path)


def plot_series(res, path: Path, title: str = "") -> Path:
    """Angles, powers and torque of an open-loop MuJoCo run (``SimulationResult``)."""
    fig, axes = _subplots(3, 1, figsize=(9, 7.5), sharex=True)
    ax = axes[0]
    ax.plot(res.t, res.phi, label="phi (photodiode 1) [rad]")
    ax.plot(res.t, res.phidot, label="phidot [rad/s]", alpha=0.7)
    ax.set_ylabel("true state")
    ax.legend(fontsize=8)
    _power_axis(axes[1], res.t, res.power, res.power_clean, res.occluded.any(axis=1),
                "line of sight blocked")
    axes[2].plot(res.t, res.torque, color="C3")
    axes[2].set_ylabel("torque [N m]")
    axes[2].set_xlabel("time [s]")
    for a in axes:
        a.grid(alpha=0.3)
    if title:
        axes[0].set_title(title)
    fig.tight_layout()
    return _save(fig, path)


def _power_axis(ax, t, power, power_clean, blocked, blocked_label: str,
                layout=None) -> None:
    """Each photodiode's measured and true power (named by ``layout``; None: P1, P2)."""
    names = [f"P{j + 1}" for j in range(2)] if layout is None else \
        [p.series.upper() for p in layout.photodiodes]
    for j, name in enumerate(names):
        ax.plot(t, power[:, j], lw=0.5, alpha=0.5, color=f"C{j}")
        ax.plot(t, power_clean[:, j], lw=1.5, color=f"C{j}", label=name)
    _shade(ax, t, blocked, blocked_label)
    ax.set_ylabel("power [W]")
    ax.legend(fontsize=8)


def plot_run(trace, title: str, estimator: str, path: Path) -> Path:
    """MuJoCo truth vs estimate and the powers of one closed-loop run (``Trace``)."""
    t = trace.t
    fig, axes = _subplots(3, 1, figsize=(9, 8), sharex=True)
    layout = getattr(trace, "layout", None)
    # a pan-tilt head: its two angles (the state's first two); one axis: phi and phidot
    labels = ["azimuth [rad]", "elevation [rad]"] if layout is not None and \
        layout.n_axes == 2 else ["phi [rad]", "phidot [rad/s]"]
    for i, (ax, label) in enumerate(zip(axes[:2], labels, strict=True)):
        ax.plot(t, trace.x[:, i], "k", lw=2, label="MuJoCo truth")
        ax.plot(t, trace.xhat[:, i], "C0", lw=1, label=f"{estimator} estimate")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    lost = getattr(trace, "lost", None)
    if lost is not None and np.any(lost):
        for ax in axes:
            ax.fill_between(t, 0, 1, where=lost, transform=ax.get_xaxis_transform(),
                            color="C3", alpha=0.12, lw=0,
                            label="link lost (supervisor)" if ax is axes[0] else None)
    axes[0].legend(fontsize=8)
    _power_axis(axes[2], t, trace.power, trace.power_clean, trace.occluded.any(axis=1),
                "blocked", layout)
    axes[2].set_xlabel("time [s]")
    axes[2].grid(alpha=0.3)
    axes[0].set_title(title)
    fig.tight_layout()
    return _save(fig, path)


def plot_powers_by_distance(traces: dict, Te: float, title: str, path: Path) -> Path:
    """Measured, true and predicted powers at several link distances, overlaid (paper
    Figs. 9-11). ``traces`` maps a distance [m] to a closed-form ``Trajectory``."""
    fig, axes = _subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for c, (d, tr) in enumerate(sorted(traces.items())):
        t = np.arange(len(tr.x)) * Te
        for i, ax in enumerate(axes):
            ax.plot(t, tr.y[:, i], color=f"C{c}", lw=0.4, alpha=0.3)
            ax.plot(t, tr.y_clean[:, i], color=f"C{c}", lw=2, label=f"true, d = {d:g} m")
            ax.plot(t, tr.yhat[:, i], "k--", lw=0.9,
                    label="predicted h(x_hat), KKL" if c == 0 else None)
    for i, ax in enumerate(axes):
        ax.set_ylabel(f"P{i + 1} [W]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8, ncol=2)
    axes[0].set_title(title)
    axes[1].set_xlabel("time [s]")
    fig.tight_layout()
    return _save(fig, path)


def plot_sweep(summary: list[dict], path: Path) -> Path:
    """Availability and steady-state x1 RMSE of a sweep: one group of bars per
    (disturbance, distance, noise scale), one bar per estimator, error bars over seeds."""
    estimators = list(dict.fromkeys(s["estimator"] for s in summary))
    combos = list(dict.fromkeys((s["disturbance"], s["distance"], s["noise_scale"])
                                for s in summary))
    by = {(s["estimator"], s["disturbance"], s["distance"], s["noise_scale"]): s
          for s in summary}
    width = 0.8 / len(estimators)
    x = np.arange(len(combos))
    fig, axes = _subplots(2, 1, figsize=(max(6.0, 1.2 * len(combos) + 3), 6.5),
                             sharex=True)
    for ax, metric, label, log in ((axes[0], "availability", "availability [-]", False),
                                   (axes[1], "rmse_steady_x1", "steady x1 RMSE [rad]",
                                    True)):
        for k, est in enumerate(estimators):
            rows = [by.get((est, *c)) for c in combos]
            mean = [np.nan if r is None or r[f"{metric}_mean"] is None
                    else r[f"{metric}_mean"] for r in rows]
            std = [0.0 if r is None or r[f"{metric}_std"] is None
                   else r[f"{metric}_std"] for r in rows]
            ax.bar(x + (k - (len(estimators) - 1) / 2) * width, mean, width, yerr=std,
                   label=est, capsize=2)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3, axis="y")
        if log:
            ax.set_yscale("log")
    axes[0].legend(fontsize=8, ncol=len(estimators))
    labels = [f"{d.replace(':', ':' + chr(10)).replace('+', '+' + chr(10))}\n"
              f"d={r:g} m, noise x{n:g}" for d, r, n in combos]  # long specs wrap
    axes[1].set_xticks(x, labels, fontsize=7)
    axes[0].set_title("sweep: mean and spread over seeds")
    fig.tight_layout()
    return _save(fig, path)
