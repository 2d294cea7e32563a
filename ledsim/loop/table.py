"""The table a closed-loop run prints: one markdown row per summary (``ledsim run``,
``ledsim demo``, the disturbance and vehicle tables)."""

from __future__ import annotations

from ledsim.loop.report import RunSummary, Stat
from ledsim.physics.disturbances import parse_disturbance

TABLE_HEADER = ("| scenario | disturbance | estimator | x1 RMSE [rad] | x2 RMSE [rad/s] "
                "| align time [s] | availability | FEC share | mean P1 [W] | recovery [s] "
                "| RTF | x1/PCRB | pointing loss [dB] |"
                "\n|---|---|---|---|---|---|---|---|---|---|---|---|---|")


def recovered(s: RunSummary) -> str:
    """The recovery cell: mean time [s] and how many seeds recovered, ``0.52 (2/4)``;
    ``- (0/4)`` when none did; ``-`` without an event."""
    if s.recovery_time.mean is None:
        return f"- (0/{s.seeds})" if _has_event(s) else "-"
    return f"{s.recovery_time.mean:.2f} ({s.recovery_time.n}/{s.seeds})"


def _has_event(s: RunSummary) -> bool:
    return any(parse_disturbance(d).event_end is not None for d in s.disturbances)


def format_summary(s: RunSummary, first_cell: str | None = None) -> str:
    """One markdown row of :data:`TABLE_HEADER` (``first_cell``: instead of the scenario;
    x1/PCRB is the steady phi RMSE over the root of the posterior Cramér-Rao bound)."""
    def f(stat: Stat, fmt="{:.2e}"):
        return "-" if stat.mean is None else fmt.format(stat.mean)

    return (f"| {first_cell or s.scenario} | {', '.join(s.disturbances) or '-'} "
            f"| {s.estimator} | {f(s.rmse_steady_x1)} | {f(s.rmse_steady_x2)} "
            f"| {f(s.alignment_time, '{:.2f}')} | {f(s.availability, '{:.3f}')} "
            f"| {f(s.fec_share, '{:.3f}')} "
            f"| {f(s.mean_power, '{:.3f}' if s.link == 'paper' else '{:.2e}')} "
            f"| {recovered(s)} "
            f"| {f(s.realtime_factor, '{:.0f}')} "
            f"| {'-' if s.rmse_over_pcrb_x1 is None else f'{s.rmse_over_pcrb_x1:.2f}'} "
            f"| {f(s.pointing_loss_db or Stat(None, None, 0), '{:.3f}')} |")
