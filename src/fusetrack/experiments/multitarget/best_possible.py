"""The best possible beside a multi-target table (issue 19, item 3): the oracle floor of
:mod:`.gospa_floor` and the clairvoyant filter of :mod:`.clairvoyant`, against every tracker,
in ``multitarget-bearings`` and ``multitarget-benchmark`` (each a :class:`Layout`).

Everything is compared in m² as the mean over runs of each run's ``mean_t d_t^2`` (a tracker's
localisation + missed + false, the floor's Eq. (2) summed), paired by run: a claim holds when
the mean over runs of ``tracker - floor`` is above ``-MARGIN_SE`` standard errors. Trackers are
held to the *whole-run* floor (their confirmations, MHT's and MCMCDA's decisions use later
scans), the clairvoyant filter, which sees the reports up to each scan only, to the *online* one.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import MARGIN_SE, Claim, gospa_over_time, mean_with_se
from ...filters import UnscentedKalmanFilter
from .claims import claim
from .clairvoyant import bearing_draw, clairvoyant_tracks
from .gospa_floor import Oracle, Path, bearing_oracle, entry_prior_cov, run_floors, states
from .methods import METHODS
from .scenario import Array, Scene, Truth
from .scoring import estimate_sets

ARRAYS = (2, 3)
NEAR = 1.5
"""``multitarget-bearings``: the clairvoyant filter comes within this factor of the online floor
(else the floor is too low to be called the best possible)."""


@dataclass(frozen=True)
class Layout:
    """Where an experiment's results frame keeps what :func:`best_table` and :func:`best_claims`
    compare, and the words its report uses for them."""

    by: str  # the column of the table's groups ("arrays", "scenario")
    groups: tuple[Any, ...]
    unit: str  # appended to a group in labels (" arrays", "")
    method: str  # the column of the trackers' names
    methods: tuple[str, ...]
    near: float  # the clairvoyant filter within this factor of the online floor
    knows: str  # what the oracle knows, in the claim's words
    clairvoyant: str  # the clairvoyant filter, in the claim's words
    row: str  # its row in the table
    datum: str  # one report ("bearing")
    later: str  # who uses later scans, in the text's words

    def label(self, group: Any) -> str:
        return f"{group}{self.unit}"

    @property
    def every_group(self) -> str:
        names = [str(g) for g in self.groups]
        return f"{', '.join(names[:-1])} and {names[-1]}{self.unit}"


BEARINGS = Layout(
    by="arrays",
    groups=ARRAYS,
    unit=" arrays",
    method="method",
    methods=METHODS,
    near=NEAR,
    knows="known association and number of targets, straight paths",
    clairvoyant="one UKF per target on its own bearings",
    row="clairvoyant UKF, own bearings",
    datum="bearing",
    later="trackers confirm and MCMCDA decides with later scans",
)


def best_possible_columns(
    scene: Scene, truth: Truth, c: float, duration: float, rng: np.random.Generator
) -> dict[str, float]:
    """One run of ``multitarget-bearings``: its floors and the clairvoyant filter's
    ``mean_t d_t^2`` (m²)."""
    n = truth.positions.shape[1]
    priors = list(entry_prior_cov(scene, n, float(duration)))
    paths = [states(truth.positions[:, i], scene.dt) for i in range(n)]
    oracle = bearing_oracle(scene)
    ukf = UnscentedKalmanFilter(oracle.motion, list(oracle.sensors))
    return floor_columns(oracle, ukf, paths, truth, c, priors, bearing_draw(scene), rng)


def floor_columns(
    oracle: Oracle,
    kf: Any,
    paths: Sequence[Path],
    truth: Truth,
    c: float,
    priors: Sequence[Array],
    draw: Any,
    rng: np.random.Generator,
) -> dict[str, float]:
    """One run's floors (:func:`.gospa_floor.run_floors`) and the ``mean_t d_t^2`` (m²) of the
    clairvoyant filter ``kf`` on the reports ``draw`` makes (:mod:`.clairvoyant`)."""
    floors = run_floors(oracle, paths, truth.times.size, c, priors)
    tracks = clairvoyant_tracks(kf, paths, truth.times, oracle.dt, priors, draw, rng)
    est = estimate_sets(tracks, truth.times)
    g = gospa_over_time(est, [truth.positions[k] for k in range(truth.times.size)], c=c)
    return {
        "floor_online": floors["online"],
        "floor_whole_run": floors["whole_run"],
        "clairvoyant": g.run_distance**2,
    }


def _per_run(df: pd.DataFrame, layout: Layout, group: Any, method: str) -> pd.DataFrame:
    """One row per run of one method in one group: its ``mean_t d_t^2`` and the run's floors."""
    d = df[(df[layout.by] == group) & (df[layout.method] == method)]
    return d.assign(mean_square=d["localisation"] + d["missed"] + d["false"])


def _fmt(values: pd.Series) -> str:
    mu, se = mean_with_se(values)
    return f"{mu:.3f}" + (f" ± {se:.3f}" if np.isfinite(se) else "")


def best_table(df: pd.DataFrame, layout: Layout = BEARINGS) -> pd.DataFrame:
    """``mean_t d_t^2`` (m², mean ± s.e. over runs): the floors, the clairvoyant filter and every
    tracker, with each one's ratio to the whole-run floor, per group."""
    rows: dict[str, dict[str, str]] = {}
    for n in layout.groups:
        first = _per_run(df, layout, n, layout.methods[0])
        floor = first["floor_whole_run"].mean()
        entries = {
            "oracle floor, whole run": first["floor_whole_run"],
            "oracle floor, online": first["floor_online"],
            layout.row: first["clairvoyant"],
            **{m: _per_run(df, layout, n, m)["mean_square"] for m in layout.methods},
        }
        for label, v in entries.items():
            rows.setdefault(label, {})[f"{layout.label(n)} (m²)"] = _fmt(v)
            rows[label][f"{layout.label(n)} / whole-run floor"] = f"{v.mean() / floor:.1f}"
    return pd.DataFrame.from_dict(rows, orient="index")


def _above(diff: pd.Series) -> bool:
    mu, se = mean_with_se(diff)
    return bool(mu >= -MARGIN_SE * (se if np.isfinite(se) else 0.0))


def best_claims(df: pd.DataFrame, layout: Layout = BEARINGS) -> list[Claim]:
    """Every tracker above the whole-run floor; the clairvoyant filter between the online floor
    and ``layout.near`` times it."""
    ratios: dict[str, float] = {}
    ok = True
    for n in layout.groups:
        for m in layout.methods:
            d = _per_run(df, layout, n, m)
            ratio = float(d["mean_square"].mean() / d["floor_whole_run"].mean())
            ratios[f"{m} {layout.label(n)}"] = round(ratio, 3)
            ok &= _above(d["mean_square"] - d["floor_whole_run"])
    clair: dict[str, float] = {}
    near = True
    for n in layout.groups:
        d = _per_run(df, layout, n, layout.methods[0])
        r = float(d["clairvoyant"].mean() / d["floor_online"].mean())
        clair[layout.label(n)] = round(r, 3)
        near &= _above(d["clairvoyant"] - d["floor_online"]) and r <= layout.near
    return [
        claim(
            "diagnostic",
            "BP_trackers_above_floor",
            "every tracker's mean GOSPA² (localisation + missed + false) is not below the oracle's "
            f"whole-run floor ({layout.knows}; "
            "gospa_floor Eq. 2); ours: mean GOSPA² / floor",
            "not in any paper",
            ratios,
            f"tracker - floor >= -{MARGIN_SE:g} s.e. (paired by run), {layout.every_group}",
            ok,
        ),
        claim(
            "diagnostic",
            "BP_clairvoyant_attains_floor",
            f"a clairvoyant filter ({layout.clairvoyant}) is not below the "
            f"online floor and within {layout.near:g} times it; ours: its mean GOSPA² / online floor",
            "not in any paper",
            clair,
            f"clairvoyant - floor >= -{MARGIN_SE:g} s.e. and ratio <= {layout.near:g}, "
            f"{layout.every_group}",
            near,
        ),
    ]


BEARING_ORACLE = """The oracle knows how many targets there are, which bearing is whose and which are clutter, and
that the paths are straight: its bound on each target's position is the Cramér-Rao bound of that
target's own bearings (P_D as an information reduction factor, the model's entry spread as its
prior; `multitarget/gospa_floor.py`)."""
BEARING_DATA = (
    "each target's own labelled bearings, no\nclutter, no merging, drawn on the run's paths"
)


def best_text(
    df: pd.DataFrame,
    claims: Sequence[Claim],
    c: float,
    layout: Layout = BEARINGS,
    oracle: str = BEARING_ORACLE,
    data: str = BEARING_DATA,
    unbounded: str = "",
) -> str:
    """The report's "Best possible" section: ``oracle`` (what it knows, its bound), the floor,
    the clairvoyant filter's ``data``, the table, the verdict and ``unbounded`` (what has no
    bound, and why)."""
    verdict = "; ".join(f"`{k.id}` {'holds' if k.holds else '**fails**'}" for k in claims)
    near = {k.id: k.holds for k in claims}.get("BP_clairvoyant_attains_floor", False)
    reading = (
        "The clairvoyant filter comes close to the online floor (the floor is nearly attainable); "
        if near
        else "The clairvoyant filter is not within the claim's factor of the online floor; "
    ) + (
        f"the gap between it and the best tracker is the price of not knowing which {layout.datum} "
        "is whose (and which are clutter)."
    )
    return f"""## Best possible (what no tracker can beat on this model)

{oracle} Any estimate set has `d_t² >= Σ_i min(D_i², c²/2) + (c²/2)
max(m - n, 0)` (`D_i`: target i's distance to its nearest estimate), and for errors at least as
wide as the bound (centred Gaussian, covariance at least `B`; not so where two targets come
within a few bound-σ of each other and one's nearest estimate is the other's)
`E min(D_i², c²/2) >= tr B - ((tr B)² + 2 tr B²) / (2c²)` (c = {c:g} m): the
floor on the mean over scans of GOSPA² (m², all of it localisation for the oracle). It bounds the
sum localisation + missed + false of the table above, a mean over runs of means over scans, not
the `gospa` column (a mean of per-run roots can lie below the root of a mean). *Whole run*: from
every {layout.datum} of the run ({layout.later}); *online*: up to
each scan. The clairvoyant filter runs the oracle's data ({data}). Mean ± s.e. over runs:

{best_table(df, layout).to_markdown()}

{verdict}. {reading}
{unbounded}"""


__all__ = [
    "BEARINGS",
    "Layout",
    "best_claims",
    "best_possible_columns",
    "best_table",
    "best_text",
    "floor_columns",
]
