"""What one mission pass delivers, against time: the range, the data detector's SNR, the
throughput through the FEC code and the pointing error, for the KKL and the oracle on
the same seed (issue 49). Writes ``docs/img/<scenario>_pass.png``.

    python scripts/mission_figure.py [--scenario flyby] [--link luma] [--water clear-ocean]
                                     [--seed 0] [--out docs/img/flyby_pass.png]
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "osmesa")


def one_pass(scenario: str, link: str, water: str, estimator: str, seed: int) -> dict:
    """Step by step: time [s], range [m], SNR [dB], throughput [bit/s], pointing error
    [rad] (the angle from the data detector's boresight to the LED) and held."""
    import numpy as np

    from ledsim.loop.closed_loop import ClosedLoop
    from ledsim.loop.run_config import RunSpec
    from ledsim.radiometry.data_channel import snr_at
    from ledsim.radiometry.goodput import delivered_bits

    cfg = RunSpec(scenario=scenario, link=link, water=water, estimator=estimator)
    cfg.validate()
    loop = ClosedLoop(cfg, [seed])
    run = loop.runs[0]
    loop.run(False)
    c = cfg.world_config().constants
    noise, Te, rate = c.measurement_noise(cfg.noise_scale), c.Te, cfg.data_bit_rate
    ref = c.layout.reference
    power = run.clean[:, ref]
    snr = snr_at(power, noise, Te, rate)
    held = ~run.flags.any(axis=1)
    bits = np.where(held, delivered_bits(power, noise, Te, rate), 0.0)
    return {"t": Te * np.arange(1, len(power) + 1), "range": run.geo[:, 0, ref],
            "snr_db": 10 * np.log10(np.maximum(snr, 1e-12)), "throughput": bits / Te,
            "pointing": np.hypot(run.state[:, 0], run.state[:, 1]), "held": held}


def main(argv=None) -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--scenario", default="flyby")
    p.add_argument("--link", default="luma")
    p.add_argument("--water", default="clear-ocean")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default=None)
    args = p.parse_args(argv)
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ledsim.files.outputs import atomic_write_bytes

    out = Path(args.out or f"docs/img/{args.scenario}_pass.png")
    passes = {e: one_pass(args.scenario, args.link, args.water, e, args.seed)
              for e in ("oracle", "kkl")}
    fig, axes = plt.subplots(4, 1, figsize=(8, 9), sharex=True)
    style = {"oracle": dict(color="k", lw=2.0, alpha=0.5), "kkl": dict(color="C0", lw=1.0)}
    for name, r in passes.items():
        axes[0].plot(r["t"], r["range"], label=name, **style[name])
        axes[1].plot(r["t"], r["snr_db"], **style[name])
        axes[2].plot(r["t"], r["throughput"] / 1e3, **style[name])
        axes[3].semilogy(r["t"], np.maximum(r["pointing"], 1e-6), **style[name])
    for ax, label in zip(axes, ("range [m]", "data SNR [dB]", "throughput [kbit/s]",
                                "pointing error [rad]"), strict=True):
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].legend()
    axes[-1].set_xlabel("time [s]")
    got = {n: r["throughput"].sum() * (r["t"][1] - r["t"][0]) / 1e6 for n, r in passes.items()}
    axes[0].set_title(f"{args.scenario}, {args.link} in {args.water}, seed {args.seed}: "
                      f"KKL {got['kkl']:.2f} Mbit, oracle {got['oracle']:.2f} Mbit")
    fig.tight_layout()
    atomic_write_bytes(out, lambda f: fig.savefig(f, format="png", dpi=90))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
