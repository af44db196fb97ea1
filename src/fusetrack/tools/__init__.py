"""Tools that run whole chains on a user's own data (``fusetrack track-video``)."""

from .synthetic_recording import write_recording
from .track_video import InputError, run_track_video_command, track_video
from .track_video_args import add_track_video_parser
from .video_tracker import FrameResult, TrackerConfig, VideoRadioTracker

__all__ = [
    "FrameResult",
    "InputError",
    "TrackerConfig",
    "VideoRadioTracker",
    "add_track_video_parser",
    "run_track_video_command",
    "track_video",
    "write_recording",
]
