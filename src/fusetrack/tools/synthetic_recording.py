"""Write a rendered recording (video file, radio-tag log, camera calibration) for
``fusetrack track-video``: the same files a user brings, with exact ground truth beside them."""

from __future__ import annotations

from itertools import chain
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..sensors import NferTagSimulator, PinholeCamera, ground_homography, plane_homography
from ..world import Person, RoomRenderer, Walk, single_person_walk, write_video


def write_recording(
    out: Path,
    *,
    seed: int = 0,
    n_empty: int = 30,
    n_frames: int = 60,
    fps: float = 15.0,
    tag_every: int = 3,
    video_name: str = "video.avi",
    camera: PinholeCamera | None = None,
    min_area: int | None = None,
) -> dict[str, Any]:
    """Render ``n_empty`` frames of the empty room then a person walking for ``n_frames``; write
    ``video.avi`` (lossless), ``tags.csv`` (5 Hz simulated NFER tag), ``camera.yaml`` and
    ``truth.csv`` into ``out``. ``camera``: the renderer's (default: 640x480, Nott 2009 spec);
    ``min_area``: the blob area (px) written into the calibration. Returns the paths."""
    import yaml

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed)
    renderer = RoomRenderer() if camera is None else RoomRenderer(camera=camera)
    walk = single_person_walk(fps, n_frames)
    shifted = Walk(walk.times + n_empty / fps, walk.xy)  # on the video clock
    person = Person(shifted)
    empty = renderer.empty_frames(n_empty, rng)
    frames = (f.image for f in renderer.frames([person], rng))
    video = out / video_name
    write_video(str(video), chain(iter(empty), frames), fps)
    tag = NferTagSimulator("field", sigma=(0.1, 0.1), quantum=0.098, field_seed=seed)
    idx = np.arange(0, n_frames, tag_every)
    z = tag.simulate(shifted.xy[idx], rng)
    pd.DataFrame({"time": shifted.times[idx], "tag": "subject", "x": z[:, 0], "y": z[:, 1]}).to_csv(
        out / "tags.csv", index=False
    )
    P = renderer.camera.P
    cal = {
        "foot_homography": ground_homography(P).tolist(),
        "head_homography": plane_homography(P, person.height).tolist(),
        "tag_cov": np.asarray(tag.position_fix().cov).tolist(),
        "sigma_px": 1.0,
        "fps": fps,
        "background_frames": n_empty,
        "subject_tag": "subject",
    }
    if min_area is not None:
        cal["min_area"] = int(min_area)
    (out / "camera.yaml").write_text(yaml.safe_dump(cal))
    pd.DataFrame(
        {
            "frame": np.arange(n_frames) + n_empty,
            "time": shifted.times,
            "x": shifted.xy[:, 0],
            "y": shifted.xy[:, 1],
        }
    ).to_csv(out / "truth.csv", index=False)
    return {
        "video": video,
        "radio": out / "tags.csv",
        "calibration": out / "camera.yaml",
        "truth": out / "truth.csv",
    }


__all__ = ["write_recording"]
