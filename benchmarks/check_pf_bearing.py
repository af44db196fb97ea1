"""Do the four implementations of ``pf_bearing.py`` compute the same filter? (no timing)

For each library, ``--runs`` independent runs (seeds 0..runs-1) at ``--N`` particles on the fixed
scenario. Prints, per library, the mean position RMSE against the truth with its standard error,
and the RMS distance of the estimates from a reference posterior mean (plain NumPy with
``--ref-N`` particles). Same filter => same mean RMSE within a few standard errors, and the same
distance to the reference (which shrinks like 1/sqrt(N) for all of them).

    python benchmarks/check_pf_bearing.py [--N 1000] [--runs 20] [--libs ...] [--ref-N 1000000]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _scenario import make_scenario, position_rmse
from pf_bearing import LIBS, RUNNERS, NumpyPF


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--N", type=int, default=1000)
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--steps", type=int, default=100)
    ap.add_argument("--libs", nargs="+", default=list(LIBS), choices=LIBS)
    ap.add_argument("--ref-N", type=int, default=1_000_000)
    args = ap.parse_args(argv)

    scn = make_scenario(steps=args.steps)
    truth = scn.truth[1:, :2]
    ref = NumpyPF(scn, args.ref_N).run(123_456, args.steps)
    print(f"reference (numpy, N={args.ref_N:,}): RMSE {position_rmse(ref, truth):.4f} m")
    print(f"N = {args.N:,}, {args.runs} runs each")
    print(
        f"  {'library':<10} {'mean RMSE (m)':>14} {'+- s.e.':>8} {'RMS dist. to reference (m)':>27}"
    )
    for lib in args.libs:
        runner = RUNNERS[lib](scn, args.N)
        rmses, dists = [], []
        for seed in range(args.runs):
            est = runner.run(seed, args.steps)  # type: ignore[attr-defined]
            if hasattr(runner, "cleanup"):
                runner.cleanup()  # type: ignore[attr-defined]
            rmses.append(position_rmse(est, truth))
            dists.append(position_rmse(est, ref))
        r = np.array(rmses)
        se = r.std(ddof=1) / np.sqrt(len(r)) if len(r) > 1 else float("nan")
        print(
            f"  {lib:<10} {r.mean():>14.4f} {se:>8.4f} {np.sqrt(np.mean(np.square(dists))):>27.4f}",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
