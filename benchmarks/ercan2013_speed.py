"""Speed of the Ercan et al. 2013 building blocks (issue 4, "Speed and scale").

* the occlusion-aware likelihood (Eqs. 6-9) for L particles, k cameras and M moving occluders
  with Gaussian priors, in the square room with its static occluder (default L = 1000, k = 8,
  M = 40), against the NumPy reference of the occlusion probabilities and pattern recursion;
* one greedy selection of k of the 12 cameras of the L-shaped room (default k = 6), including
  the moments (P{eta}, Sigma_Z, Sigma_Zx) from L predicted particles, for both metrics, and the
  brute-force search over all C(12, k) subsets for comparison.

    python benchmarks/ercan2013_speed.py [--particles 1000] [--cameras 8] [--occluders 40]
        [--select 6] [--exclusion 3.33] [--repeats 5] [--threads T] [--json] [--save | --out PATH]

``--exclusion``: Eq. 7's rectangles end this far before the particle in both the likelihood and
the selection (default one occluder diameter, what the experiments use; 0 = as printed).
``greedy_<model>_total_ms`` = moments + Algorithm 2: one selection epoch of the tracker.

Median wall time over ``--repeats`` calls after one warm-up call (Numba compile excluded); the
median CPU time of the same calls (``time.process_time``, all threads) in ``"cpu"``. BLAS and
Numba at their defaults (``--threads T``: T threads for both, ``_results.py``). fusetrack only
(its Numba kernels against its own NumPy references): no peer, no agreement check.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import _results
from fusetrack.experiments.ercan2013.scenes import l_scene, square_scene
from fusetrack.management.camera_selection import (
    brute_force_selection,
    greedy_selection,
    selection_moments,
)
from fusetrack.sensors.occlusion_aware_camera import OcclusionAwareLikelihood
from fusetrack.world.occlusion import (
    OccluderPriors,
    occlusion_probability_reference,
    pattern_probability_reference,
)

_CPU: dict[str, float] = {}  # the CPU seconds of the last timed() call


def timed(fn: Callable[[], object], repeats: int) -> float:
    """Median wall seconds of ``repeats`` calls after a warm-up; their median CPU seconds are
    left in ``_CPU["last"]``."""
    fn()
    both = _results.repeat(fn, repeats, stat="median")
    _CPU["last"] = both["cpu"]
    return both["wall"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--particles", type=int, default=1000)
    ap.add_argument("--cameras", type=int, default=8)
    ap.add_argument("--occluders", type=int, default=40)
    ap.add_argument("--select", type=int, default=6)
    ap.add_argument("--exclusion", type=float, default=3.33)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", action="store_true")
    _results.add_arguments(ap)
    a = ap.parse_args()
    (out,) = _results.measured(a, __file__, lambda: [measure(a)])
    if a.json:
        print(json.dumps(out))
    else:
        for k, v in out.items():
            print(f"{k:32s} {v:.3f}" if isinstance(v, float) else f"{k:32s} {v}")


def measure(a: argparse.Namespace) -> dict[str, object]:
    """Every timing of the module docstring: ``{key_ms: wall ms, ..., "cpu": {key_ms: cpu ms}}``."""
    cpu: dict[str, float] = {}
    rng = np.random.default_rng(0)

    sq = square_scene(True)
    cams = np.arange(min(a.cameras, len(sq.cameras)))
    truth = sq.room.sample_free(rng, 1)[0]
    x = truth + 2.0 * rng.standard_normal((a.particles, 2))
    pri = OccluderPriors(
        sq.room.sample_free(rng, a.occluders),
        np.broadcast_to(16.0 * np.eye(2), (a.occluders, 2, 2)),
    )
    lik = OcclusionAwareLikelihood(sq.cameras, sq.room, 3.33, "gaussian", exclusion=a.exclusion)
    z = sq.cameras.subset(cams).image_coordinate(truth[None, :])
    z[~lik.assigned(cams, truth[None, :])[:, 0]] = np.nan  # out of view or behind the block
    z[rng.random(len(cams)) < 0.4] = np.nan  # some cameras occluded
    possible = np.isfinite(lik.log_likelihood(z, cams, x, pri))
    if possible.mean() < 0.5:  # the readings must come from where the cloud is
        raise SystemExit(f"only {possible.mean():.0%} of the particles are possible")
    t_lik = timed(lambda: lik.log_likelihood(z, cams, x, pri), a.repeats)
    cpu["likelihood_ms"] = 1e3 * _CPU["last"]

    def reference() -> None:
        eta = np.isfinite(z)
        assigned = lik.assigned(cams, x)
        q = occlusion_probability_reference(sq.cameras.positions[cams], x, pri, 3.33, a.exclusion)
        pattern_probability_reference(q, eta, assigned)

    t_ref = timed(reference, max(1, a.repeats // 2))
    cpu["likelihood_numpy_reference_ms"] = 1e3 * _CPU["last"]

    ls = l_scene()
    centre = ls.room.sample_free(rng, 1)[0]
    xs = centre + 8.0 * rng.standard_normal((a.particles, 2))
    w = np.full(a.particles, 1.0 / a.particles)
    pri_l = OccluderPriors(
        ls.room.sample_free(rng, a.occluders),
        np.broadcast_to(60.0 * np.eye(2), (a.occluders, 2, 2)),
    )
    out: dict[str, object] = {
        "particles": a.particles,
        "cameras": len(cams),
        "occluders": a.occluders,
        "select": a.select,
        "exclusion": a.exclusion,
        "likelihood_ms": 1e3 * t_lik,
        "possible_particles": float(possible.mean()),
        "likelihood_numpy_reference_ms": 1e3 * t_ref,
    }
    for model in ("perspective", "weak"):
        mom_t = timed(
            lambda m=model: selection_moments(
                ls.cameras, ls.room, xs, w, pri_l, 3.33, "gaussian", (m,), a.exclusion
            ),
            a.repeats,
        )
        mom = selection_moments(
            ls.cameras, ls.room, xs, w, pri_l, 3.33, "gaussian", (model,), a.exclusion
        )
        out[f"moments_{model}_ms"] = 1e3 * mom_t
        cpu[f"moments_{model}_ms"] = 1e3 * _CPU["last"]
        out[f"greedy_{model}_ms"] = 1e3 * timed(
            lambda m=model, mm=mom: greedy_selection(mm, a.select, m), a.repeats
        )
        cpu[f"greedy_{model}_ms"] = 1e3 * _CPU["last"]
        out[f"greedy_{model}_total_ms"] = out[f"moments_{model}_ms"] + out[f"greedy_{model}_ms"]  # type: ignore[operator]
        cpu[f"greedy_{model}_total_ms"] = cpu[f"moments_{model}_ms"] + cpu[f"greedy_{model}_ms"]
        out[f"brute_{model}_ms"] = 1e3 * timed(
            lambda m=model, mm=mom: brute_force_selection(mm, a.select, m), a.repeats
        )
        cpu[f"brute_{model}_ms"] = 1e3 * _CPU["last"]
    out["cpu"] = cpu
    return out


if __name__ == "__main__":
    main()
