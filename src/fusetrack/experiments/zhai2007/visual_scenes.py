"""The synthetic sequences that stand in for Zhai 2007's private videos (spec 001, Sec. 7).

Each scene follows the thesis's description of its sequence (frame counts, manoeuvre timeline,
occlusions, scale change, camera motion, target size and contrast); the numbers that the thesis
does not give (speeds in px/frame, positions, clutter density) are our choices, fixed here and
quoted in the report. ``build(name, rng)`` is a pure function of the generator.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...core import ConfigError, invalid
from ...world import Actor, RenderedSequence, Scene, Sprite, keyframe_trajectory, render

HEAD = Sprite()  # 14 x 18 px semi-axes, skin with a dark hair cap
JITTER = 0.03  # px/frame^2 random acceleration on every scripted path


def lab(rng: np.random.Generator) -> RenderedSequence:
    """E9 (Sec. 3.6.1, Figs 35-36): a person walking in a highly cluttered lab, 50 frames; the
    first 20 nearly rectilinear, accelerations from about frame 25 with clutter around the head."""
    truth = keyframe_trajectory(
        [60, 120, 3.0, 0.0],
        [
            (0, 3, 0),
            (22, 3, 0),
            (27, 6, -2.5),
            (32, 1, 2.5),
            (38, 5, 1.5),
            (44, 1.5, -2),
            (49, 3, 0),
        ],
        50,
        rng,
        JITTER,
    )
    scene = Scene(clutter=70, clutter_box=(150, 60, 260, 180), clutter_local=40)
    return render(scene, Actor(HEAD, truth), rng)


def office(rng: np.random.Generator) -> RenderedSequence:
    """E10 / E14 (case 1, Sec. 3.6.2, Figs 37-42; Sec. 4.3, Figs 48-49): a head in an office,
    100 frames, four manoeuvres: frames 11-15 acceleration with a heading change; 30-40
    decelerates and stops; from 55 a sudden dramatic move left, waving back in 70-80 (large
    positive acceleration); a sudden stop near 85."""
    truth = keyframe_trajectory(
        [100, 120, 2.0, 0.5],
        [
            (0, 2, 0.5),
            (10, 2, 0.5),
            (15, 3.5, -1.5),
            (30, 3.5, -1.5),
            (40, 0, 0),
            (55, 0, 0),
            (58, -9, 0),
            (70, -9, 0),
            (76, 8, 0),
            (84, 8, 0),
            (86, 0, 0),
        ],
        100,
        rng,
        JITTER,
    )
    return render(Scene(clutter=60), Actor(HEAD, truth), rng)


def crossing(rng: np.random.Generator) -> RenderedSequence:
    """E11 (case 2, Sec. 3.6.3, Figs 43-44): two people, one tracked, 115 frames: still for ~10
    frames, moves left with acceleration then deceleration and comes back; the other person
    passes in front (partial occlusions) in frames 20-27 and 80-90."""
    truth = keyframe_trajectory(
        [230, 120, 0.0, 0.0],
        [
            (0, 0, 0),
            (10, 0, 0),
            (18, -4, 0),
            (40, -4, 0),
            (50, 0, 0),
            (60, 0, 0),
            (70, 4, 0),
            (95, 4, 0),
            (105, 0, 0),
        ],
        115,
        rng,
        JITTER,
    )
    other = Sprite(colour=(205, 150, 120), hair=(40, 30, 25))
    k1, k2 = 23, 85
    p1 = truth[k1, :2] + [0.0, 18.0]
    p2 = truth[k2, :2] + [0.0, -16.0]
    a = keyframe_trajectory([p1[0] - 6.0 * k1, p1[1], 6.0, 0.0], [], 115)
    b = keyframe_trajectory([p2[0] + 5.0 * k2, p2[1], -5.0, 0.0], [], 115)
    return render(
        Scene(clutter=50),
        Actor(HEAD, truth),
        rng,
        [Actor(other, a, in_front=True), Actor(other, b, in_front=True)],
    )


def football(rng: np.random.Generator) -> RenderedSequence:
    """E12 (case 3, Sec. 3.6.4): a football player, 78 frames: clutter, occlusions by other
    players, scale change and strong camera ego-motion (the background pans)."""
    n = 78
    world = keyframe_trajectory(
        [90, 130, 3.0, -1.0],
        [(0, 3, -1), (15, 6, 0), (25, 2, 2), (40, 5, -2), (55, 1, 1), (65, 4, 0), (77, 2, -1)],
        n,
        rng,
        JITTER,
    )
    # the camera follows the player (80 % of its motion) and shakes (a smoothed random walk)
    shake = np.cumsum(np.cumsum(rng.normal(0.0, 0.35, (n, 2)), axis=0), axis=0)
    ego = 0.8 * (world[:, :2] - world[0, :2]) + np.clip(shake, -40, 40)
    truth = world.copy()
    truth[:, :2] -= ego
    truth[:, 2:] -= np.gradient(ego, axis=0)
    scale = np.interp(np.arange(n), [0, 30, 55, 77], [1.0, 1.35, 1.15, 1.25])
    player = Sprite(colour=(205, 160, 130), hair=(30, 30, 30))
    others = []
    for k, dy in ((20, 10.0), (50, -12.0)):
        p = truth[k, :2] + [0.0, dy]
        v = -4.0 if k == 20 else 4.0
        others.append(
            Actor(player, keyframe_trajectory([p[0] - v * k, p[1], v, 0.0], [], n), in_front=True)
        )
    return render(
        Scene(clutter=160, ego_motion=ego, margin=300), Actor(HEAD, truth, scale), rng, others
    )


SMALL = Sprite(
    axes=(5.0, 8.0), colour=(150, 130, 115), hair=(95, 85, 75), hair_fraction=0.3, texture=10.0
)


def group(rng: np.random.Generator) -> RenderedSequence:
    """E18 case 1 (Sec. 5.4.3, Figs 74-75): a group of people outdoors, 120 frames; the target
    fits a 16 x 10 px window, has little colour contrast and lots of edge clutter; similar
    people walk nearby (one passes it around frame 70)."""
    n = 120
    truth = keyframe_trajectory(
        [70, 130, 1.0, 0.0],
        [(0, 1, 0), (30, 1.2, -0.5), (50, 0.5, 0.5), (80, 1.5, 0), (100, 1.0, -0.8)],
        n,
        rng,
        JITTER,
    )
    k = 70
    p = truth[k, :2] + [0.0, 4.0]
    others = [
        Actor(SMALL, keyframe_trajectory([p[0] + 1.2 * k, p[1], -1.2, 0.0], [], n)),
        Actor(SMALL, keyframe_trajectory([60, 175, 1.1, -0.1], [], n, rng, JITTER)),
        Actor(SMALL, keyframe_trajectory([260, 90, -0.8, 0.2], [], n, rng, JITTER)),
    ]
    return render(Scene(clutter=110, contrast=0.6), Actor(SMALL, truth), rng, others)


def vehicle(rng: np.random.Generator) -> RenderedSequence:
    """E18 case 2 (Figs 76): an outdoor vehicle with distinctive colour and a large scale change
    (approaching: twice as large at the end), 80 frames."""
    n = 80
    truth = keyframe_trajectory(
        [60, 150, 2.5, -0.8], [(0, 2.5, -0.8), (40, 2.0, -0.2), (79, 1.5, 0.3)], n, rng, JITTER
    )
    car = Sprite(axes=(12.0, 8.0), colour=(200, 30, 30), hair=None, texture=12.0)
    scale = np.linspace(1.0, 2.0, n)
    return render(Scene(clutter=60), Actor(car, truth, scale), rng)


def indoor(rng: np.random.Generator) -> RenderedSequence:
    """E18 case 3 (Fig 77): indoors, complicated motion, good illumination, no big scale change,
    120 frames."""
    truth = keyframe_trajectory(
        [80, 100, 2.0, 1.0],
        [
            (0, 2, 1),
            (15, 3, -2),
            (30, -1, -2),
            (45, -3, 2),
            (60, 2, 3),
            (75, 4, -1),
            (90, -2, -2),
            (105, 1, 1),
            (119, 2, 0),
        ],
        120,
        rng,
        JITTER,
    )
    return render(Scene(clutter=50), Actor(HEAD, truth), rng)


def noisy_grey(rng: np.random.Generator) -> RenderedSequence:
    """E21 (App. B demo): a noisy grey-level sequence (``NoisyFrameData.mat`` is not provided):
    QCIF 144 x 176, a small textured head moving at ~2 px/frame with gentle turns, heavy noise."""
    truth = keyframe_trajectory(
        [63, 69, -2.0, -1.0],
        [(0, -2, -1), (20, 1, -2), (40, 2, 1), (60, 0, 2), (80, -2, 0), (99, -1, -1)],
        100,
        rng,
        JITTER,
    )
    truth[:, :2] += [40.0, 20.0]
    small = Sprite(axes=(6.0, 8.0), colour=(230, 200, 180), hair=(50, 40, 30), texture=25.0)
    return render(Scene(height=144, width=176, clutter=25, noise=20.0), Actor(small, truth), rng)


SCENES: dict[str, Callable[[np.random.Generator], RenderedSequence]] = {
    "lab": lab,
    "office": office,
    "crossing": crossing,
    "football": football,
    "group": group,
    "vehicle": vehicle,
    "indoor": indoor,
    "noisy_grey": noisy_grey,
}


def build(name: str, rng: np.random.Generator) -> RenderedSequence:
    if name not in SCENES:
        raise ConfigError(invalid("scene", name, f"one of {sorted(SCENES)}"))
    return SCENES[name](rng)
