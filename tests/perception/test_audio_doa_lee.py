"""Azimuth and polar angle from simulated sound (pyroomacoustics) are close to the true angles."""

import math

import numpy as np
import pytest

from fusetrack.core.errors import ConfigError
from fusetrack.perception.audio_doa import AudioDoaArray
from fusetrack.sensors.doa_projection import direction_angles

pytest.importorskip("pyroomacoustics")


def test_free_field_music_recovers_angles():
    arr = AudioDoaArray(snr_db=20.0)
    rng = np.random.default_rng(3)
    for p in ([3.0, 3.0, 1.0], [-2.0, 4.0, -1.5]):
        z = arr.estimate(np.array(p), rng)
        th, ph = direction_angles(np.array(p))
        d_az = (z[0] - float(th) + math.pi) % (2 * math.pi) - math.pi
        assert abs(math.degrees(d_az)) < 2.0
        assert abs(math.degrees(z[1] - float(ph))) < 2.0
    with pytest.raises(ConfigError):
        AudioDoaArray(algorithm="beamformer")
