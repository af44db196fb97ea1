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


# --- drawing on a given axes (shared by the experiments' figures) ---


def _axes():
    fig, axes = plots.figure(1, 1)
    return fig, axes[0, 0]


def test_figure_returns_a_grid_of_axes_in_the_common_style():
    fig, axes = plots.figure(2, 3)
    assert axes.shape == (2, 3)
    assert len(fig.axes) == 6
    plt.close(fig)


def test_draw_tracks_labels_each_track_by_id_and_truth_once():
    from fusetrack.core import Track

    t = np.arange(20.0)
    path = np.column_stack([t, t])
    tracks = [Track(t, path + k * 0.0, id=k + 3) for k in range(3)]  # identical paths
    fig, ax = _axes()
    plots.draw_tracks(ax, tracks, truth=[path, path + 5])
    labels = [x.get_text() for x in ax.get_legend().get_texts()]
    assert labels == ["truth", "track 3", "track 4", "track 5"]
    lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("track")]
    assert len({(ln.get_linestyle(), ln.get_marker(), ln.get_color()) for ln in lines}) == 3
    assert len(ax.get_lines()) == 5  # two truth paths + three tracks
    plt.close(fig)


def test_draw_particles_sizes_follow_weights():
    from fusetrack.core import Particles

    states = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]])
    fig, ax = _axes()
    plots.draw_particles(ax, Particles(states, np.log([1.0, 2.0, 4.0])))
    sizes = ax.collections[0].get_sizes()
    assert np.allclose(sizes, 2.0 + 30.0 * np.array([0.25, 0.5, 1.0]))
    plots.draw_particles(ax, states, weights=[1, 1, 1], label="equal")
    assert len(ax.collections) == 2 and np.allclose(ax.collections[1].get_sizes(), 32.0)
    plt.close(fig)


def test_draw_grid_belief_has_colour_bar_and_extent_in_metres():
    from fusetrack.core import GridBelief

    grid = GridBelief.uniform((np.arange(0.5, 10.0, 1.0), np.arange(0.25, 4.0, 0.5)))
    fig, ax = _axes()
    plots.draw_grid_belief(ax, grid)
    (im,) = ax.get_images()
    assert np.allclose(im.get_extent(), (0.0, 10.0, 0.0, 4.0))
    assert im.get_array().shape == (8, 10)  # rows are y
    assert len(fig.axes) == 2  # the colour bar
    plt.close(fig)


def test_covariance_ellipse_axes_from_eigenvalues_computed_by_hand():
    fig, ax = _axes()
    # diag(4, 1), 2 sigma: full width 2*2*2 = 8 along x, height 2*2*1 = 4
    e = plots.draw_covariance_ellipse(ax, [1.0, 2.0], np.diag([4.0, 1.0]), nsigma=2)
    assert (e.center, e.width, e.height) == ((1.0, 2.0), 8.0, 4.0)
    assert abs(e.angle % 180) < 1e-9
    # [[2, 1], [1, 2]]: eigenvalues 3 along (1, 1)/sqrt2 and 1 along (1, -1)/sqrt2
    e = plots.draw_covariance_ellipse(ax, [0, 0], [[2.0, 1.0], [1.0, 2.0]], nsigma=1)
    assert np.isclose(e.width, 2 * np.sqrt(3)) and np.isclose(e.height, 2.0)
    assert np.isclose(e.angle % 180, 45.0)
    # components (0, 2) of a 4-D state
    e = plots.draw_covariance_ellipse(ax, np.zeros(4), np.diag([1.0, 9.0, 0.25, 9.0]), dims=(0, 2))
    assert np.isclose(e.width, 4.0) and np.isclose(e.height, 2.0)
    assert len(ax.patches) == 3
    plt.close(fig)


def test_covariance_ellipse_rejects_bad_covariance():
    import pytest

    from fusetrack.core import ShapeError

    fig, ax = _axes()
    with pytest.raises(ShapeError, match="cov"):
        plots.draw_covariance_ellipse(ax, [0, 0], [[1.0, 0.0], [0.0, -1.0]])
    with pytest.raises(ShapeError, match=r"cov\.shape"):
        plots.draw_covariance_ellipse(ax, [0, 0], [1.0, 2.0])
    plt.close(fig)


def test_draw_scene_walls_occluders_cameras_and_sensors():
    from fusetrack.world.room import Room

    room = Room(
        np.array([[0, 0], [10, 0], [10, 8], [0, 8]], float),
        static_occluders=(np.array([[4, 4], [5, 4], [5, 5], [4, 5]], float),),
    )
    cams = [((0.0, 0.0), np.pi / 4, np.pi / 3), ((10.0, 8.0), -3 * np.pi / 4, np.pi / 3)]
    fig, ax = _axes()
    plots.draw_scene(
        ax, room, occluders=[((2.0, 2.0), 0.5), np.array([[7, 1], [8, 1], [8, 2]], float)],
        cameras=cams, sensors=[("mic A", (1.0, 7.0)), ("tag", (9.0, 1.0))],
    )  # fmt: skip
    from matplotlib.patches import Circle, Polygon, Wedge

    kinds = [type(p) for p in ax.patches]
    assert kinds.count(Polygon) == 3  # walls, static occluder, polygon occluder
    assert kinds.count(Circle) == 1 and kinds.count(Wedge) == 2
    wedge = next(p for p in ax.patches if isinstance(p, Wedge))
    assert np.isclose(wedge.theta1, 15.0) and np.isclose(wedge.theta2, 75.0)
    assert [t.get_text() for t in ax.texts] == ["1", "2", "mic A", "tag"]
    assert ax.get_xlim()[0] < 0 < 10 < ax.get_xlim()[1]
    plt.close(fig)


def test_label_axes_sets_units():
    fig, ax = _axes()
    plots.label_axes(ax, title="scene")
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) == ("x (m)", "y (m)", "scene")
    plt.close(fig)
