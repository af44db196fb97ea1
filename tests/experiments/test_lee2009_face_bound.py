"""lee2009-face-matching's best possible: the Bayes-optimal identification of a synthetic face
and the exact accuracy of walking-direction rules, against hand-computed cases and brute force."""

import math

import numpy as np
import pytest
from scipy.special import logsumexp
from scipy.stats import norm

from fusetrack.core import ConfigError
from fusetrack.experiments.lee2009 import face_bound as fb
from fusetrack.perception import (
    CAMERA_VIEWS,
    COMPASS,
    apparent_motion,
    synthetic_face,
    walking_direction,
)

SIZE = 40


def test_hair_masks_cover_the_head_and_sum_to_one():
    edges, skin, hair = fb.hair_masks(SIZE)
    probs = fb.mask_probabilities(edges)
    assert probs.sum() == pytest.approx(1.0) and np.all(probs > 0)
    head = skin | hair
    assert np.all(head == head[0]) and not np.any(skin & hair)
    assert np.all(np.diff(hair.sum(axis=(1, 2))) >= 0)  # the hair grows towards the back
    assert skin[-1].sum() == 0  # from the back the hair covers the head
    # the mask of one interval is synthetic_face's own drawing at any view inside it
    view = (0.5 * (edges[3] + edges[4]) - fb.HAIR_LINE[0]) / 1.5 * math.pi
    img = synthetic_face(
        view, (0.0, 0.0, 0.0), (1.0, 1.0, 1.0), np.random.default_rng(0), SIZE, 0.0
    )
    assert np.array_equal(np.all(img == 1.0, axis=-1), hair[3])


def test_mask_probabilities_of_a_window():
    """Views in [0, pi/8]: hair lines in [-0.6, -0.4125], each interval's share of that."""
    edges, _, _ = fb.hair_masks(SIZE)
    p = fb.mask_probabilities(edges, (0.0, math.pi / 8))
    assert p.sum() == pytest.approx(1.0)
    top = -0.6 + 1.5 / 8
    assert np.all(p[edges[:-1] >= top] == 0.0)
    assert p[0] == pytest.approx((min(edges[1], top) + 0.6) / (top + 0.6))
    with pytest.raises(ConfigError, match="window"):
        fb.mask_probabilities(edges, (1.0, 0.5))


def test_clipped_gaussian_loglik_by_hand():
    ll = fb.clipped_gaussian_loglik(
        np.array([0.5, 0.0, 1.0, 0.7]), np.array([0.5, 0.0, 1.0, 0.5]), 1.0
    )
    expected = [-0.5 * math.log(2 * math.pi), math.log(0.5), math.log(0.5)]
    expected.append(-0.5 * 0.04 - 0.5 * math.log(2 * math.pi))
    np.testing.assert_allclose(ll, expected)


def test_pixel_logliks_equal_the_elementwise_sum():
    rng = np.random.default_rng(1)
    px = np.clip(rng.uniform(-0.1, 1.1, (500, 3)), 0, 1)  # about a tenth of the channels clipped
    colours = rng.uniform(0, 1, (4, 3))
    brute = fb.clipped_gaussian_loglik(px[None], colours[:, None, :], 0.05).sum(-1)
    np.testing.assert_allclose(fb.pixel_logliks(px, colours, 0.05), brute, rtol=1e-10)


def test_oracle_likelihood_matches_brute_force_integration():
    """``log p(image | person)`` against the average over 4,001 views of the likelihood of
    ``synthetic_face``'s own noiseless drawing: the second person looks like the first (dark
    hair, some channels clipped at 0), so for both the true view's mask dominates, and its
    share, 3.4 %, is known on the grid to 1 %."""
    rng = np.random.default_rng(2)
    people = [((0.85, 0.65, 0.5), (0.12, 0.09, 0.06)), ((0.8, 0.6, 0.45), (0.1, 0.07, 0.05))]
    oracle = fb.FaceOracle(people, 0.03)
    img = synthetic_face(1.1, *people[0], rng)
    views = np.linspace(0, math.pi, 4001)
    for k, (skin, hair) in enumerate(people):
        ll = [
            fb.clipped_gaussian_loglik(
                img, synthetic_face(v, skin, hair, rng, SIZE, 0.0), 0.03
            ).sum()
            for v in views
        ]
        brute = logsumexp(ll) - math.log(len(views))
        assert oracle.log_likelihoods(img)[k] == pytest.approx(brute, abs=0.02)


def test_oracle_accuracy_by_hand():
    """Two people alike but for ``delta`` in the red of the skin (mid-range colours: no
    clipping). The hair tells the mask, so the Bayes error is that of two Gaussians on the mask's
    ``n`` skin pixels: ``sum_masks P(mask) Phi(-sqrt(n) delta / (2 sigma))`` (0.5 from the back,
    where no skin shows). 3,000 queries, view unknown."""
    sigma, delta = 0.03, 0.003
    people = [((0.5, 0.4, 0.3), (0.1, 0.2, 0.9)), ((0.5 + delta, 0.4, 0.3), (0.1, 0.2, 0.9))]
    edges, skin, _ = fb.hair_masks(SIZE)
    n = skin.sum(axis=(1, 2))
    exact = 1 - np.sum(fb.mask_probabilities(edges) * norm.cdf(-np.sqrt(n) * delta / (2 * sigma)))
    oracle = fb.FaceOracle(people, sigma)
    rng = np.random.default_rng(4)
    hits = []
    for _ in range(3000):
        who = int(rng.integers(2))
        img = synthetic_face(rng.uniform(0, math.pi), *people[who], rng, SIZE, sigma)
        hits.append(oracle.classify(img) == who)
    se = math.sqrt(exact * (1 - exact) / len(hits))
    assert 0.75 < exact < 0.95
    assert abs(np.mean(hits) - exact) <= 3 * se


def test_direction_accuracy_by_hand():
    """No flips: 1. Flip 1/2: the signs say nothing, only the zeros (never flipped) do: they
    tell {N, S}, {E, W} or a diagonal, so the Bayes accuracy is 2/8 (1/2) + 2/8 (1/2) + 4/8
    (1/4) = 0.375. A rule that always says N: 1/8 at any flip."""
    assert fb.direction_accuracy(None, 0.0) == pytest.approx(1.0)
    assert fb.direction_accuracy(walking_direction, 0.0) == pytest.approx(1.0)
    assert fb.direction_accuracy(None, 0.5) == pytest.approx(0.375)
    assert fb.direction_accuracy(lambda obs: "N", 0.1) == pytest.approx(1 / 8)
    with pytest.raises(ConfigError, match="flip"):
        fb.direction_accuracy(None, 1.5)


def test_bayes_beats_every_rule_and_matches_a_simulation():
    """The Bayes accuracy is at least any rule's (the sign vote, a rule that ignores camera 5);
    the sign vote's exact accuracy at flip 0.2 agrees with 8,000 simulated draws."""
    flip = 0.2
    bayes = fb.direction_accuracy(None, flip)

    def without_5(obs):
        return walking_direction({c: o for c, o in obs.items() if c != "5"})

    for rule in (walking_direction, without_5, lambda obs: fb.bayes_direction(obs, flip)):
        assert fb.direction_accuracy(rule, flip) <= bayes + 1e-12
    assert fb.direction_accuracy(without_5, flip) < bayes - 0.01
    rng = np.random.default_rng(5)
    hits = 0
    names = list(COMPASS)
    for _ in range(8_000):
        true = names[int(rng.integers(8))]
        obs = {}
        for cam, view in CAMERA_VIEWS.items():
            lat, size = apparent_motion(view, COMPASS[true])
            obs[cam] = (
                -lat if rng.random() < flip else lat,
                -size if rng.random() < flip else size,
            )
        hits += walking_direction(obs) == true
    exact = fb.direction_accuracy(walking_direction, flip)
    assert abs(hits / 8_000 - exact) <= 3 * math.sqrt(exact * (1 - exact) / 8_000)
