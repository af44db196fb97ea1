"""Kushwaha 2010's central contributions and the claims that decide them (the verdict word is
computed from the committed reports: :mod:`fusetrack.evaluation.verdict`)."""

from ...evaluation import Contribution, PaperVerdict, Reading, refs

VERDICT = PaperVerdict(
    "Kushwaha 2010",
    "kushwaha2010",
    (
        Contribution(
            "Ch. III: audio-video fusion (product rule) tracks vehicles better than audio or "
            "video alone, with grid SBE and with MCMCDA",
            (
                *refs("kushwaha2010-sbe", "av_beats_each_modality"),
                *refs("kushwaha2010-mcmcda", "av_lowest_error"),
            ),
        ),
        Contribution(
            "Ch. III: product fusion is more accurate than the quality-weighted sum",
            (
                *refs("kushwaha2010-sbe", "product_more_accurate"),
                *refs("kushwaha2010-mcmcda", "product_lower_error"),
            ),
        ),
        Contribution(
            "Ch. V: the image-plane trackers (T3/T4) beat the 3-D kernel-density ones (T1/T2) on "
            "large targets (setup A), the kernel-density ones win on small targets (setup B)",
            (
                *refs("kushwaha2010-cameras-a", "a_image_plane_beat_kernel"),
                *refs("kushwaha2010-cameras-b", "b_kernel_best"),
            ),
            readings=(
                Reading(
                    "one scene swept over the target's pixel area (H19: where T2 and T3 cross)",
                    refs(
                        "kushwaha2010-cameras-area",
                        "area_t3_better_large",
                        "area_t2_better_small",
                        "area_crossover_near_1pct",
                    ),
                ),
                Reading(
                    "medians of paired per-run differences (one diverged run decides a mean)",
                    (
                        *refs("kushwaha2010-cameras-a", "a_image_plane_beat_kernel"),
                        *refs("kushwaha2010-cameras-b", "b_kernel_best_median"),
                    ),
                ),
            ),
        ),
    ),
)
