"""Ercan 2013's central contributions and the claims that decide them (the verdict word is
computed from the committed reports: :mod:`fusetrack.evaluation.verdict`)."""

from ...evaluation import Contribution, PaperVerdict, Reading, refs

VERDICT = PaperVerdict(
    "Ercan 2013",
    "ercan2013",
    (
        Contribution(
            "E1 (Figs. 5-6): the tracking error falls as cameras are added, and at every camera "
            "count better occluder priors give a lower error (perfect <= Gaussian <= none)",
            refs(
                "ercan2013-cameras",
                "C3_decreasing_perfect",
                "C3_decreasing_gaussian",
                "C3_decreasing_none",
                "C3_ordering",
            ),
            readings=(
                Reading(
                    "sigma_v = 2",
                    refs(
                        "ercan2013-cameras-sigma-v",
                        "C3_decreasing_perfect_sigma_v_2",
                        "C3_decreasing_gaussian_sigma_v_2",
                        "C3_decreasing_none_sigma_v_2",
                        "C3_ordering_sigma_v_2",
                    ),
                ),
            ),
            best_possible=refs("ercan2013-cameras", "BP_ordering_possible"),
        ),
        Contribution(
            "E2 (Fig. 7): the occlusion-aware particle filter with perfect occluder priors cuts "
            "the error of ignoring the occluders 2.34x, and priors pay off until their RMSE "
            "reaches 3.72",
            refs("ercan2013-prior-accuracy", "C4_gain_perfect", "C4_crossing"),
            readings=(
                Reading(
                    "sigma_v = 2",
                    refs(
                        "ercan2013-prior-accuracy",
                        "C4_gain_perfect_sigma_v_2",
                        "C4_crossing_sigma_v_2",
                    ),
                ),
            ),
            best_possible=refs(
                "ercan2013-prior-accuracy",
                "BP_possible_perfect",
                "BP_possible_none",
                "BP_possible_crossing",
            ),
        ),
        Contribution(
            "E2 (Fig. 7): at realistic prior accuracy the occluder priors still gain 1.94x",
            refs("ercan2013-prior-accuracy", "C4_gain_realistic"),
            readings=(
                Reading(
                    "sigma_v = 2", refs("ercan2013-prior-accuracy", "C4_gain_realistic_sigma_v_2")
                ),
            ),
            best_possible=refs(
                "ercan2013-prior-accuracy", "BP_possible_none", "BP_possible_crossing"
            ),
        ),
        Contribution(
            "E3 (Fig. 8): cameras trade off against occluder-prior accuracy; with enough cameras "
            "no prior is needed",
            refs("ercan2013-tradeoff", "C5_monotone", "C5_no_prior_needed"),
        ),
        Contribution(
            "E6-E8 (Figs. 11-15): greedy camera-subset selection is close to brute force and "
            "beats the closest, random and fixed subsets",
            (
                *refs(
                    "ercan2013-selection",
                    "C8_greedy_close_to_brute_perspective",
                    "C8_greedy_beats_closest",
                    "C8_greedy_beats_random",
                    "C8_greedy_beats_fixed",
                ),
                *refs("ercan2013-lab", "C11_fig15_greedy_brute", "C11_fig15_greedy_beats"),
            ),
        ),
    ),
)
