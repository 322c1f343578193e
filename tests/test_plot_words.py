"""Plots that say what they show: `srdda plot --quantity energy` draws the energy ledger, labels are words
with SI units, each block's energies add up to the ledger's (and match closed forms)."""
from __future__ import annotations

from pathlib import Path

import matplotlib.figure
import numpy as np
import pytest
from click.testing import CliRunner

import srdda
from srdda.apps import plotting
from srdda.apps.cli import main
from srdda.geometry.polyhedron import box
from srdda.io.results_store import ResultsStore, read_results
from results_models import two_block_model

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="module")
def stored(tmp_path_factory: pytest.TempPathFactory):
    path = tmp_path_factory.mktemp("plot") / "run.h5"
    settings = srdda.RunSettings(dt=1e-3, n_steps=30, method="srdda")
    srdda.run(two_block_model(), settings, recorders=[ResultsStore(path, settings, flush_every=10)])
    return read_results(path)


def _drawn(monkeypatch: pytest.MonkeyPatch) -> list[matplotlib.figure.Figure]:
    saved: list[matplotlib.figure.Figure] = []
    original = matplotlib.figure.Figure.savefig
    monkeypatch.setattr(matplotlib.figure.Figure, "savefig",
                        lambda fig, *a, **k: (saved.append(fig), original(fig, *a, **k))[1])
    return saved


def test_plot_quantity_energy_draws_the_ledger_not_the_model(stored, tmp_path: Path, monkeypatch) -> None:
    # issue 31 item 4: `srdda plot RUN --quantity energy` (advised by rockfall-3d.toml) drew the model
    saved = _drawn(monkeypatch)
    res = CliRunner().invoke(main, ["plot", stored.path, "--quantity", "energy", "-o", str(tmp_path / "e.png")])
    assert res.exit_code == 0, res.output
    (fig,) = saved
    titles = [ax.get_title() for ax in fig.axes]
    assert "kinetic energy" in titles and any(t.startswith("balance error") for t in titles)
    assert all(ax.get_ylabel() == "energy (J/m)" or ax.get_ylabel().startswith("energy (") for ax in fig.axes)
    assert not any("_" in ax.get_ylabel() for ax in fig.axes)  # no internal keys (dissipated_friction)


def test_labels_are_words_with_units(stored) -> None:
    assert plotting.quantity_label(stored, "stress.sxx") == "normal stress σx (Pa)"
    assert plotting.quantity_label(stored, "energy.dissipated_friction") == "energy dissipated by friction (J/m)"
    assert plotting.quantity_label(stored, "velocity.omega") == "angular velocity ω (rad/s)"
    assert plotting.quantity_label(stored, "measured_position.y") == "measured point y (m)"
    fig = plotting.fig_time_series(stored, "energy.kinetic")
    assert fig.axes[0].get_ylabel() == "kinetic energy (J/m)"
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["SRDDA"]


def test_per_block_energies_add_up_to_the_ledger(stored) -> None:
    # the ledger's kinetic energy is ½ḋᵀMḋ summed over the blocks; the two blocks barely strain (ε̇ ~ 1e-6),
    # so translation and rotation carry it to 1e-9; their gravity changes sum to the ledger's gravity change
    arrays = two_block_model().arrays()
    e = plotting.block_energies(stored, arrays)
    kinetic = plotting.history(stored, "energy.kinetic")
    np.testing.assert_allclose((e["translational"] + e["rotational"]).sum(axis=1), kinetic, rtol=1e-9)
    gravity = plotting.history(stored, "energy.gravity")
    np.testing.assert_allclose(e["potential"].sum(axis=1), gravity - gravity[0], rtol=1e-9,
                               atol=1e-12 * np.max(np.abs(gravity)))
    fig = plotting.fig_block_energies(stored, arrays)
    assert [ax.get_title() for ax in fig.axes] == list(stored.block_names)


def test_a_spinning_box_s_rotational_energy_is_half_i_omega_squared(tmp_path: Path) -> None:
    # a 1 × 2 × 3 m box spinning at ω = 0.7 rad/s about z in free flight: J_zz = m (a² + b²) / 12
    m = srdda.Model(gravity=(0.0, 0.0, 0.0))
    m.add_material("rock", srdda.Material(2000.0, 1e10, 0.25))
    m.add_polyhedron(*box((0, 0, 0), (1, 2, 3)), "rock", velocity=(0.5, 0.0, 0.0), angular_velocity=(0, 0, 0.7))
    settings = srdda.RunSettings(dt=1e-3, n_steps=5, method="srdda")
    srdda.run(m, settings, recorders=[ResultsStore(tmp_path / "r.h5", settings)])
    e = plotting.block_energies(read_results(tmp_path / "r.h5"), m.arrays())
    mass = 2000.0 * 6.0
    np.testing.assert_allclose(e["rotational"][:, 0], 0.5 * mass * (1 + 4) / 12 * 0.7**2, rtol=1e-9)
    np.testing.assert_allclose(e["translational"][:, 0], 0.5 * mass * 0.25, rtol=1e-9)


def test_plot_block_energy_names_blocks_and_refuses_unknown_ones(stored, tmp_path: Path) -> None:
    runner = CliRunner()
    ok = runner.invoke(main, ["plot", stored.path, "--what", "block-energy", "--block", "block 1",
                              "-o", str(tmp_path / "b.png")])
    assert ok.exit_code == 0, ok.output
    bad = runner.invoke(main, ["plot", stored.path, "--what", "block-energy", "--block", "nope"])
    assert bad.exit_code == 2 and "no such block" in bad.output
