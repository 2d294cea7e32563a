"""``ledsim budget``: SNR, BER, throughput and FEC share against distance for a link
preset, a water and a bit rate, and the range at the FEC limit."""

from __future__ import annotations

import json
import logging

from ledsim.files.results import to_jsonable

log = logging.getLogger("ledsim")


def budget(args) -> int:
    """Print the link budget (a table, or ``--json``) and write ``--plot``."""
    from ledsim.files.outputs import atomic_write_bytes, check_out_file
    from ledsim.radiometry.budget import budget_report, format_budget, plot_budget

    plot = check_out_file(args.plot, ".png", "--plot") if args.plot else None
    report = budget_report(args.link, args.water, args.attenuation, args.bit_rate,
                           args.distance or None, args.pointing_error)
    if args.json:
        print(json.dumps(to_jsonable(report), indent=2))
    else:
        print(format_budget(report))
    if plot is not None:
        def write(tmp):
            plot_budget(report, tmp)

        atomic_write_bytes(plot, write)
        log.info(f"wrote {plot}")
    return 0
