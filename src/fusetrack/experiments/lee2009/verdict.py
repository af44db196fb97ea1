"""Lee 2009's central contributions and the claims that decide them (the verdict word is
computed from the committed reports: :mod:`fusetrack.evaluation.verdict`)."""

from ...evaluation import Contribution, PaperVerdict, Reading, refs

VERDICT = PaperVerdict(
    "Lee 2009",
    "lee2009",
    (
        Contribution(
            "Ch. 2: 3-D tracking from one acoustic DOA sensor on the two selected projected planes "
            "(PPS) is at least as accurate as a direct 3-D particle filter, and its selected "
            "planes weigh the measurements more",
            refs(
                "lee2009-projected-planes",
                "C5_pps_rmse_vs_3d",
                "C5_pps_rmse_vs_3d_from_prior",
                "C4_weight_sums",
            ),
        ),
        Contribution(
            "Ch. 3: cameras triggered by the acoustic trackers cut the error of no cooperation "
            "with fewer camera uses than periodic cooperation of the same error",
            refs("lee2009-camera-triggering", "C9_trigger_beats_none", "C9_cheaper_than_periodic"),
            readings=tuple(
                Reading(
                    reading,
                    refs(
                        "lee2009-camera-triggering",
                        f"C9_trigger_beats_none_variant_{variant}",
                        f"C9_cheaper_than_periodic_variant_{variant}",
                    ),
                )
                for variant, reading in (
                    ("alpha=0.01", "turn acceleration alpha = 0.01"),
                    ("printed", "the printed estimator chain (3.7)-(3.11)"),
                )
            ),
            best_possible=refs(
                "lee2009-camera-triggering",
                *(
                    f"BP_possible_t31_{policy}_{who}"
                    for policy in ("none", "trigger")
                    for who in ("O1", "O2", "O3", "average")
                ),
            ),
        ),
        Contribution(
            "Ch. 4: quality-weighted fusion of camera detections with a dynamic prior rejects the "
            "false detection the unweighted rule accepts, and tolerates more spread with more "
            "cameras",
            refs(
                "lee2009-detection-fusion",
                "C12_decisions",
                "C13_baseline_accepts_false",
                "C14_falls_with_spread",
                "C14_more_cameras_tolerate_more",
            ),
        ),
        Contribution(
            "Sec. 5.2.3: RFID virtual sensors refined by cameras beat the coarse RFID position, "
            "with an accuracy roughly independent of the readers' layout and almost the same "
            "from one or two reference points (Fig. 5-36)",
            refs(
                "lee2009-rfid-camera",
                "C17_refined_beats_coarse",
                "C17_refined_flat",
                "C17_one_vs_two_references",
            ),
        ),
    ),
)
