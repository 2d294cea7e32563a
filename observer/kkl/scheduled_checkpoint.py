"""The gain-scheduled KKL in a checkpoint: its tables of output weights, and its design
and schedule in the metadata (format ``ledsim-kkl-scheduled/1``).

:func:`observer.kkl.checkpoint.save` and :func:`observer.kkl.checkpoint.load` dispatch here, so a
scheduled checkpoint is a ``.safetensors`` file like every other, and is checked against
the run like every other (Te and the model constants in its metadata).
"""

from __future__ import annotations

import numpy as np

from observer.kkl.gainmaps import GainTableMap
from observer.kkl.scheduled import GainSchedule, ScheduledDesign, ScheduledKKL

FORMAT = "ledsim-kkl-scheduled/1"
_MAPS = ("encoder_T", "decoder_T_star", "decoder_locked")
_ARRAYS = ("W1", "b1", "coef", "log_w", "log_s")


def metadata(obs: ScheduledKKL) -> dict:
    return {"format": FORMAT, "system": obs.system.metadata(),
            "scheduled_design": obs.design.to_dict(),
            "schedule": {k: getattr(obs.schedule, k)
                         for k in GainSchedule.__dataclass_fields__},
            "u_bar": obs.u_bar}


def arrays(obs: ScheduledKKL) -> dict[str, np.ndarray]:
    out = {}
    for name in _MAPS:
        net = getattr(obs, name)
        if net is not None:
            out.update({f"{name}.{k}": a for k, a in net.arrays().items()})
    return out


def build(arrays: dict[str, np.ndarray], meta: dict, model, use_omega: bool) -> ScheduledKKL:
    """The observer from a checkpoint's named arrays and metadata (raises on anything
    malformed; the caller turns that into one line)."""
    design = ScheduledDesign.from_dict(meta["scheduled_design"])
    schedule = GainSchedule(**meta["schedule"])
    maps = {}
    for name in _MAPS:
        if f"{name}.W1" not in arrays:
            maps[name] = None
            continue
        net = GainTableMap(*(np.asarray(arrays[f"{name}.{k}"], dtype=np.float64)
                             for k in _ARRAYS))
        if not net.consistent() or not all(np.isfinite(a).all()
                                           for a in net.arrays().values()):
            raise ValueError(f"{name}: bad shapes or non-finite numbers")
        maps[name] = net
    enc, dec = maps["encoder_T"], maps["decoder_T_star"]
    n = model.n_state
    if enc is None or dec is None or enc.n_in != n or enc.n_out != design.q or \
            dec.n_in != design.q or dec.n_out != n or \
            (maps["decoder_locked"] is not None and maps["decoder_locked"].n_out != n):
        raise ValueError("network shapes do not fit the design and the system")
    return ScheduledKKL(model, design, enc, dec, maps["decoder_locked"], schedule,
                        u_bar=float(meta.get("u_bar", 0.0)), use_omega=use_omega)
