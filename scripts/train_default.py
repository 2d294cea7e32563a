"""Train the shipped observers (default design for each Table 2 distance, paper design at
d = 0.085 m, the slow half of kkl-handover at d = 0.1 and 0.2 m) into assets/checkpoints.
Fixed seeds; about 15 s per observer on 2 cores (about 40 s for a slow one)."""

from __future__ import annotations

import argparse

from ledsim.constants import LinkConstants
from ledsim.experiment.observer_presets import observer_preset
from ledsim.files.outputs import save_checkpoint
from ledsim.paper.evaluate import default_checkpoint
from ledsim.paper.model import LEDLinkModel
from observer.kkl.training import train_kkl


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--distances", type=float, nargs="*", default=[0.085, 0.1, 0.2])
    ap.add_argument("--no-paper", action="store_true", help="skip the paper-design observer")
    ap.add_argument("--slow-distances", type=float, nargs="*", default=[0.1, 0.2],
                    help="distances of the slow observers (kkl-handover)")
    args = ap.parse_args()
    jobs = [("default", d) for d in args.distances]
    if not args.no_paper:
        jobs.append(("paper", 0.085))
    jobs += [("slow", d) for d in args.slow_distances]
    for design_name, d in jobs:
        system = LEDLinkModel(LinkConstants(distance=d))
        design, cfg = observer_preset(design_name, system.Te)
        obs, rep = train_kkl(system, design, cfg)
        path = save_checkpoint(obs, default_checkpoint(d, design_name))
        print(f"{design_name:8s} d={d:<6g} {rep.seconds:6.1f} s  L_dyn={rep.loss_dyn:.2e} "
              f"L_recon={rep.loss_recon:.2e} -> {path}")


if __name__ == "__main__":
    main()
