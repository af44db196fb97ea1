"""Nott 2009's central contributions and the claims that decide them (the verdict word is
computed from the committed reports: :mod:`fusetrack.evaluation.verdict`)."""

from ...evaluation import Contribution, PaperVerdict, refs

VERDICT = PaperVerdict(
    "Nott 2009",
    "nott2009",
    (
        Contribution(
            "Sec. 5.1 (Figs. 5.1-5.4): the joint camera + tag EKF beats the tag alone, beats "
            "switching to the tag during occlusion and beats the camera alone in long occlusions",
            refs(
                "nott2009-simulation",
                "H1-S1",
                "H1-S2",
                "H3-S3-ca",
                "H3-S3-cv",
                "H4-S4-ca-mean",
                "H4-S4-cv-mean",
            ),
        ),
        Contribution(
            "Sec. 5.2 (Figs. 5.6-5.9): on video, the whole chain (homographies, background "
            "subtraction, occlusion detection) keeps the joint track closer than the tag "
            "through dropped frames and a crossing",
            refs("nott2009-video", "R2-joint", "H5", "H6", "H8-recall"),
        ),
    ),
)
