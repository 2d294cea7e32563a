"""``ledsim replay``: a saved trace through a fresh estimator or an ONNX export."""

from __future__ import annotations

import json

from ledsim.files.results import to_jsonable


def replay(args) -> int:
    """Replay TRACE (``ledsim run --save-trace``) and print the largest difference of
    the replayed estimates from the run's."""
    from ledsim.loop.replay import replay as run_replay

    result = run_replay(args.trace, args.onnx)
    if args.json:
        print(json.dumps(to_jsonable(result), indent=2))
    else:
        print(f"{result.trace}: {result.estimates} estimates of {result.estimator} "
              f"replayed through {result.against} ({result.calls} calls): largest "
              f"difference {result.max_abs_difference:.3g}")
    return 0
