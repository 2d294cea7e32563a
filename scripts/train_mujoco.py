"""Train the shipped KKL observers of the MuJoCo world (``ledsim train --world mujoco``)
into assets/checkpoints/kkl_mujoco_d<d>.safetensors.

    python scripts/train_mujoco.py [--distances 0.085] [--noise-scales 1] [--samples 200000]

``--lens --bank`` trains their bank (kkl_mujoco_lens_d0.085_noise<s>.safetensors).

``--lens`` trains the gain-scheduled KKL of the physical presets (``--link aquaoptical``
and the others): the bench with their receiver's response and relative noise
(``ledsim.radiometry.link_presets.kkl_reference_constants``), saved as
kkl_mujoco_scheduled_lens_d0.085.safetensors.

``--bank`` trains the bank the closed loop runs at every distance
(``ledsim.loop.build.estimation.BANK``): the observers of d = 0.085 m for 1x, 3x, 6x and 13x
the nominal measurement noise (what the noise becomes, rescaled to the reference gain,
at about d = 0.085-0.3 m), saved as kkl_mujoco_d0.085_noise<s>.safetensors (no suffix for 1).
"""

from __future__ import annotations

import argparse
import os

from ledsim.cli.options import WORKERS
from ledsim.files.outputs import save_checkpoint
from ledsim.files.resources import shipped_checkpoint
from ledsim.loop.build.estimation import BANK_NOISE, REFERENCE_DISTANCE
from ledsim.loop.world_training import train_mujoco_observer
from ledsim.radiometry.link_presets import kkl_reference_constants


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--distances", type=float, nargs="+", default=[0.085])
    ap.add_argument("--noise-scales", type=float, nargs="+", default=[1.0])
    ap.add_argument("--bank", action="store_true",
                    help="train every member of the shipped bank (overrides the above)")
    ap.add_argument("--samples", type=int, default=200_000)
    ap.add_argument("--threads", type=WORKERS, default=min(os.cpu_count() or 1, 64),
                    help="threads that step the transitions' physics (mujoco.rollout; "
                         "default: every core)")
    ap.add_argument("--lens", action="store_true",
                    help="train the physical presets' gain-scheduled KKL (overrides the above)")
    args = ap.parse_args()
    if args.lens and args.bank:
        for s in BANK_NOISE:
            obs, rep, extra = train_mujoco_observer(
                REFERENCE_DISTANCE, s, samples=args.samples, threads=args.threads,
                constants=kkl_reference_constants())
            path = save_checkpoint(obs, shipped_checkpoint(REFERENCE_DISTANCE, "mujoco",
                                                           "lens", noise=s), extra=extra)
            print(f"physical presets' bank, noise x{s:g}: training {rep.seconds:.0f} s, "
                  f"L_dyn={rep.loss_dyn:.2e}, L_recon={rep.loss_recon:.2e} -> {path}")
        return
    if args.lens:
        obs, rep, extra = train_mujoco_observer(
            REFERENCE_DISTANCE, 1.0, "scheduled", args.samples, threads=args.threads,
            progress=True, constants=kkl_reference_constants())
        path = save_checkpoint(obs, shipped_checkpoint(REFERENCE_DISTANCE, "mujoco",
                                                       design="scheduled-lens"), extra=extra)
        print(f"physical presets' scheduled KKL: {args.samples} MuJoCo transitions in "
              f"{extra['data']['seconds']:.0f} s, training {rep.seconds:.0f} s, "
              f"L_dyn={rep.loss_dyn:.2e}, L_recon={rep.loss_recon:.2e} -> {path}")
        return
    if args.bank:
        args.distances, args.noise_scales = [REFERENCE_DISTANCE], list(BANK_NOISE)
    for d, s in [(d, s) for d in args.distances for s in args.noise_scales]:
        obs, rep, extra = train_mujoco_observer(d, s, samples=args.samples,
                                                threads=args.threads)
        path = save_checkpoint(obs, shipped_checkpoint(d, "mujoco", noise=s), extra=extra)
        print(f"d={d:g}, noise x{s:g}: {args.samples} MuJoCo transitions in "
              f"{extra['data']['seconds']:.0f} s, training {rep.seconds:.0f} s, "
              f"L_dyn={rep.loss_dyn:.2e}, L_recon={rep.loss_recon:.2e} -> {path}")


if __name__ == "__main__":
    main()
