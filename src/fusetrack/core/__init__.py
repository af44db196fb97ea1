"""Core values: beliefs, measurements, tracks, model interfaces, errors, angles, resampling, slice sampling."""

from .angles import angle_diff, circular_mean, wrap_angle
from .beliefs import Gaussian, GaussianMixture, GridBelief, Particles
from .errors import (
    ConfigError,
    DegenerateWeightsWarning,
    FusetrackError,
    MeasurementError,
    ShapeError,
    UnknownExperimentError,
    UnknownSensorError,
    check_positive,
    check_probability,
    invalid,
)
from .measurement import Measurement, as_measurements, group_by_time, order_by_time, stack_values
from .models import (
    Belief,
    Filter,
    LikelihoodFilter,
    MotionModel,
    SensorMap,
    SensorModel,
    SteppingFilter,
    filter_step,
    step_with_likelihood,
)
from .resampling import RESAMPLERS, get_resampler, multinomial, residual, stratified, systematic
from .slice_sampling import SliceDraw, slice_sample
from .track import Estimate, Track

__all__ = [
    "RESAMPLERS",
    "Belief",
    "ConfigError",
    "DegenerateWeightsWarning",
    "Estimate",
    "Filter",
    "FusetrackError",
    "Gaussian",
    "GaussianMixture",
    "GridBelief",
    "LikelihoodFilter",
    "Measurement",
    "MeasurementError",
    "MotionModel",
    "Particles",
    "SensorMap",
    "SensorModel",
    "ShapeError",
    "SliceDraw",
    "SteppingFilter",
    "Track",
    "UnknownExperimentError",
    "UnknownSensorError",
    "angle_diff",
    "as_measurements",
    "check_positive",
    "check_probability",
    "circular_mean",
    "filter_step",
    "get_resampler",
    "group_by_time",
    "invalid",
    "multinomial",
    "order_by_time",
    "residual",
    "slice_sample",
    "stack_values",
    "step_with_likelihood",
    "stratified",
    "systematic",
    "wrap_angle",
]
