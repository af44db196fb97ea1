"""Speed of the Nott 2009 chain against the targets of issue 7.

1. Video front end on 640x480 frames of the rendered room: Horprasert background subtraction
   (fused Numba kernel) + clean-up + connected components + fragment merging. Target >= 25 fps.
   The NumPy reference of the same classifier is timed beside it.
2. Joint EKF for many people at once (batched over people, one NumPy call per step): predict,
   radio-tag update and camera (foot point) update per frame. Target: 1000 people at >= 25 fps.

CPU seconds (``time.process_time``); the same work by the wall clock in ``"wall"``. BLAS and Numba
at their defaults (``--threads T``: T threads for both, ``_results.py``). fusetrack only.

    python benchmarks/nott2009_speed.py [--frames 60] [--people 1000] [--threads T] [--json]
        [--save | --out PATH]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.experiments.nott2009.video import ekf_step_time
from fusetrack.perception.video import HorprasertModel, find_blobs
from fusetrack.world.rendered_room import Person, RoomRenderer, crossing_walks


def front_end_fps(n_frames: int) -> dict[str, object]:
    rng = np.random.default_rng(0)
    renderer = RoomRenderer()
    model = HorprasertModel.train(renderer.empty_frames(60, rng))
    a, b = crossing_walks(15.0, n_frames)
    frames = [f.image for f in renderer.frames([Person(a), Person(b)], rng)]
    find_blobs(model.foreground(frames[0]))  # compile
    with _results.Clock() as c:
        for f in frames:
            find_blobs(model.foreground(f))
    with _results.Clock() as r:
        for f in frames[:10]:
            find_blobs(model.foreground_reference(f))
    return {
        "front_end_fps": len(frames) / c.cpu,
        "front_end_numpy_reference_fps": 10 / r.cpu,
        "wall": {
            "front_end_fps": len(frames) / c.wall,
            "front_end_numpy_reference_fps": 10 / r.wall,
        },
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=60)
    ap.add_argument("--people", type=int, default=1000)
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    args = ap.parse_args()

    def both() -> list[dict[str, Any]]:
        out = front_end_fps(args.frames)
        out["ekf_people"] = args.people
        ekf_step_time(args.people, steps=2)  # warm-up (imports, compilation): not timed
        out["ekf_fps"] = 1.0 / ekf_step_time(args.people)
        out["wall"]["ekf_fps"] = 1.0 / ekf_step_time(args.people, clock=time.perf_counter)  # type: ignore[index]
        return [out]

    (out,) = _results.measured(args, __file__, both)
    if args.json:
        print(json.dumps(out, indent=2))
        return
    print(f"front end (Numba kernel):   {out['front_end_fps']:7.1f} frames/s  (target >= 25)")
    print(f"front end (NumPy reference):{out['front_end_numpy_reference_fps']:7.1f} frames/s")
    print(f"joint EKF, {args.people} people:    {out['ekf_fps']:7.1f} frames/s  (target >= 25)")


if __name__ == "__main__":
    main()
