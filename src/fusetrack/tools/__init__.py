"""Tools that run whole chains on a user's own data (``fusetrack track``, ``track-video``,
``make-sample``)."""

from .sample import add_make_sample_parser, make_sample, run_make_sample_command
from .scene import Scene, load_scene
from .synthetic_recording import write_recording
from .track_scene import add_track_parser, run_track_command, track_scene
from .track_video import InputError, run_track_video_command, track_video
from .track_video_args import add_track_video_parser
from .video_tracker import FrameResult, TrackerConfig, VideoRadioTracker

__all__ = [
    "FrameResult",
    "InputError",
    "Scene",
    "TrackerConfig",
    "VideoRadioTracker",
    "add_make_sample_parser",
    "add_track_parser",
    "add_track_video_parser",
    "load_scene",
    "make_sample",
    "run_make_sample_command",
    "run_track_command",
    "run_track_video_command",
    "track_scene",
    "track_video",
    "write_recording",
]
