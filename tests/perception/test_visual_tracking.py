"""Particle filters over frames: condensation, MMPF-SP and the App. B loop on a clean sequence."""

import numpy as np
import pytest

from fusetrack.core import Gaussian
from fusetrack.filters.multiple_model import MultipleModelParticleFilter
from fusetrack.filters.sis import ProposalParticleFilter
from fusetrack.motion.langevin import Langevin
from fusetrack.perception.visual_edges import EllipseEdgeSensor, edge_map
from fusetrack.perception.visual_tracking import PrecomputedMeasurements, lost_frames, track_frames
from fusetrack.world.head_video import Actor, Scene, Sprite, keyframe_trajectory, render


def test_lost_frames_by_hand():
    err = np.array([1, 9, 9, 9, 9, 1, 9, 9, 9, 9, 9, 1.0])
    assert lost_frames(err, 5.0) == (True, 6)
    assert lost_frames(err, 5.0, frames=6) == (False, -1)
    assert lost_frames(err, np.full(12, 10.0)) == (False, -1)


def _sequence():
    tr = keyframe_trajectory([40, 45, 2.0, 0.5], [(0, 2, 0.5), (8, 3, -1), (15, 0, 0)], 20)
    seq = render(
        Scene(height=90, width=120, clutter=10, noise=3.0),
        Actor(Sprite(), tr),
        np.random.default_rng(0),
    )
    sensor = EllipseEdgeSensor("head", 90, 120, seq.sprite.axes)
    return (
        seq,
        sensor,
        PrecomputedMeasurements([[sensor.measurement(edge_map(f))] for f in seq.frames]),
    )


def test_condensation_follows_a_clean_head():
    seq, sensor, fe = _sequence()
    pf = ProposalParticleFilter(Langevin(), [sensor], None, 150)
    tk = track_frames(
        pf,
        Gaussian(seq.truth[0], np.diag([4, 4, 1, 1.0])),
        seq.frames,
        fe,
        np.random.default_rng(1),
    )
    err = np.hypot(*(tk.means[:, :2] - seq.truth[:, :2]).T)
    assert tk.means.shape == (20, 4)
    assert np.sqrt(np.mean(err**2)) < 2.0


def test_mmpf_sp_with_the_edge_sensor():
    from fusetrack.experiments.zhai2007.visual import PI_B, _prior6, mm_models

    seq, sensor, fe = _sequence()
    mm = MultipleModelParticleFilter(
        mm_models(), PI_B, [sensor], 100, proposal="sp-pekf", n_channels=5
    )
    prior = _prior6(Gaussian(seq.truth[0], np.diag([4, 4, 1, 1.0])))
    tk = track_frames(mm, prior, seq.frames, fe, np.random.default_rng(2))
    err = np.hypot(*(tk.means[:, :2] - seq.truth[:, :2]).T)
    assert tk.means.shape == (20, 6)
    assert np.sqrt(np.mean(err**2)) < 2.0
    assert tk.info["degenerate_steps"] == 0


def test_gaussian_and_unscented_proposal_trackers_follow_a_clean_head():
    """The beyond-the-paper comparators on the edge sensor: an IMM-EKF (MMPF models) through
    track_frames as a plain Filter and the UPF (UKF proposal on the centre pseudo-measurement)."""
    from fusetrack.experiments.zhai2007.visual import PI_B, _prior6, mm_models
    from fusetrack.filters.imm import InteractingMultipleModel
    from fusetrack.filters.unscented_proposal import UnscentedProposal

    seq, sensor, fe = _sequence()
    prior = Gaussian(seq.truth[0], np.diag([4, 4, 1, 1.0]))
    imm = InteractingMultipleModel(mm_models(), PI_B, [sensor])
    start = imm.initialize(_prior6(prior))
    tk = track_frames(imm, start, seq.frames, fe, np.random.default_rng(3), sensor_ids=["head"])
    err = np.hypot(*(tk.means[:, :2] - seq.truth[:, :2]).T)
    assert tk.means.shape == (20, 6)
    assert np.sqrt(np.mean(err**2)) < 2.0
    _, _, fe2 = _sequence()
    upf = ProposalParticleFilter(Langevin(), [sensor], UnscentedProposal(), 100)
    tk = track_frames(upf, prior, seq.frames, fe2, np.random.default_rng(4))
    err = np.hypot(*(tk.means[:, :2] - seq.truth[:, :2]).T)
    assert np.sqrt(np.mean(err**2)) < 2.0


def test_sensor_ids_default_to_the_filters_and_the_track_is_the_library_track():
    from fusetrack.core import Track
    from fusetrack.core.errors import ConfigError
    from fusetrack.filters.kalman import ExtendedKalmanFilter

    seq, sensor, fe = _sequence()
    ekf = ExtendedKalmanFilter(Langevin(), [sensor])
    prior = Gaussian(seq.truth[0], np.diag([4, 4, 1, 1.0]))
    with pytest.raises(ConfigError, match="sensor_ids"):
        track_frames(object(), prior, seq.frames, fe, np.random.default_rng(0))  # type: ignore[arg-type]
    default = track_frames(ekf, prior, seq.frames, fe, np.random.default_rng(0))
    tk = track_frames(
        ekf, prior, seq.frames, _sequence()[2], np.random.default_rng(0), sensor_ids=["head"]
    )
    np.testing.assert_array_equal(default.means, tk.means)
    assert isinstance(tk, Track) and len(tk) == 20 and tk.info["seconds"] > 0
    np.testing.assert_array_equal(tk.times, np.arange(20.0))
    np.testing.assert_array_equal(tk.means[0], seq.truth[0])
