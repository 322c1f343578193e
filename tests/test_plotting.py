"""Figures checked for content: axes count, lines carrying the recorded data, pixels drawn."""
from __future__ import annotations

import matplotlib
import numpy as np
import pytest

import srdda
from srdda.apps import plotting
from srdda.io.results_store import ResultsStore, read_results
from srdda.results import Result
from results_models import rod_model, rod_settings, two_block_model

matplotlib.use("Agg")
METHODS = ("dda0", "dda1", "srdda")


def _ink(fig) -> float:
    """Fraction of pixels that are not background white."""
    fig.canvas.draw()
    rgba = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(float)
    return float(np.mean(np.any(rgba < 250, axis=-1)))


def _data_lines(ax) -> list:
    return [ln for ln in ax.get_lines() if np.sum(np.isfinite(ln.get_xydata()).all(axis=1)) > 1]


def _check(fig, n_axes: int) -> None:
    # top-level axes only (insets are children of their axes); each one draws data
    assert len(fig.axes) == n_axes
    for ax in fig.axes:
        assert _data_lines(ax) or ax.collections, f"axes {ax.get_title()!r} is empty"
    assert _ink(fig) > 0.02  # a blank figure has 0; axes frames and ticks alone stay below 1%
    matplotlib.pyplot.close(fig)


@pytest.fixture(scope="module")
def rod_runs() -> dict[str, Result]:
    return {m: srdda.run(rod_model(), rod_settings(m, n_steps=300)) for m in METHODS}


def test_swing_trajectories_draw_each_method_and_the_offset(rod_runs) -> None:
    fig = plotting.fig_swing_trajectories(rod_runs, pivot=(0.0, 0.05))
    for col, method in enumerate(METHODS):
        top = fig.axes[col]
        path = _data_lines(top)[0].get_xydata()
        np.testing.assert_array_equal(path, rod_runs[method].array("measured_position")[:, 0])
        zoom = fig.axes[3 + col]  # the zoomed view: the same path, limits around its lowest point
        np.testing.assert_array_equal(_data_lines(zoom)[0].get_xydata(), path)
        assert zoom.get_ylim()[0] <= path[:, 1].min() <= zoom.get_ylim()[1]
    # dda0's rod lengthens (area grows as 1 + Δr² per step): its tip's radial offset is the largest
    offsets = [np.max(np.abs(_data_lines(fig.axes[6 + c])[0].get_xydata()[:, 1])) for c in range(3)]
    assert offsets[0] > offsets[1] and offsets[0] > offsets[2]
    _check(fig, 9)


def test_wave_shapes_plot_the_centroid_displacement_at_each_step() -> None:
    # synthetic histories: 10 bars whose centroids follow a known travelling sine
    x = np.linspace(0.125, 2.375, 10)
    runs = {}
    for method, speed in zip(METHODS, (1.0, 1.1, 1.2)):
        res = Result(tuple(f"bar {i}" for i in range(10)), method)
        for step in range(0, 901, 50):
            res.step.append(step)
            res.time.append(step * 0.005)
            res.centroid.append(np.column_stack([x, np.sin(x - speed * step / 300)]))
        runs[method] = res
    fig = plotting.fig_wave_shapes(runs, steps=(300, 600, 900))
    line = _data_lines(fig.axes[3 * 1 + 2])[0]  # row CS 600, column srdda
    np.testing.assert_allclose(line.get_ydata(), np.sin(x - 1.2 * 2) - np.sin(x), rtol=0, atol=1e-15)
    _check(fig, 9)


def _nunchaku_model() -> srdda.Model:
    """Two 1 x 0.1 m sticks hinged by point springs, hanging from A; released horizontal (paper 4.4)."""
    m = srdda.Model(gravity=(0.0, -10.0))
    m.add_material("wood", srdda.Material(density=2500.0, young=2e10, poisson=0.45))
    m.add_block([[0, 0], [1, 0], [1, 0.1], [0, 0.1]], "wood", name="AB1")
    m.add_block([[1, 0], [2, 0], [2, 0.1], [1, 0.1]], "wood", name="B2C")
    m.add_fixed_point([0.0, 0.05], block=0, stiffness=2e14)
    m.add_point_spring([1.0, 0.05], [1.0, 0.05], 2e14, block_a=0, block_b=1)
    for p, b in (([1.0, 0.05], 0), ([1.0, 0.05], 1), ([2.0, 0.05], 1)):
        m.add_measured_point(p, block=b)
    return m


def test_nunchaku_figures() -> None:
    runs = {m: srdda.run(_nunchaku_model(), srdda.RunSettings(dt=2e-3, n_steps=150, method=m, penalty=2e14))
            for m in METHODS}
    fig12, fig13 = plotting.fig_nunchaku(runs)
    omega = _data_lines(fig12.axes[6])
    assert len(omega) == 2  # one ω line per stick
    np.testing.assert_array_equal(omega[1].get_ydata(), runs["dda0"].array("velocity")[:, 1, 2])
    _check(fig12, 9)
    assert len(_data_lines(fig13.axes[0])) == 3
    _check(fig13, 1)


def test_rockfall_draws_slope_and_paths() -> None:
    model = two_block_model()
    runs = {m: srdda.run(model, srdda.RunSettings(dt=1e-3, n_steps=50, method=m)) for m in METHODS}
    arrays = model.arrays()
    fig = plotting.fig_rockfall(runs, background=(arrays.vertex_position, arrays.block_ptr))
    for ax in fig.axes:
        assert len(ax.collections) == 1 and len(_data_lines(ax)) == 2
    _check(fig, 3)


def test_configuration_marks_supports_loads_and_measured_points() -> None:
    arrays = rod_model().arrays()
    fig = plotting.fig_configuration(arrays, "rod")
    ax = fig.axes[0]
    labels = [ln.get_label() for ln in ax.get_lines()]
    assert labels == ["fixed point", "point load", "measured point"]
    attached = arrays.attached
    np.testing.assert_array_equal(ax.get_lines()[0].get_xydata(), attached.point_position[attached.fixed_rows])
    np.testing.assert_array_equal(ax.collections[0].get_paths()[0].vertices[:4], arrays.vertex_position)
    assert [t.get_text() for t in ax.texts] == ["P0"]
    _check(fig, 1)


def test_any_run_model_trajectories_and_time_series(tmp_path) -> None:
    path = tmp_path / "r.h5"
    settings = srdda.RunSettings(dt=1e-3, n_steps=40, method="dda0")
    srdda.run(two_block_model(), settings, recorders=[ResultsStore(path, settings)])
    res = read_results(path)
    fig = plotting.fig_model(res, index=20, color="area_change")
    assert len(fig.axes[0].collections) == 1
    _check(fig, 2)  # the model and its colour bar
    _check(plotting.fig_trajectories(res, "centroid"), 1)
    fig = plotting.fig_time_series(res, "velocity.omega")
    np.testing.assert_array_equal(_data_lines(fig.axes[0])[0].get_ydata(), res.velocity[:, 0, 2])
    _check(fig, 1)
    fig = plotting.fig_time_series({"a": res, "b": res}, "energy.total")
    assert len(_data_lines(fig.axes[0])) == 2
    _check(fig, 1)
    fig = plotting.fig_time_series(res, "measured_position.y")
    lines = _data_lines(fig.axes[0])
    assert len(lines) == 2 and lines[1].get_label() == "point 1"
    np.testing.assert_array_equal(lines[1].get_ydata(), res.measured_position[:, 1, 1])
    _check(fig, 1)
    with pytest.raises(ValueError, match="plot centroid.x"):
        plotting.fig_time_series(res, "centroid")
    with pytest.raises(KeyError, match="unknown quantity"):
        plotting.history(res, "velocity.nope")
    with pytest.raises(ValueError, match="vertex history"):
        plotting.fig_model(srdda.run(two_block_model(), settings))


def test_every_quantity_has_a_unit_and_colour_bars_say_it(tmp_path) -> None:
    path = tmp_path / "r.h5"
    settings = srdda.RunSettings(dt=1e-3, n_steps=10, method="srdda")
    srdda.run(two_block_model(), settings, recorders=[ResultsStore(path, settings)])
    res = read_results(path)
    units = {name: plotting.quantity_unit(res, name) for name in plotting.quantity_names(res)}
    assert units["stress.sxx"] == "Pa" and units["velocity.omega"] == "rad/s" and units["energy.total"] == "J/m"
    fig = plotting.fig_model(res, color="stress.sxx")
    assert fig.axes[1].get_ylabel() == "normal stress σx (Pa)"  # words, not the internal key
    matplotlib.pyplot.close(fig)
    with pytest.raises(KeyError, match="no unit known for 'nope'"):
        plotting.quantity_unit(res, "nope")
