"""Kushwaha 2010, Ch. III "Evaluation" (Figs 10–11): DOA error of one beamformer node against range.

The paper put one node outdoors and played recorded speech at 3–150 ft and at −180° … +180° in
5° steps (1800 experiments); Fig. 11 shows the mean DOA error per distance, smallest at 25 ft:
closer, the planar-wavefront assumption fails; farther, the SNR drops. No error values are
printed. Here a speech-like source (:func:`fusetrack.world.acoustics.speech_like`) at mouth
height 1.6 m is propagated with exact spherical delays to the 4-microphone array on its 1 m
tripod, with background noise at 40 dB SNR at 1 m (spec 003 §3.1) and a ground reflection
(coefficient 0.5) — the outdoor multipath the paper names. The DOA estimate is the beam of
largest energy (36 beams, 2^14 samples at 100 kHz).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pandas as pd

from ...evaluation import (
    Claim,
    ClaimKinds,
    Outcome,
    RunContext,
    interval_values,
    paired_interval,
    plots,
    shown_positive,
)
from ...perception import Beamformer, MicrophoneArray, beam_angles
from ...world import pink_noise, propagate, speech_like

FEET = 0.3048
DISTANCES_FT = (3, 5, 10, 25, 50, 75, 100, 150)
MIC_HEIGHT = 1.0
MOUTH_HEIGHT = 1.6
FS = 100e3


def beam_energies(
    distance: float,
    angle: float,
    rng: np.random.Generator,
    snr_1m_db: float = 40.0,
    reflection: float = 0.5,
) -> np.ndarray:
    """The 36 beam energies of one trial (the node's detection function; Fig. 10b)."""
    array = MicrophoneArray.rectangle()
    bf = Beamformer(array, alpha=0.0)
    n = bf.window + bf.preroll
    mics = np.column_stack([array.world_positions((0.0, 0.0), 0.0), np.full(4, MIC_HEIGHT)])
    src = np.array([distance * np.cos(angle), distance * np.sin(angle), MOUTH_HEIGHT])
    image = src * np.array([1.0, 1.0, -1.0])  # ground reflection (image source below the ground)
    emission = speech_like(n / FS + 0.3, rng)
    times = 0.25 + np.arange(n) / FS
    x = propagate(emission, lambda t: np.broadcast_to(src, (t.size, 3)), mics, times, FS)
    x += reflection * propagate(
        emission, lambda t: np.broadcast_to(image, (t.size, 3)), mics, times, FS
    )
    x += 10 ** (-snr_1m_db / 20) * pink_noise(x.shape, rng)
    return bf.energies(x)


def doa_trial(
    distance: float,
    angle: float,
    rng: np.random.Generator,
    snr_1m_db: float = 40.0,
    reflection: float = 0.5,
) -> float:
    """Absolute DOA error (rad) of one trial: a source at ``distance`` m and ``angle`` rad."""
    est = beam_angles()[int(np.argmax(beam_energies(distance, angle, rng, snr_1m_db, reflection)))]
    return float(abs((est - angle + np.pi) % (2 * np.pi) - np.pi))


def beam_grid_floor(angle: float) -> float:
    """Absolute error (rad) of the beam nearest to ``angle``: what no estimate restricted to the
    36 beams can beat on that trial (the best possible of Fig. 11's estimator)."""
    gaps = np.abs((beam_angles() - angle + np.pi) % (2 * np.pi) - np.pi)
    return float(gaps.min())


def realtime_factor(
    nodes: int = 6, repeats: int = 3, clock: Callable[[], float] | None = None
) -> float:
    """Seconds of processing per second of audio for ``nodes`` nodes (band-pass + 36 beams over
    contiguous 2^14-sample windows; best of ``repeats``), by ``clock`` (default
    ``time.perf_counter``; ``time.process_time`` for CPU seconds)."""
    import time

    rng = np.random.default_rng(0)
    bfs = [Beamformer() for _ in range(nodes)]
    x = rng.standard_normal((4, bfs[0].window + bfs[0].preroll))
    tick = time.perf_counter if clock is None else clock
    best = np.inf
    for _ in range(repeats):
        tic = tick()
        for bf in bfs:
            bf.process(x)
        best = min(best, tick() - tic)
    return float(best * FS / bfs[0].window)


def run_once(config: Mapping[str, Any], seed: int) -> list[dict[str, Any]]:
    rng = np.random.default_rng(seed)
    step = float(config["angle_step_deg"])
    rows = []
    for d_ft in DISTANCES_FT:
        for a_deg in np.arange(-180.0, 180.0, step):
            a = np.deg2rad(a_deg + rng.uniform(-0.5, 0.5) * step)
            rows.append(
                {
                    "distance_ft": d_ft,
                    "angle_deg": float(np.rad2deg(a)),
                    "error_deg": np.rad2deg(doa_trial(d_ft * FEET, a, rng)),
                    "floor_deg": np.rad2deg(beam_grid_floor(a)),
                }
            )
    return rows


# Each claim's kind (fusetrack.evaluation.KINDS), by id or fnmatch pattern, first match.
CLAIM_KINDS = ClaimKinds(
    {
        "faster_than_realtime": "beyond",  # our CPU against the paper's FPGA
        "min_error_mid_range": "paper",
        "error_grows_far": "paper",
        "error_grows_near": "paper",
        "within_one_beam": "paper",
        "BP_*": "diagnostic",  # against the beam grid's floor (issue 19 item 3)
    }
)


def _grows_claim(df: pd.DataFrame, claim_id: str, d_ft: int, mid_ft: int, where: str) -> Claim:
    """err(d_ft) > err(best mid range), judged on paired trials (same run, same nominal angle):
    the 95 % t-interval of the paired difference must lie above 0 (a bare ``>`` held by 0.1°)."""
    trials = df.assign(trial=df.groupby(["run", "distance_ft"]).cumcount())
    piv = trials.pivot_table(index=["run", "trial"], columns="distance_ft", values="error_deg")
    gap = paired_interval(piv[d_ft], piv[mid_ft])
    return CLAIM_KINDS.claim(
        claim_id,
        f"the error grows {where} ({d_ft} ft worse than the best mid range, {mid_ft} ft)",
        f"err({d_ft} ft) > err(mid)",
        {
            f"{d_ft} ft": float(piv[d_ft].mean()),
            "best mid": float(piv[mid_ft].mean()),
            "paired gap (mean, 95% half-width)": interval_values(gap),
        },
        "95% paired t-interval of the gap above 0",
        shown_positive(gap),
    )


def run(ctx: RunContext) -> Outcome:
    runs = ctx.n_runs(full=3, quick=1)  # repeats of the whole distance × angle sweep
    step = 30.0 if ctx.quick else 5.0
    df = ctx.monte_carlo(run_once, [{"angle_step_deg": step}], runs, desc="sweeps")
    mean = df.groupby("distance_ft")["error_deg"].mean()
    best = int(mean.idxmin())
    mid_ft = int(mean.loc[[10, 25, 50]].idxmin())
    mid = float(mean.loc[mid_ft])
    floor = df.groupby("distance_ft")["floor_deg"].mean()
    nearest = (df["error_deg"] - df["floor_deg"] < 1e-9).groupby(df["distance_ft"]).mean()
    claims = [
        CLAIM_KINDS.claim(
            "min_error_mid_range",
            "the mean DOA error is smallest at mid range (paper: 25 ft)",
            25,
            best,
            "10–50 ft",
            best in (10, 25, 50),
        ),
        _grows_claim(df, "error_grows_far", 150, mid_ft, "at long range as the SNR falls"),
        _grows_claim(df, "error_grows_near", 3, mid_ft, "close to the array"),
        CLAIM_KINDS.claim(
            "within_one_beam",
            "at mid range the mean error is within the 10° beam spacing",
            "< 10°",
            mid,
            "10°",
            mid < 10.0,
        ),
    ]
    excess = mean - floor
    best_excess = int(excess.idxmin())
    claims.append(
        CLAIM_KINDS.claim(
            "BP_min_above_floor_mid_range",
            "the mean error above the beam grid's floor (the part range can change; the floor "
            "varies with the trials' jittered angles) is smallest at mid range",
            25,
            {"distance (ft)": best_excess, "above floor (deg)": float(excess.loc[best_excess])},
            "10–50 ft",
            best_excess in (10, 25, 50),
        )
    )
    claims.append(
        CLAIM_KINDS.claim(
            "BP_nearest_beam_mid_range",
            f"at mid range ({mid_ft} ft) the beamformer picks the beam nearest to the source in at "
            "least 90 % of the trials, i.e. its mean error is the beam grid's floor",
            "no value (Fig. 11 shows only the curve)",
            {
                "nearest beam (share)": float(nearest.loc[mid_ft]),
                "mean error (deg)": mid,
                "grid floor (deg)": float(floor.loc[mid_ft]),
            },
            ">= 0.9 of the trials",
            bool(nearest.loc[mid_ft] >= 0.9),
        )
    )
    rt = realtime_factor()
    pattern = beam_energies(50 * FEET, np.deg2rad(120.0), np.random.default_rng(ctx.seed))
    fig_beam = _polar(ctx, pattern)
    claims.append(
        CLAIM_KINDS.claim(
            "faster_than_realtime",
            "six nodes' four channels at 100 kHz are beamformed faster than real time",
            "FPGA: 2^14 samples in ≈ 160 ms",
            rt,
            "< 1 s of processing per s of audio",
            rt < 1.0,
        )
    )
    fig = plots.plot_series(
        ctx.figure_path("doa_error_vs_range"),
        np.array(mean.index),
        {"mean |DOA error|": mean.to_numpy()},
        xlabel="distance (ft)",
        ylabel="mean DOA error (deg)",
        title="DOA error against range (Fig. 11 analogue)",
    )
    trials = len(df)
    body = f"""
## Set-up

{trials} trials: {len(DISTANCES_FT)} distances ({", ".join(map(str, DISTANCES_FT))} ft) × angles from −180° in {step:.0f}° steps
(jittered within the step) × {runs} repeat(s); the paper: 1800 trials at 3–150 ft, 5° steps.
Speech-like source at 1.6 m height, array at 1 m, ground reflection 0.5, 40 dB SNR at 1 m.

## Mean DOA error per distance

{_error_table(df, mean, floor, nearest).to_markdown(floatfmt=".2f")}

The paper prints no values for Fig. 11, only that 25 ft was best and why. **Best possible**: the
estimate is one of 36 beams 10° apart, so no trial's error can be below the distance from the
source to the nearest beam; "grid floor" is the mean of that distance over the same trials (2.5°
for angles spread uniformly between beams), "nearest beam" the share of trials whose estimate is
that beam, and "above floor" the part of the error that range can change.

![DOA error against range]({fig.name})

![Beam energies, source at 50 ft and 120°]({fig_beam.name})

Speed: beamforming six nodes (4 channels at 100 kHz each) takes {rt:.3f} s per second of audio
on this machine (the FPGA needs ≈ 160 ms per 2^14-sample window, i.e. it runs in real time).

## Differences from the paper and their causes

Beyond about 10 ft our mean error sits at the floor set by 10° beams (the table's grid floor),
so where along 10–150 ft the minimum falls is decided by noise of a few hundredths of a degree; the simulated SNR at 150 ft, integrated over 2^14 samples, is still
high, so the far-range growth the paper saw outdoors is weak here. Our errors are what quantisation to 10° beams, the 10 cm aperture, the noise and the ground
reflection leave. Close to the array the source is 0.6 m above it, so at 3 ft the wave arrives
steeply from above and the horizontal delays shrink (the far-field, coplanar assumption fails
as in the paper); at 150 ft the SNR is {40 - 20 * np.log10(150 * FEET):.0f} dB per microphone. Real speech, wind and
reverberation of the paper's outdoor site are not modelled.
"""
    return Outcome(df, claims, body, runs)


def _error_table(
    df: pd.DataFrame, mean: pd.Series, floor: pd.Series, nearest: pd.Series
) -> pd.DataFrame:
    """Per distance: mean error, the beam grid's floor, the error above it, the share of trials
    at the nearest beam, and the trial count."""
    return pd.DataFrame(
        {
            "mean error (deg)": mean,
            "grid floor (deg)": floor,
            "above floor (deg)": mean - floor,
            "nearest beam (%)": 100 * nearest,
            "trials": df.groupby("distance_ft").size(),
        }
    )


def _polar(ctx: RunContext, energies: np.ndarray) -> Any:
    """Fig. 10b analogue: the beam energies of a source at 50 ft and 120°."""
    a = np.append(beam_angles(), 2 * np.pi)
    e = np.append(energies, energies[0])
    fig, ax = plots.panel(size=(4.5, 4.5), projection="polar")
    ax.plot(a, e / e.max(), "o-", ms=3, label="beam energy (normalised)")
    ax.plot([np.deg2rad(120.0)] * 2, [0, 1], "k--", lw=1, label="true direction 120°")
    plots.legend(ax, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.08))
    ax.set_title("Beamform, source at 50 ft and 120° (Fig. 10b analogue)", fontsize=9)
    return plots.save(fig, ctx.figure_path("beamform_50ft_120deg"))
