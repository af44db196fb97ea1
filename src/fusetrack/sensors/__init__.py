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

from .angles import AzimuthPolar, Bearing
from .base import MIN_RANGE_SQ, SensorBase, wrap
from .linear_gaussian import LinearGaussianSensor
from .position_fix import PositionFix
from .range import Range, RangeBearing

__all__ = [
    "MIN_RANGE_SQ",
    "AzimuthPolar",
    "Bearing",
    "LinearGaussianSensor",
    "PositionFix",
    "Range",
    "RangeBearing",
    "SensorBase",
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
from .occlusion_aware_camera import OcclusionAwareLikelihood as OcclusionAwareLikelihood
from .perspective_camera import CameraArray as CameraArray
from .perspective_camera import PerspectiveCamera as PerspectiveCamera
from .stacked import StackedSensor as StackedSensor
