"""Figures people can read: overlapping curves stay distinguishable, every curve and shaded
interval is in the legend (issue 20)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np

from fusetrack.evaluation import plots


def _legend_of_last_figure(monkeypatch, call):
    seen = {}

    def keep(fig, path):
        ax = fig.axes[0]
        seen["labels"] = [t.get_text() for t in ax.get_legend().get_texts()]
        seen["lines"] = {ln.get_label(): ln for ln in ax.get_lines()}
        seen["spans"] = len(ax.patches)
        plt.close(fig)
        return path

    monkeypatch.setattr(plots, "save", keep)
    call()
    return seen


def test_identical_curves_get_different_styles_and_shading_is_labelled(monkeypatch, tmp_path):
    t = np.linspace(0, 10, 50)
    same = np.sin(t)
    seen = _legend_of_last_figure(
        monkeypatch,
        lambda: plots.plot_series(
            tmp_path / "a.png", t, {"EKF": same, "UKF": same, "PF": same, "bound": same},
            xlabel="t (s)", ylabel="m", styles={"bound": "k--"}, shade=[(2, 3), (6, 7)],
            shade_label="camera occluded",
        ),
    )  # fmt: skip
    assert seen["labels"] == ["camera occluded", "EKF", "UKF", "PF", "bound"]
    styles = {
        (ln.get_linestyle(), ln.get_marker(), ln.get_color()) for ln in seen["lines"].values()
    }
    assert len(styles) == 4  # no two curves drawn alike
    assert seen["spans"] == 2


def test_trajectories_mark_part_of_the_truth(monkeypatch, tmp_path):
    truth = np.c_[np.arange(20.0), np.zeros(20)]
    marked = np.arange(20) >= 10
    seen = _legend_of_last_figure(
        monkeypatch,
        lambda: plots.plot_trajectories(
            tmp_path / "b.png", truth, {"A": truth, "B": truth}, truth_marked=marked,
            marked_label="hidden",
        ),
    )  # fmt: skip
    assert seen["labels"][:2] == ["hidden", "truth"]
    band = seen["lines"]["hidden"].get_xydata()
    assert np.isnan(band[:10]).all() and np.isfinite(band[10:]).all()
    a, b = seen["lines"]["A"], seen["lines"]["B"]
    assert (a.get_linestyle(), a.get_marker()) != (b.get_linestyle(), b.get_marker())
