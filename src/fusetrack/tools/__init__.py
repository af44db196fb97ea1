"""Tools that run whole chains on a user's own data (``fusetrack track``, ``track-video``,
``make-sample``), regenerate the full-size reports (``fusetrack reproduce``) and tally their
claims (``fusetrack reports tally``)."""

from .report_tally import (
    add_reports_parser,
    refresh_reports_folder,
    run_reports_command,
    tally_markdown,
)
from .reproduce import add_reproduce_parser, run_reproduce_command
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
    "add_reports_parser",
    "add_reproduce_parser",
    "add_track_parser",
    "add_track_video_parser",
    "load_scene",
    "make_sample",
    "refresh_reports_folder",
    "run_make_sample_command",
    "run_reports_command",
    "run_reproduce_command",
    "run_track_command",
    "run_track_video_command",
    "tally_markdown",
    "track_scene",
    "track_video",
    "write_recording",
]
