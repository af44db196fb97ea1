"""Simulated worlds: rooms, occluders, walkers and targets, sound and clocks, rendered video."""

from .acoustics import harmonic_engine as harmonic_engine
from .acoustics import pink_noise as pink_noise
from .acoustics import propagate as propagate
from .acoustics import speech_like as speech_like
from .box_target import BoxTarget as BoxTarget
from .box_target import render_box as render_box
from .clocks import HopTranslation as HopTranslation
from .clocks import NodeClock as NodeClock
from .clocks import RbsDomain as RbsDomain
from .clocks import fit_clock_map as fit_clock_map
from .demo_scene import AREA as AREA
from .demo_scene import DemoScene as DemoScene
from .demo_scene import simulate_demo as simulate_demo
from .ellipsoid_scene import EllipsoidTarget as EllipsoidTarget
from .ellipsoid_scene import Frames as Frames
from .ellipsoid_scene import PaintedTarget as PaintedTarget
from .ellipsoid_scene import Trajectory as Trajectory
from .ellipsoid_scene import corner_cameras as corner_cameras
from .ellipsoid_scene import cube_viewpoints as cube_viewpoints
from .ellipsoid_scene import perimeter_cameras as perimeter_cameras
from .ellipsoid_scene import reference_views as reference_views
from .ellipsoid_scene import render_frames as render_frames
from .ellipsoid_scene import render_target as render_target
from .ellipsoid_scene import smooth_trajectory as smooth_trajectory
from .geometry import rectangle as rectangle
from .geometry import segment_point_distance as segment_point_distance
from .harmonic_sources import HarmonicSource as HarmonicSource
from .harmonic_sources import noise_sigma as noise_sigma
from .harmonic_sources import random_sources as random_sources
from .harmonic_sources import received_signals as received_signals
from .head_video import Actor as Actor
from .head_video import RenderedSequence as RenderedSequence
from .head_video import Scene as Scene
from .head_video import Sprite as Sprite
from .head_video import keyframe_trajectory as keyframe_trajectory
from .head_video import render as render
from .occluder_priors import PRIOR_FILTERS as PRIOR_FILTERS
from .occluder_priors import RandomWalkPriorFilter as RandomWalkPriorFilter
from .occluder_priors import prior_nees as prior_nees
from .occluder_priors import prior_track as prior_track
from .occluder_priors import rmse_per_coordinate as rmse_per_coordinate
from .occlusion import OccluderPriors as OccluderPriors
from .occlusion import disks_block as disks_block
from .occlusion import occlusion_probability as occlusion_probability
from .occlusion import occlusion_probability_eq7 as occlusion_probability_eq7
from .occlusion import occlusion_probability_reference as occlusion_probability_reference
from .occlusion import pattern_probability as pattern_probability
from .occlusion_kernels import camera_likelihood_kernel as camera_likelihood_kernel
from .occlusion_kernels import pair_visibility_kernel as pair_visibility_kernel
from .occlusion_kernels import (
    pair_visibility_of_priors_kernel as pair_visibility_of_priors_kernel,
)
from .occlusion_kernels import (
    pair_visibility_per_particle_kernel as pair_visibility_per_particle_kernel,
)
from .occlusion_kernels import prior_draw_hits_kernel as prior_draw_hits_kernel
from .potential_field import NavigationResult as NavigationResult
from .potential_field import PotentialField as PotentialField
from .potential_field import navigate as navigate
from .rendered_room import WALL as WALL
from .rendered_room import Person as Person
from .rendered_room import RoomRenderer as RoomRenderer
from .rendered_room import behind_wall_walk as behind_wall_walk
from .rendered_room import crossing_walks as crossing_walks
from .rendered_room import diverse_training_walk as diverse_training_walk
from .rendered_room import single_person_walk as single_person_walk
from .rendered_room import straight_training_walk as straight_training_walk
from .rendered_room import write_video as write_video
from .road_video import RoadRenderer as RoadRenderer
from .road_video import Vehicle as Vehicle
from .room import Room as Room
from .room import l_shaped_room as l_shaped_room
from .room import square_room as square_room
from .walkers import Walk as Walk
from .walkers import WaypointWalkers as WaypointWalkers
from .walkers import polyline_walk as polyline_walk
