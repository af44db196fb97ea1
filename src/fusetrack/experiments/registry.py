"""The experiment registry and the one way every experiment is run.

An experiment is a module with ``run(ctx: RunContext) -> Outcome``. The registry maps a name to
``module:function`` so that ``fusetrack list`` does not import every experiment. The experiment's
options are a pydantic model in the same module, named by :class:`ExperimentInfo` (``None``: it
takes no options, and checking that needs no import); :func:`run_experiment` validates
``ctx.extra`` against it before any work and hands the experiment ``ctx.options``.
"""

from __future__ import annotations

import importlib
import time
from dataclasses import dataclass
from typing import Any

from ..core import ConfigError, UnknownExperimentError
from ..evaluation import (
    ClaimKinds,
    ExperimentOptions,
    Outcome,
    RunContext,
    parse_options,
    peak_memory_mb,
    write_outputs,
)


@dataclass(frozen=True)
class ExperimentInfo:
    name: str
    target: str  # "module:function", relative to fusetrack.experiments
    title: str
    paper: str
    options: str | None = None  # its options model (a class in the target module), if any


REGISTRY: dict[str, ExperimentInfo] = {
    info.name: info
    for info in [
        ExperimentInfo(
            "demo",
            "demo:run",
            "Demo: one manoeuvring target, two microphone arrays, a camera and a radio tag; "
            "EKF, UKF and particle filter against the posterior CRLB",
            "fusetrack",
        ),
        ExperimentInfo(
            "zhai2007-scalar",
            "zhai2007.scalar:run",
            "Zhai 2007 E1 (Tables 2-3): EKF, bootstrap and PF-SP-PEKF on the scalar benchmark",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-mcmc",
            "zhai2007.mcmc:run",
            "Zhai 2007 E19 (Table 15): particle filters with MH, random-walk and independence moves",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-multiple-model",
            "zhai2007.multiple_model:run",
            "Zhai 2007 E5-E8 (Figs 25-30): regime transitions, turn models, MM-bootstrap, multi-sensor MMPF",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-bearings",
            "zhai2007.bearings:run",
            "Zhai 2007 E2-E3 (Figs 10-12): bearings-only EKF, bootstrap and PF-SP-PEKF",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-galerkin",
            "zhai2007.galerkin:run",
            "Zhai 2007 E13 (Table 9, Figs 45-47): Galerkin-projection PF vs bootstrap, bearings-only",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-discretisation",
            "zhai2007.discretisation:run",
            "Zhai 2007 E15-E17 (Figs 50-72): discretisation PF and discretisation MMPF",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-sensor-network",
            "zhai2007.sensor_network:run",
            "Zhai 2007 E4 (Table 5, Figs 15-24): CPF-SP vs centralised bootstrap on an acoustic sensor network",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "zhai2007-denoising",
            "zhai2007.denoising:run",
            "Zhai 2007 E20 (Figs 79-80): PF-DWT denoising of Gaussian + Cauchy noise, ISNR",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "lee2009-projected-planes",
            "lee2009.projected_planes:run",
            "Lee 2009 Ch. 2: 3-D acoustic tracking on projected planes (PPS) vs direct 3-D, with CRLB",
            "Lee 2009 (seed 000)",
            options="Options",
        ),
        ExperimentInfo(
            "nott2009-simulation",
            "nott2009.simulation:run",
            "Nott 2009, Figs. 5.1-5.4: camera + radio tag EKF in simulation (S1-S4), occlusion "
            "sweep, irregular tag rates, tag clock offsets",
            "Nott 2009 (M.S. thesis, Univ. of Kentucky)",
        ),
        ExperimentInfo(
            "nott2009-radio-accuracy",
            "nott2009.radio:run",
            "Nott 2009, Table 5.1: radio tag accuracy at six test points, and the simulated tag "
            "tuned to it",
            "Nott 2009 (M.S. thesis, Univ. of Kentucky)",
        ),
        ExperimentInfo(
            "nott2009-video",
            "nott2009.video:run",
            "Nott 2009, Sec. 5.2: the whole chain on rendered video (homographies, background "
            "subtraction, occlusion detection, joint tracking through occlusions)",
            "Nott 2009 (M.S. thesis, Univ. of Kentucky)",
        ),
        ExperimentInfo(
            "lee2009-detection-fusion",
            "lee2009.detection_fusion:run",
            "Lee 2009 Ch. 4: quality-weighted camera detection fusion with a dynamic prior",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "lee2009-robot-navigation",
            "lee2009.robot_navigation:run",
            "Lee 2009 Sec. 5.2.2: potential-field robot navigation, aligned-obstacle collision, fix and escape",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "kushwaha2010-sbe",
            "kushwaha2010.sbe:run",
            "Kushwaha 2010 Ch. III (Figs 17-22): grid SBE, eight audio/video fusion approaches on simulated vehicle passes",
            "Kushwaha 2010 Ch. III (seed 003)",
        ),
        ExperimentInfo(
            "ercan2013-occlusion-probability",
            "ercan2013.occlusion_probability:run",
            "Ercan 2013 E0 (App. C, Fig. 17): Eq. 7 occlusion probability against Monte Carlo; p(eta|u) sums to one",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-cameras",
            "ercan2013.cameras:run",
            "Ercan 2013 E1 (Figs. 5-6): tracker RMSE vs number of cameras for three occluder-prior accuracies",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-cameras-sigma-v",
            "ercan2013.cameras_sigma_v:run",
            "Ercan 2013 E1 (Figs. 5-6) along the tracker's unstated motion noise sigma_v: C3 judged at sigma_v = 1 and 2",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-prior-accuracy",
            "ercan2013.prior_accuracy:run",
            "Ercan 2013 E2 (Fig. 7): tracker RMSE vs occluder-prior RMSE; the 2.34x and 1.94x gains, the 3.72 crossing",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-prior-calibration",
            "ercan2013.prior_calibration:run",
            "Ercan 2013, beyond the paper: why Gaussian occluder priors lose to none (overconfident vs persistent errors)",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-tradeoff",
            "ercan2013.tradeoff:run",
            "Ercan 2013 E3 (Fig. 8): cameras vs occluder-prior accuracy needed for RMSE_tr = 3",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-occluders",
            "ercan2013.occluders:run",
            "Ercan 2013 E4 (Fig. 9): tracker RMSE vs number of moving occluders, perfect vs no priors",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-likelihood-cost",
            "ercan2013.likelihood_cost:run",
            "Ercan 2013 E5 (Fig. 10): CPU time of the occlusion-aware likelihood vs number of cameras",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
        ),
        ExperimentInfo(
            "ercan2013-selection",
            "ercan2013.selection:run",
            "Ercan 2013 E6 (Figs. 11-12): greedy, brute-force and heuristic camera selection in the L-shaped room",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
            options="Options",
        ),
        ExperimentInfo(
            "ercan2013-lab",
            "ercan2013.lab:run",
            "Ercan 2013 E7-E8 (Figs. 13-15): lab replica, fixed subsets vs prior accuracy and selection methods",
            "Ercan, El Gamal, Guibas 2013 (seed 002)",
            options="Options",
        ),
        ExperimentInfo(
            "kushwaha2010-mcmcda",
            "kushwaha2010.mcmcda:run",
            "Kushwaha 2010 Ch. III (Tables 8-9, Figs 24-25): online MCMCDA on fused-likelihood peaks, single vehicles",
            "Kushwaha 2010 Ch. III (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-crossing",
            "kushwaha2010.crossing:run",
            "Kushwaha 2010 Ch. III (Fig. 26): three vehicles, two crossing, video-only MCMCDA",
            "Kushwaha 2010 Ch. III (seed 003)",
        ),
        ExperimentInfo(
            "lee2009-camera-triggering",
            "lee2009.camera_triggering:run",
            "Lee 2009 Ch. 3: acoustic multi-object tracking with periodic or triggered camera cooperation",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "kushwaha2010-beamformer",
            "kushwaha2010.beamformer:run",
            "Kushwaha 2010 Ch. III (Fig. 11): beamformer DOA error against range, speech-like source",
            "Kushwaha 2010 Ch. III (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-timesync",
            "kushwaha2010.timesync:run",
            "Kushwaha 2010 Ch. III: residual time-synchronisation error and tracking error against injected clock offsets",
            "Kushwaha 2010 Ch. III (seed 003)",
        ),
        ExperimentInfo(
            "lee2009-rfid-camera",
            "lee2009.rfid_camera:run",
            "Lee 2009 Sec. 5.2.3: RFID virtual sensors refined by two cameras",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "lee2009-face-matching",
            "lee2009.face_matching:run",
            "Lee 2009 Sec. 5.2.1: multi-view colour-histogram face matching and walking direction",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "lee2009-network-traffic",
            "lee2009.network_traffic:run",
            "Lee 2009 Sec. 5.2.3: network delay of router-based vs server-based visual compensation",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "lee2009-projected-planes-audio",
            "lee2009.projected_planes_audio:run",
            "Beyond Lee 2009 Ch. 2: PPS on azimuth/polar angles estimated from simulated sound (MUSIC)",
            "Lee 2009 (seed 000)",
        ),
        ExperimentInfo(
            "zhai2007-visual",
            "zhai2007.visual:run",
            "Zhai 2007 E9-E12, E14, E18, E21: ellipse-edge, MMPF-SP, Galerkin and multi-cue visual "
            "trackers against condensation on synthetic head video",
            "Zhai 2007 (seed 001)",
        ),
        ExperimentInfo(
            "kushwaha2010-harmonic-sources",
            "kushwaha2010.harmonic_sources:run",
            "Kushwaha 2010 Ch. IV (Figs 29-32): several harmonic sources located from beamform and PSD "
            "features (ML fundamentals, Gibbs + slice-sampling MAP) against number, SNR, separation, "
            "harmonicity and directivity, with energy-based localisation",
            "Kushwaha 2010 Ch. IV (seed 003)",
            options="Options",
        ),
        ExperimentInfo(
            "kushwaha2010-cameras-a",
            "kushwaha2010.cameras:run_a",
            "Kushwaha 2010 Ch. V setup A (Figs 40-49): 3-D tracking with 4 smart cameras, trackers P and T0-T4",
            "Kushwaha 2010 Ch. V (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-cameras-b",
            "kushwaha2010.cameras:run_b",
            "Kushwaha 2010 Ch. V setup B (Figs 50-56): 10 cameras, small target, a one-camera gap",
            "Kushwaha 2010 Ch. V (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-cameras-area",
            "kushwaha2010.camera_area:run",
            "Kushwaha 2010 Ch. V conclusion (H19): T2 against T3 as the target's pixel share "
            "shrinks (setup A, target scaled), where they cross over",
            "Kushwaha 2010 Ch. V (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-cameras-gap",
            "kushwaha2010.camera_gap:run",
            "Kushwaha 2010 Ch. V setup B at QVGA (Fig. 53, H20): the target leaves all views but "
            "one for two steps; does T2 re-converge and T0 not?",
            "Kushwaha 2010 Ch. V (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-cameras-occlusion",
            "kushwaha2010.camera_occlusion:run",
            "Kushwaha 2010 Ch. V FGH #2 analogue (H24): an occluder crosses two cameras' views for "
            "five frames; T2 tracks on without re-initialisation?",
            "Kushwaha 2010 Ch. V (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-cameras-lcr",
            "kushwaha2010.camera_lcr:run",
            "Kushwaha 2010 Ch. V LCR analogue (Figs 57-60, A-V-18): a textured box carried through "
            "a 10 x 8 m room, 4 cameras, tracker T3 against its ellipsoid model (T2, T0 beside)",
            "Kushwaha 2010 Ch. V (seed 003)",
        ),
        ExperimentInfo(
            "kushwaha2010-outdoor-triangle",
            "kushwaha2010.outdoor_triangle:run",
            "Kushwaha 2010 Ch. IV outdoor experiment, simulated (Fig. 34b, H17): three nodes in a "
            "9.144 m triangle, two harmonic sources 0.5-8 m apart",
            "Kushwaha 2010 Ch. IV (seed 003)",
        ),
        ExperimentInfo(
            "lee2009-periodic-sweep",
            "lee2009.camera_triggering:run_sweep",
            "Lee 2009 E3.2 (Fig. 3-6): periodic camera cooperation, error against the camera period, 1,000 trials",
            "Lee 2009 (seed 000)",
            options="SweepOptions",
        ),
        ExperimentInfo(
            "multitarget-bearings",
            "multitarget.experiment:run",
            "Beyond the papers: several targets from unlabelled bearings of 2-3 arrays, ghost "
            "intersections; GNN/JPDA on triangulated points, MCMCDA, grid peaks, direct bearings",
            "fusetrack (issue 17; Kushwaha 2010 field, Lee 2009 bearings)",
            options="Options",
        ),
        ExperimentInfo(
            "multitarget-benchmark",
            "multitarget.benchmark:run",
            "Beyond the papers: GNN, JPDA, MHT, MCMCDA, GM-PHD and PMB on targets born and dying, "
            "position + range-bearing sensors, P_D 0.9, sparse/dense Poisson clutter, crossings; "
            "GOSPA, OSPA(2), CLEAR MOT, cardinality",
            "fusetrack (issue 17)",
            options="Options",
        ),
    ]
}


def describe(name: str) -> ExperimentInfo:
    try:
        return REGISTRY[name]
    except KeyError:
        raise UnknownExperimentError(
            f"experiment={name!r} is unknown: expected one of {sorted(REGISTRY)} (see `fusetrack list`)"
        ) from None


def _module(info: ExperimentInfo) -> Any:
    return importlib.import_module(f"{__package__}.{info.target.split(':')[0]}")


def options_model(name: str) -> type[ExperimentOptions]:
    """The pydantic model of experiment ``name``'s options (imports its module if it has one)."""
    info = describe(name)
    if info.options is None:
        return ExperimentOptions
    model = getattr(_module(info), info.options, None)
    if not (isinstance(model, type) and issubclass(model, ExperimentOptions)):
        raise TypeError(f"{info.target}: {info.options} is not an ExperimentOptions model")
    return model


def claim_kinds(name: str) -> ClaimKinds | None:
    """Experiment ``name``'s ``claim id -> kind`` table (``CLAIM_KINDS`` in its module), or
    ``None`` if its module keeps none (its claims then carry their kinds in ``summary.json``)."""
    kinds = getattr(_module(describe(name)), "CLAIM_KINDS", None)
    return kinds if isinstance(kinds, ClaimKinds) else None


def validate_options(name: str, raw: dict[str, Any]) -> ExperimentOptions:
    """``--set``/``--config`` values of experiment ``name`` validated against its options model;
    an unknown key or a bad value raises :class:`ConfigError` naming the valid keys or values."""
    try:
        return parse_options(options_model(name), raw)
    except ConfigError as err:
        raise ConfigError(f"{name}: {err}") from None


def run_experiment(ctx: RunContext) -> dict[str, Any]:
    """Validate the options of the experiment ``ctx.name`` and open its checkpoint (before any
    work), run it and write its three output files; return the summary."""
    info = describe(ctx.name)
    ctx.options = validate_options(ctx.name, ctx.extra)
    ctx.checkpoint()  # a file at the checkpoint's name that fusetrack did not write: refused now
    fn = getattr(_module(info), info.target.split(":")[1])
    start = time.perf_counter()
    outcome: Outcome = fn(ctx)
    if not outcome.title:
        outcome.title = info.title
    return write_outputs(ctx, outcome, time.perf_counter() - start, peak_memory_mb())
