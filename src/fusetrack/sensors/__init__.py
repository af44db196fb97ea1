"""Sensor (measurement) models: ``z = h(x) + v``, seen with a detection probability.

Every model shares :class:`SensorBase` (geometry, field of view, maximum range, detection,
residuals with wrapped angles, Gaussian log-likelihood, simulation, Fisher information) and adds
only ``predict``, ``jacobian`` and ``noise_cov``:

* :class:`Bearing` -- 2-D bearing relative to the heading;
* :class:`AzimuthPolar` -- 3-D azimuth (relative to the heading) and polar angle from +z;
* :class:`Range` -- distance in 2-D or 3-D;
* :class:`RangeBearing` -- 2-D range and bearing;
* :class:`PositionFix` -- radio tag / localiser: position + bias with a full covariance.
"""

from .acoustic_intensity import AcousticIntensity
from .angles import AzimuthPolar, Bearing
from .appearance import N_HS, N_LBP, BinMap, region_histograms
from .appearance_camera import RHO_FLOOR, colour_log_likelihood, reference_histogram
from .base import MIN_RANGE_SQ, SensorBase, wrap
from .camera_geometry import (
    PinholeCamera,
    apply_homography,
    back_project,
    default_camera,
    ground_homography,
    invert_homography,
    plane_homography,
)
from .detection_function import mixture_arc_mean, normalize_likelihood
from .doa_projection import (
    PLANE_AXES,
    PLANES,
    DoaSensor3D,
    check_angles,
    direction_angles,
    literal_second_plane,
    monte_carlo_projected_variance,
    projected_angles,
    projected_variance,
)
from .ellipsoid_camera import (
    EllipsoidCamera,
    axis_angle_quaternion,
    ellipsoid_matrix,
    intersect_rays,
    look_at,
    project_ellipsoid,
    quaternion_multiply,
    quaternion_to_rotation,
    rotation_to_quaternion,
    shape_matrix,
)
from .likelihood_map import LikelihoodMapSensor, detection_quality
from .linear_gaussian import LinearGaussianSensor
from .perspective_camera import MIN_DEPTH, ring_of_cameras
from .position_fix import PositionFix
from .power import Power
from .range import Range, RangeBearing
from .rfid_coverage import (
    RfidReader,
    WallCameraPair,
    coarse_position,
    max_virtual_sensors,
    virtual_sensors,
)
from .unlabelled_bearings import merge_close, simulate_bearings, true_bearings

__all__ = [
    "MIN_DEPTH",
    "MIN_RANGE_SQ",
    "N_HS",
    "N_LBP",
    "PLANES",
    "PLANE_AXES",
    "RHO_FLOOR",
    "AcousticIntensity",
    "AngularSampling",
    "AppearanceCamera",
    "AppearanceModel",
    "AzimuthPolar",
    "Bearing",
    "BinMap",
    "CameraArray",
    "CameraNetworkReport",
    "DetectionFunctionSensor",
    "DoaCone",
    "DoaSensor3D",
    "EllipsoidCamera",
    "FeatureImage",
    "GroundPlaneDetection",
    "LikelihoodMapSensor",
    "LinearGaussianSensor",
    "OcclusionAwareCameraSensor",
    "OcclusionAwareLikelihood",
    "PinholeCamera",
    "PositionFix",
    "Power",
    "ProjectedPlaneBearing",
    "Range",
    "RangeBearing",
    "RfidReader",
    "SensorBase",
    "StackedSensor",
    "WallCameraPair",
    "apply_homography",
    "arc_mean_matrix",
    "axis_angle_quaternion",
    "back_project",
    "cell_arcs",
    "check_angles",
    "coarse_position",
    "colour_log_likelihood",
    "default_camera",
    "detection_quality",
    "direction_angles",
    "ellipsoid_matrix",
    "ground_homography",
    "intersect_rays",
    "invert_homography",
    "literal_second_plane",
    "look_at",
    "max_virtual_sensors",
    "merge_close",
    "mixture_arc_mean",
    "monte_carlo_projected_variance",
    "normalize_likelihood",
    "plane_homography",
    "project_ellipsoid",
    "projected_angles",
    "projected_variance",
    "quaternion_multiply",
    "quaternion_to_rotation",
    "reference_histogram",
    "region_histograms",
    "ring_of_cameras",
    "rotation_to_quaternion",
    "shape_matrix",
    "simulate_bearings",
    "true_bearings",
    "virtual_sensors",
    "wrap",
]

# Nott 2009 (issue 7): the camera that sees a person on the floor, a simulated NFER radio tag
from . import camera_geometry as camera_geometry

# Cameras and tags: Kushwaha 2010's appearance camera (issue 16), Nott 2009's (issue 7)
from .appearance import AppearanceModel as AppearanceModel
from .appearance import FeatureImage as FeatureImage
from .appearance_camera import AppearanceCamera as AppearanceCamera
from .bearing_detection import DetectionFunctionSensor as DetectionFunctionSensor
from .detection_function import AngularSampling as AngularSampling
from .detection_function import arc_mean_matrix as arc_mean_matrix
from .detection_function import cell_arcs as cell_arcs
from .doa_plane_likelihood import DoaCone as DoaCone
from .doa_plane_likelihood import ProjectedPlaneBearing as ProjectedPlaneBearing
from .ground_plane_detection import GroundPlaneDetection as GroundPlaneDetection
from .homography_camera import HomographyCamera as HomographyCamera
from .nfer_tag import NferTagSimulator as NferTagSimulator
from .nfer_tag import fit_position_fix as fit_position_fix
from .occlusion_aware_camera import CameraNetworkReport as CameraNetworkReport
from .occlusion_aware_camera import OcclusionAwareCameraSensor as OcclusionAwareCameraSensor
from .occlusion_aware_camera import OcclusionAwareLikelihood as OcclusionAwareLikelihood
from .perspective_camera import CameraArray as CameraArray
from .perspective_camera import PerspectiveCamera as PerspectiveCamera
from .stacked import StackedSensor as StackedSensor
