"""Video front end (Nott 2009, Ch. 4): background subtraction, blobs, occlusion, homographies."""

from .blobs import Blob as Blob
from .blobs import clean_mask as clean_mask
from .blobs import find_blobs as find_blobs
from .blobs import largest_blob as largest_blob
from .blobs import merge_fragments as merge_fragments
from .homography_fit import DegenerateGeometryError as DegenerateGeometryError
from .homography_fit import HomographyFit as HomographyFit
from .homography_fit import calibrate_from_checkerboard as calibrate_from_checkerboard
from .homography_fit import dlt as dlt
from .homography_fit import fit_homography as fit_homography
from .homography_fit import reprojection_errors as reprojection_errors
from .homography_fit import spread_ratio as spread_ratio
from .horprasert import HorprasertModel as HorprasertModel
from .mog2 import Mog2Subtractor as Mog2Subtractor
from .occlusion import OcclusionDecision as OcclusionDecision
from .occlusion import associate as associate
from .occlusion import detect_occlusion as detect_occlusion
