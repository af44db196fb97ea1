"""Lee 2009 Ch. 4: quality, fused position, dynamic prior and the decision statistic (C12, C13)."""

import math

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError, ShapeError
from fusetrack.core.measurement import Measurement
from fusetrack.filters.detection_fusion import (
    DetectionFusion,
    chair_varshney,
    frame_measurements,
    fused_position,
    presence_prior,
    quality,
    quality_weighted_statistic,
    to_ground,
    to_image,
)


def _case(cams, g_pred):
    det = np.array([c is not None for c in cams])
    gc = np.array([c for c in cams if c is not None], float)
    w = quality(gc, np.array(g_pred), 1.0)
    g = fused_position(gc, w)
    wa = np.zeros(len(cams))
    wa[det] = w
    return det, w, wa, g, float(presence_prior(g, np.array(g_pred), 1.0))


def test_case1_occlusion():
    det, w, wa, g, p1 = _case([None, (5.2, 5.2), (4.9, 5.0)], (5.0, 5.0))
    assert w == pytest.approx([0.9608, 0.9950], abs=1e-4)
    assert g == pytest.approx([5.047, 5.098], abs=1e-3)
    assert p1 == pytest.approx(0.9941, abs=1e-4)
    assert float(quality_weighted_statistic(0.9938, det, wa, 0.2, 0.2)) == pytest.approx(
        2.78, abs=0.02
    )


def test_case2_shadow_needs_printed_prior():
    det, w, wa, g, p1 = _case([(13.0, 7.0), (15.2, 7.4), (15.8, 6.9)], (13.1, 7.0))
    assert w == pytest.approx([0.9950, 0.1018, 0.0260], abs=1e-4)
    assert g == pytest.approx([13.264, 7.034], abs=1e-3)  # not the printed (13.55, 7.18)
    assert float(quality_weighted_statistic(0.8892, det, wa, 0.2, 0.2)) == pytest.approx(
        0.13, abs=0.02
    )
    assert float(quality_weighted_statistic(p1, det, wa, 0.2, 0.2)) == pytest.approx(
        1.075, abs=0.01
    )


def test_case3_false_detection_and_baseline():
    det, _, wa, _, p1 = _case([(7.3, 5.1), (7.1, 6.3), None], (4.9, 3.4))
    assert p1 == pytest.approx(0.0114, abs=1e-4)
    assert float(quality_weighted_statistic(p1, det, wa, 0.2, 0.2)) == pytest.approx(
        -6.101, abs=0.02
    )
    # C13: without prior or quality the false detection is accepted: log10(4) = 0.602 (text: 0.4)
    assert chair_varshney(0.5, det, 0.2, 0.2) == pytest.approx(math.log10(4.0))


def test_logit_term_and_bad_input():
    y1 = quality_weighted_statistic(0.5, [True], [0.5], 0.2, 0.2, quality_term="logit")
    assert float(y1) == pytest.approx(math.log10(4))
    with pytest.raises(ConfigError, match="quality_term"):
        quality_weighted_statistic(0.5, [True], [0.5], 0.2, 0.2, quality_term="ln")
    with pytest.raises(ConfigError, match="p_miss"):
        chair_varshney(0.5, [True], 0.0, 0.2)
    with pytest.raises(ShapeError):
        quality_weighted_statistic(0.5, [True, False], [0.5], 0.2, 0.2)


def test_sequence_recovers_miss_and_rejects_far_false_alarm():
    hs = [np.eye(3), np.array([[2.0, 0, 1], [0, 2, 0], [0, 0, 1]])]
    u = to_image(hs[1], np.array([3.0, 4.0]))
    assert to_ground(hs[1], u) == pytest.approx([3.0, 4.0])
    f = DetectionFusion(hs)
    belief = f.initial_belief()

    def frame(dets):
        nonlocal belief
        belief = f.update(f.predict(belief, 1.0), frame_measurements(0.0, dets, f.camera_ids))
        return belief.decision

    first = frame([np.array([1.0, 1.0]), to_image(hs[1], np.array([1.0, 1.0]))])
    assert first.real and belief.mean == pytest.approx([1.0, 1.0])
    d = frame([np.array([1.1, 1.0]), None])  # camera 2 misses: recovered
    assert d.real and d.local[1] is not None
    assert to_ground(hs[1], d.local[1]) == pytest.approx(d.fused)
    assert d.state == pytest.approx([1.1, 0.1, 1.0, 0.0])  # velocity from the previous frame
    d = frame([np.array([9.0, 9.0]), None])  # far from the prediction: false
    assert not d.real and all(v is None for v in d.local)
    assert np.all(np.isfinite(d.state))
    assert belief.mean == pytest.approx([1.2, 1.0])  # coasted on the prediction
    empty = frame([None, None])
    assert not empty.real and empty.statistic == -math.inf
    with pytest.raises(ShapeError):
        frame([None])
    with pytest.raises(ShapeError, match="sensor_id"):
        f.update(belief, [Measurement(0.0, "elsewhere", [1.0, 1.0])])


def test_ground_plane_detection_is_the_quality_kernel():
    from fusetrack.sensors.ground_plane_detection import GroundPlaneDetection

    h = np.array([[2.0, 0, 1], [0, 2, 0], [0, 0, 1]])
    cam = GroundPlaneDetection("c", h, sigma2=0.5)
    z = to_image(h, np.array([3.0, 4.0]))
    assert cam.ground(z) == pytest.approx([3.0, 4.0])
    x = np.array([[3.0, 4.0, 9.9], [4.0, 4.0, 0.0]])  # particles: only (x, y) count
    assert cam.log_likelihood(z, x) == pytest.approx([0.0, -1.0])
    assert cam.quality(z, x[1]) == pytest.approx(quality([[3.0, 4.0]], [4.0, 4.0], 0.5)[0])
