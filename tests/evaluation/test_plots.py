"""Figures people can read: overlapping curves stay distinguishable, every curve and shaded
interval is in the legend (issue 20)."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.colors import to_rgb

from fusetrack.evaluation import drawing, plots


def _legend_of_last_figure(monkeypatch, call):
    seen = {}

    def keep(fig, path):
        ax = fig.axes[0]
        seen["labels"] = [t.get_text() for t in ax.get_legend().get_texts()]
        seen["lines"] = {ln.get_label(): ln for ln in ax.get_lines()}
        seen["spans"] = len(ax.patches)
        plt.close(fig)
        return path

    monkeypatch.setattr(drawing, "save", keep)
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


# --- the helpers the experiments' figures are made of ---


def test_curves_label_every_curve_and_keep_given_styles():
    fig, ax = _axes()
    x = np.arange(30.0)
    same = np.ones(30)
    plots.curves(ax, x, {"A": same, "B": same, "C": same, "bound": same}, styles={"bound": "k--"})
    assert plots.labelled(ax) == ["A", "B", "C", "bound"]
    lines = {ln.get_label(): ln for ln in ax.get_lines()}
    assert (lines["bound"].get_color(), lines["bound"].get_linestyle()) == ("k", "--")
    looks = {(ln.get_color(), ln.get_linestyle(), ln.get_marker()) for ln in lines.values()}
    assert len(looks) == 4
    plt.close(fig)


def test_error_bars_are_spread_sideways_and_short_curves_mark_every_point():
    fig, ax = _axes()
    x = np.array([0.0, 10.0])
    plots.curves(ax, x, {"A": [1, 2], "B": [1, 2]}, errors={"A": [0.1, 0.1], "B": [0.2, 0.2]},
                 spread=0.05)  # fmt: skip
    xs = [c.lines[0].get_xdata() for c in ax.containers]
    assert np.allclose(xs[0], [-0.25, 9.75]) and np.allclose(xs[1], [0.25, 10.25])
    assert plots.distinct_style(3, 5)["markevery"] == (0, 1)
    assert plots.distinct_style(3, 120)["markevery"] == (3, 10)
    plt.close(fig)


def test_curve_rejects_y_of_the_wrong_length_naming_the_curve():
    import pytest

    from fusetrack.core import ShapeError

    fig, ax = _axes()
    with pytest.raises(ShapeError, match=r"EKF: y\.shape"):
        plots.curve(ax, [0, 1, 2], [1, 2], index=0, label="EKF")
    with pytest.raises(ShapeError, match=r"UKF: yerr\.shape"):
        plots.curve(ax, [0, 1], [1, 2], index=0, label="UKF", yerr=[1])
    plt.close(fig)


def test_shaded_intervals_where_given_and_bad_ones_named():
    import pytest

    from fusetrack.core import ConfigError

    fig, ax = _axes()
    plots.shade_intervals(ax, plots.runs_of([0, 1, 1, 0, 0, 1], np.arange(6.0)), "occluded")
    spans = [p.get_x() for p in ax.patches], [p.get_width() for p in ax.patches]
    assert np.allclose(spans[0], [0.5, 4.5]) and np.allclose(spans[1], [2.0, 1.0])
    assert plots.labelled(ax) == ["occluded"]
    with pytest.raises(ConfigError, match=r"intervals\[1\]"):
        plots.shade_intervals(ax, [(0, 1), (3, 2)], "outage")
    plt.close(fig)


def test_bars_one_labelled_series_per_method_with_distinct_hatches():
    fig, ax = _axes()
    plots.bars(
        ax, ["S1", "S2", "S3"], {"EKF": [1, 2, 3], "PF": [2, 3, 4]}, errors={"PF": [1, 1, 1]}
    )
    assert plots.labelled(ax) == ["EKF", "PF"]
    rects = ax.patches
    assert len(rects) == 6 and rects[0].get_hatch() != rects[3].get_hatch()
    assert np.isclose(rects[3].get_x() - rects[0].get_x(), 0.4)  # side by side in a group
    assert [t.get_text() for t in ax.get_xticklabels()] == ["S1", "S2", "S3"]
    plt.close(fig)


def test_figure_rejects_bad_grid_and_log_axis_bad_axis():
    import pytest

    from fusetrack.core import ConfigError

    with pytest.raises(ConfigError, match="cols"):
        plots.figure(1, 0)
    fig, ax = _axes()
    with pytest.raises(ConfigError, match="axis"):
        plots.log_axis(ax, "z")
    plt.close(fig)


def test_draw_paths_one_entry_per_path_or_one_for_all():
    fig, ax = _axes()
    paths = [np.c_[np.arange(5.0), np.full(5, k)] for k in range(3)]
    plots.draw_paths(ax, paths, labels=["a", "b", "c"])
    assert plots.labelled(ax) == ["a", "b", "c"]
    fig2, ax2 = _axes()
    plots.draw_paths(ax2, paths, label="tracks", mark_start=True)
    assert plots.labelled(ax2) == ["tracks"]
    assert len(ax2.get_lines()) == 6  # a path and its start dot each
    plt.close(fig)
    plt.close(fig2)


def test_reference_lines_are_labelled_and_bad_axis_named():
    import pytest

    from fusetrack.core import ConfigError

    fig, ax = _axes()
    plots.reference_line(ax, 2.0, "CRLB")
    plots.reference_line(ax, 5.0, "outage starts", axis="x", color="r")
    assert plots.labelled(ax) == ["CRLB", "outage starts"]
    h, v = ax.get_lines()
    assert np.allclose(h.get_ydata(), 2.0) and np.allclose(v.get_xdata(), 5.0)
    with pytest.raises(ConfigError, match="axis"):
        plots.reference_line(ax, 1.0, "x", axis="t")
    plt.close(fig)


def test_write_animation_writes_one_gif_frame_per_frame(tmp_path):
    from PIL import Image

    fig, ax = plots.panel(size=(2, 2))
    (line,) = ax.plot([], [])
    ax.set(xlim=(0, 4), ylim=(0, 4))

    def draw(k):
        line.set_data(np.arange(k + 2), np.arange(k + 2))
        return [line]

    out = plots.write_animation(fig, draw, range(3), tmp_path / "a.mp4", fps=5)
    assert out == tmp_path / "a.gif"  # no mp4 asked for
    assert Image.open(out).n_frames == 3


def test_spread_band_fills_between_the_bounds_in_the_curve_colour_and_names_bad_shapes():
    import pytest

    from fusetrack.core import ShapeError

    fig, ax = _axes()
    x = np.arange(4.0)
    plots.curve(ax, x, [1.0, 2.0, 3.0, 4.0], index=2, label="median")
    plots.spread_band(ax, x, [0.5, 1.5, 2.5, 3.5], [1.5, 2.5, 3.5, 4.5], index=2, label="quartiles")
    (band,) = ax.collections
    path = band.get_paths()[0].vertices
    assert path[:, 1].min() == 0.5 and path[:, 1].max() == 4.5  # from the lower to the upper bound
    assert np.allclose(band.get_facecolor()[0][:3], to_rgb(ax.get_lines()[0].get_color()))
    assert "quartiles" in plots.labelled(ax)
    with pytest.raises(ShapeError, match=r"high\.shape"):
        plots.spread_band(ax, x, x, x[:3], index=0)
    plt.close(fig)
