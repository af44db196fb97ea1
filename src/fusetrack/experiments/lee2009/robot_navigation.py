"""Lee 2009, Sec. 5.2.2: potential-field navigation, the aligned-obstacle collision (CAROG), its fix and escape (C15)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import Claim, ClaimKinds, Outcome, RunContext, plots
from ...world import NavigationResult, PotentialField, navigate
from .navigation_bound import min_steps, shortest_path_length

PAPER_FORCES = {(12.0, 12.0): -8.46, (10.0, 10.0): -5.34, (9.0, 9.0): -1.21}
VARIANT_START = (12.0, 12.0)
"""The robot's start in every variant (:func:`~fusetrack.world.navigate`'s default)."""


VARIANTS: dict[str, dict[str, Any]] = {
    "standard field": {},
    "modified (Eq. 5.24)": {"modified": True},
    "modified + escape": {"modified": True, "escape": True},
    "modified + escape, r_r = r_o = 0.3": {
        "modified": True,
        "escape": True,
        "r_robot": 0.3,
        "r_obstacle": 0.3,
    },
    "standard, r_r = r_o = 0.3": {"r_robot": 0.3, "r_obstacle": 0.3},
}


def run(ctx: RunContext) -> Outcome:
    """E5 (C15): the field's forces, the paths of every variant, claims, figures, text."""
    fld = PotentialField()
    u = np.array([1.0, 1.0]) / math.sqrt(2.0)
    forces = {p: float(fld.total(np.array(p)) @ u) for p in PAPER_FORCES}
    delta = fld.zero_force_distance()
    results = {name: navigate(fld, **kw) for name, kw in VARIANTS.items()}
    best = _best_possible(fld, results)
    claims = [*_claims(forces, delta, results), _best_claim(best)]
    fig526, figpath = _figures(ctx, fld, u, results)
    body = _report_text(forces, delta, results, fig526, figpath) + _best_text(best)
    return Outcome(pd.DataFrame(_path_rows(results)), claims, body, 1)


def _path_rows(results: Mapping[str, NavigationResult]) -> list[dict[str, Any]]:
    """One row per variant and step."""
    rows = []
    for name, res in results.items():
        for k, p in enumerate(res.path):
            rows.append(
                {
                    "variant": name,
                    "step": k,
                    "x": float(p[0]),
                    "y": float(p[1]),
                    "collided_at": res.collided_at,
                    "oscillation_at": res.oscillation_at,
                    "reached_goal_at": res.reached_goal_at,
                }
            )
    return rows


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "C15_*": "paper",
        "BP_*": "diagnostic",  # the best possible (issue 19): the shortest path's steps
    }
)


def _best_possible(fld: PotentialField, results: Mapping[str, NavigationResult]) -> pd.DataFrame:
    """Per variant that reaches the goal: its steps and path length beside the shortest path
    that keeps ``r_r + r_o`` from the obstacle and the fewest steps of ``s_r T_s`` along it
    (:mod:`.navigation_bound`)."""
    start = VARIANT_START
    rows = {}
    for name, res in results.items():
        if res.reached_goal_at is None:
            continue
        kw = VARIANTS[name]
        clearance = kw.get("r_robot", 0.0) + kw.get("r_obstacle", 0.0)
        shortest = shortest_path_length(start, fld.goal, fld.obstacle, clearance)
        rows[name] = {
            "steps to the goal": res.reached_goal_at,
            "fewest possible steps": min_steps(shortest, math.sqrt(2.0)),
            "path length": float(np.sum(np.hypot(*np.diff(res.path, axis=0).T))),
            "shortest path length": shortest,
        }
    int_columns = {"steps to the goal": int, "fewest possible steps": int}
    return pd.DataFrame.from_dict(rows, orient="index").astype(int_columns)


def _best_claim(best: pd.DataFrame) -> Claim:
    """Diagnostic: no variant reaches the goal in fewer steps, or along a shorter path, than the
    shortest path allows (fails only if a step is longer than s_r T_s or cuts the obstacle)."""
    ok = bool(
        len(best)
        and (best["steps to the goal"] >= best["fewest possible steps"]).all()
        and (best["path length"] >= best["shortest path length"] - 1e-9).all()
    )
    return CLAIM_KINDS.claim(
        "BP_goal_not_before_shortest_path",
        "the variants that reach the goal take no fewer steps (and no shorter path) than the "
        "shortest path clearing the obstacle by r_r + r_o allows; ours: steps / fewest",
        "not in the paper",
        {
            str(k): f"{int(r['steps to the goal'])} / {int(r['fewest possible steps'])}"
            for k, r in best.iterrows()
        },
        "steps >= fewest and length >= shortest",
        ok,
    )


def _claims(
    forces: Mapping[tuple[float, float], float],
    delta: float,
    results: Mapping[str, NavigationResult],
) -> list[Claim]:
    """C15: forces, zero-force distance, collision, oscillation, escape."""
    std, mod, esc, esc3 = (results[k] for k in list(VARIANTS)[:4])
    return [
        CLAIM_KINDS.claim(
            "C15_forces",
            "signed total force along the diagonal at (12,12), (10,10), (9,9)",
            list(PAPER_FORCES.values()),
            [round(v, 3) for v in forces.values()],
            "+-0.01",
            all(abs(forces[p] - v) <= 0.01 for p, v in PAPER_FORCES.items()),
        ),
        CLAIM_KINDS.claim(
            "C15_delta",
            "zero-force distance delta from the obstacle (text: 1.27, from the rounded 8.9)",
            1.27,
            round(delta, 4),
            "< s_r T_s = 1.414",
            delta < math.sqrt(2),
        ),
        CLAIM_KINDS.claim(
            "C15_collision_step4",
            "standard field: the robot passes (11,11), (10,10), (9,9) and collides at step 4",
            4,
            std.collided_at,
            "== 4",
            std.collided_at == 4,
        ),
        CLAIM_KINDS.claim(
            "C15_modified_oscillates",
            "modified field (Eq. 5.24): no collision, (9,9) <-> (10,10) oscillation detected by Eq. 5.26",
            "oscillation, no collision",
            {
                "collided": mod.collided_at,
                "oscillation_step": mod.oscillation_at,
                "visits": sorted({tuple(p) for p in mod.path.round(6).tolist()})[:3],
            },
            "oscillation detected, no collision",
            mod.collided_at is None and mod.oscillation_at is not None,
        ),
        CLAIM_KINDS.claim(
            "C15_escape_reaches_goal",
            "escape (heading turned by theta_osc) reaches the goal without collision (r = 0 and r = 0.3)",
            "escape",
            {"r=0": esc.reached_goal_at, "r=0.3": esc3.reached_goal_at},
            "goal reached, no collision",
            esc.reached_goal_at is not None
            and esc.collided_at is None
            and esc3.reached_goal_at is not None
            and esc3.collided_at is None,
        ),
    ]


def _outcome(res: NavigationResult) -> str:
    """How a navigation ended, for a panel title: collision, oscillation or goal, at which step."""
    if res.collided_at is not None:
        return f"collides at step {res.collided_at}"
    if res.reached_goal_at is not None:
        return f"goal at step {res.reached_goal_at}"
    if res.oscillation_at is not None:
        return f"oscillates from step {res.oscillation_at}"
    return f"no goal in {len(res.path) - 1} steps"


def _figures(
    ctx: RunContext, fld: PotentialField, u: np.ndarray, results: Mapping[str, NavigationResult]
) -> tuple[Path, Path]:
    """Fig. 5-26 (force profile on the diagonal) and the robot paths."""
    # Fig 5-26: force profile on the diagonal
    t = np.linspace(2, 14, 481)
    prof = np.array(
        [[fld.attractive(np.array([a, a])) @ u, fld.repulsive(np.array([a, a])) @ u] for a in t]
    )
    fig, axs = plots.panels(3, size=(13, 3.6))
    for ax, y, name in zip(
        axs, (prof[:, 0], prof[:, 1], prof.sum(1)), ("(a) attractive", "(b) repulsive", "(c) total")
    ):
        plots.curve(ax, t, np.clip(y, -20, 20), index=0, label="force, clipped to +-20")
        plots.reference_line(ax, 0.0, "zero", linestyle="-", lw=0.6)
        plots.label_axes(ax, "position on the diagonal x = y (field units)",
                         "signed force along the diagonal", f"Fig. 5-26 {name}")  # fmt: skip
    plots.legend(axs[0], fontsize=7)
    fig526 = plots.save(fig, ctx.figure_path("fig5_26_force_profile"))
    # one panel per variant: the paths run on the same grid points and would hide one another
    cols = 3
    rows = -(-len(results) // cols)
    fig, grid = plots.figure(rows, cols, size=(3.6 * cols, 3.9 * rows), sharex=True, sharey=True)
    axs = grid.ravel()
    plots.hide_unused(axs, len(results))
    for k, (ax, (name, res)) in enumerate(zip(axs, results.items())):
        plots.draw_paths(ax, [res.path], labels=["path"], start=k, mark_start=True)
        ax.plot(*fld.obstacle, "ks", ms=9, label="obstacle")
        ax.plot(*fld.goal, "g*", ms=13, label="goal")
        ax.set_aspect("equal")
        plots.label_axes(ax, "x (field units)", "y (field units)" if k % cols == 0 else "",
                         f"{name}\n{_outcome(res)}")  # fmt: skip
        ax.title.set_fontsize(8)
    plots.legend(axs[0], fontsize=7)
    fig.suptitle("Robot paths from (12, 12) (Figs. 5-25, 5-28, 5-29)")
    figpath = plots.save(fig, ctx.figure_path("robot_paths"))
    return fig526, figpath


def _report_text(
    forces: Mapping[tuple[float, float], float],
    delta: float,
    results: Mapping[str, NavigationResult],
    fig526: Path,
    figpath: Path,
) -> str:
    """The report body."""
    ev = "\n".join(f"* **{name}**: " + "; ".join(res.events) for name, res in results.items())
    return f"""
## The example (p_r = (12, 12), p_o = (8, 8), p_g = (6, 6), s_r T_s = sqrt 2, rho_0 = 10, c_att = 0.5, c_rep = 5, m = n = 2)

Signed total force along the diagonal (negative = towards the origin): paper {list(PAPER_FORCES.values())},
ours {[round(v, 3) for v in forces.values()]}. Zero-force point at distance delta = {delta:.4f} from the
obstacle (the text prints 1.27, i.e. sqrt 2 x 0.9 from the rounded 8.9; the exact value is {delta:.3f}), below
the step sqrt 2, so the aligned robot steps onto the obstacle.

{ev}

![force profile]({fig526.name})

![paths]({figpath.name})

The escape step is not fully specified in the text (its step 3, Fig. 5-29): we turn the last heading
anticlockwise by theta_osc = the top of the applicable range (pi/2 when the robot is within
s_r T_s + r_r + r_o of the obstacle, Eq. 5.30 with arcsin for the printed csc) for one step and then
follow the field again.
"""


def _best_text(best: pd.DataFrame) -> str:
    """The report's best-possible section."""
    gap = "; ".join(
        f"{name}: {int(r['steps to the goal'])} steps where {int(r['fewest possible steps'])} "
        "might do"
        for name, r in best.iterrows()
    )
    return f"""
## The best possible

No Cramér-Rao bound applies here: the example estimates nothing. The field is evaluated at the
robot's exact position, with no sensor and no noise, and every number above (forces, delta,
the collision step) is computed exactly and compared exactly; there is no error to bound and no
paper number that a model's noise could make impossible. What the escape does have is a best
possible: no planner moving at most s_r T_s = sqrt 2 per step reaches the goal in fewer steps
than the shortest path from (12, 12) to (6, 6) that keeps the robot's centre r_r + r_o from the
obstacle's allows (straight, or tangent, arc, tangent; `navigation_bound`; with r = 0 the
infimum is the straight line, which a path may approach but not follow).

{best.to_markdown(floatfmt=("", ".0f", ".0f", ".3f", ".3f"))}

`BP_goal_not_before_shortest_path` holds unless a step is longer than s_r T_s or cuts the
obstacle. Its 90° turn takes the robot off the diagonal before the field brings it back: {gap}.
The paper gives no step count to judge.
"""
