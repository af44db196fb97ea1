"""kushwaha2010-cameras-occlusion (spec H24): the occluder is drawn over the target."""

import numpy as np

from fusetrack.experiments.kushwaha2010.camera_gap import qvga_cameras
from fusetrack.experiments.kushwaha2010.camera_occlusion import OCCLUDER, occluder_position
from fusetrack.experiments.kushwaha2010.cameras import appearance_model
from fusetrack.world import render_target


def test_occluder_on_the_line_of_sight_hides_the_target():
    cam = qvga_cameras()[0]
    target, _ = appearance_model()
    x = np.asarray(cam.centre) + 10.0 * (np.array([6.0, 12.0, 1.0]) - cam.centre) / np.linalg.norm(
        np.array([6.0, 12.0, 1.0]) - cam.centre
    )
    q = np.array([0.0, 0.0, 0.0, 1.0])
    img = np.zeros((240, 320, 3), np.uint8)
    own = render_target(img.copy(), cam, target, x, q)
    assert own.sum() > 20
    middle = occluder_position(cam, x, 2, 5)  # the middle frame: on the line of sight
    d = (x - cam.centre) / np.linalg.norm(x - cam.centre)
    assert np.allclose(np.cross(middle - cam.centre, d), 0.0, atol=1e-9)
    occ = render_target(img, cam, OCCLUDER, middle, q)
    assert (own & occ).sum() == own.sum()  # wholly hidden
