"""``fusetrack make-sample DIR``: the sample recordings of ``examples/sample/``, from the simulators.

One person walks through the rendered room of Nott (2009) (:mod:`fusetrack.world.rendered_room`)
for ``duration`` seconds after ``empty`` seconds of empty scene, talking as they go. Written into
``DIR``, all on one clock (seconds from the first video frame):

* ``video.avi`` + ``camera.yaml``: the rendered camera at low resolution (160x120, 10 frames/s, lossless FFV1: background subtraction
  needs it, MPEG-4 blocks read as foreground),
  with its floor homography (:func:`fusetrack.tools.write_recording`);
* ``tags.csv``: the person's radio tag (simulated NFER fixes, 5 Hz; columns time, tag, x, y);
* ``array.wav``: a 4-microphone square array (0.2 m side, 16 kHz, 16-bit PCM) hearing the
  speech-like source at the person's position, free field (spherical spreading and propagation
  delay, Kushwaha 2010, Eq. 6) with pink background noise (:mod:`fusetrack.world.acoustics`);
  its first sample is at ``empty`` seconds (``offset`` in the scene);
* ``truth.csv``: the person's floor position at every frame (time, x, y);
* ``scene.yaml``: the ``fusetrack track`` scene using them.

Everything comes from one seed, so the files are the same on every run (the test checks it).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ..core import ConfigError, invalid
from ..sensors import PinholeCamera, default_camera
from ..world import pink_noise, propagate, single_person_walk, speech_like
from .synthetic_recording import write_recording

FPS = 10.0
SCALE = 0.25  # of the 640x480 camera: 160x120
AUDIO_FS = 16_000
ARRAY_POSITION = (8.0, 1.0)
ARRAY_HEADING = 0.0
ARRAY_SIDE = 0.2
SNR_DB = 20.0  # speech RMS at the array over the background noise RMS


def square_array(side: float = ARRAY_SIDE) -> list[list[float]]:
    """Four microphones on the corners of a square (node frame, metres), in channel order."""
    h = side / 2
    return [[h, h], [-h, h], [-h, -h], [h, -h]]


def low_resolution_camera(scale: float = SCALE) -> PinholeCamera:
    """The default room camera with its image scaled by ``scale`` (same pose, same view)."""
    c = default_camera()
    K = c.K.copy()
    K[:2] *= scale
    return PinholeCamera(K, c.R, c.centre, round(c.width * scale), round(c.height * scale))


def _write_audio(
    path: Path, truth: pd.DataFrame, start: float, duration: float, rng: np.random.Generator
) -> None:
    """The array's 4 channels while the person walks (16-bit PCM WAV, first sample at ``start``)."""
    from scipy.io import wavfile

    times = np.arange(round(duration * AUDIO_FS)) / AUDIO_FS  # WAV clock
    emission = speech_like(duration + 0.1, rng, fs=AUDIO_FS)  # emitted from WAV time -0.05 s
    t_truth, xy = truth["time"].to_numpy() - start, truth[["x", "y"]].to_numpy()

    def path_at(t: np.ndarray) -> np.ndarray:
        return np.column_stack([np.interp(t, t_truth, xy[:, 0]), np.interp(t, t_truth, xy[:, 1])])

    c, s = np.cos(ARRAY_HEADING), np.sin(ARRAY_HEADING)
    offsets = np.asarray(square_array()) @ np.array([[c, s], [-s, c]])
    mics = np.asarray(ARRAY_POSITION) + offsets
    x = propagate(emission, lambda t: path_at(t - 0.05), mics, times + 0.05, fs=AUDIO_FS)
    x += 10 ** (-SNR_DB / 20) * x.std() * pink_noise(x.shape, rng)
    pcm = np.round(x / np.abs(x).max() * 0.9 * 32767).astype(np.int16)
    wavfile.write(path, AUDIO_FS, pcm.T.copy())


def _scene(empty: float) -> dict[str, Any]:
    """The scene YAML of the sample (see docs/track.md)."""
    return {
        "name": "sample: one person, a microphone array, a camera and a radio tag",
        "area": [0.0, 9.0, 0.0, 10.0],
        "clock_tolerance": 1.0,
        "truth": "truth.csv",
        "sensors": [
            {
                "id": "array",
                "kind": "bearing",
                "position": list(ARRAY_POSITION),
                "heading": ARRAY_HEADING,
                "sigma_deg": 2.0,
                "recording": {
                    "format": "wav",
                    "path": "array.wav",
                    "offset": empty,
                    "microphones": square_array(),
                    "hop": 0.1,
                    "window": 2048,
                    "band": [300.0, 3400.0],
                },
            },
            {
                "id": "camera",
                "kind": "image_position",
                "sigma_px": 3.0,
                "image_size": [160, 120],
                "recording": {"format": "video", "path": "video.avi", "calibration": "camera.yaml"},
            },
            {
                "id": "tag",
                "kind": "position_fix",
                "cov": [[0.04, 0.0], [0.0, 0.04]],
                "recording": {"format": "csv", "path": "tags.csv", "where": {"tag": "subject"}},
            },
        ],
        "fusion": {"rate_hz": 5.0},
        "tracker": {
            "filter": "ekf",
            "motion": {"model": "constant_velocity", "q": 0.5},
            "prior_mean": [4.5, 5.0, 0.0, 0.0],
            "prior_std": [3.0, 3.0, 1.0, 1.0],
        },
    }


def make_sample(
    out: str | Path, *, seed: int = 0, empty: float = 1.5, duration: float = 5.0
) -> dict[str, Path]:
    """Write the sample recordings and their scene into ``out`` (module docstring); the paths."""
    import yaml

    if not (duration > 0 and empty > 0):
        raise ConfigError(invalid("duration/empty", (duration, empty), "seconds > 0"))
    out = Path(out)
    rng = np.random.default_rng(seed)
    n_empty, n_frames = round(empty * FPS), round(duration * FPS)
    paths = write_recording(
        out,
        seed=seed,
        n_empty=n_empty,
        n_frames=n_frames,
        fps=FPS,
        tag_every=2,
        video_name="video.avi",
        camera=low_resolution_camera(),
        min_area=20,
    )
    truth = pd.read_csv(paths["truth"])
    walk = single_person_walk(FPS, n_frames)
    assert np.allclose(truth[["x", "y"]].to_numpy(), walk.xy)
    truth[["time", "x", "y"]].to_csv(paths["truth"], index=False, float_format="%.6f")
    _write_audio(out / "array.wav", truth, empty, duration, rng)
    scene = out / "scene.yaml"
    scene.write_text(
        "# The sample scene of `fusetrack track` (written by `fusetrack make-sample`; docs/track.md)\n"
        + yaml.safe_dump(_scene(empty), sort_keys=False, default_flow_style=None)
    )
    return {**paths, "audio": out / "array.wav", "scene": scene}


def run_make_sample_command(args: Any) -> int:
    paths = make_sample(args.out, seed=args.seed)
    print(f"make-sample: wrote {', '.join(p.name for p in paths.values())} into {args.out}")
    return 0


def add_make_sample_parser(sub: Any) -> None:
    """The ``make-sample`` subcommand (``fusetrack.cli`` calls this)."""
    p = sub.add_parser(
        "make-sample", help="write the sample recordings (examples/sample) from the simulators"
    )
    p.add_argument("--out", type=Path, default=Path("examples/sample"), help="output directory")
    p.add_argument("--seed", type=int, default=0, help="the one seed of every random number")


__all__ = ["add_make_sample_parser", "make_sample", "run_make_sample_command", "square_array"]
