"""Model files with hinges, pins, springs and prescribed motion; the paper's TOML files."""
from pathlib import Path

import numpy as np
import pytest

from srdda.io.modelfile import ModelFileError, load_model, model_from_dict, save_model
from srdda.apps.paper import examples_dir, nunchaku, sine_wave

EXAMPLES = examples_dir() / "paper"
USER_EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _same_arrays(a, b):
    assert np.array_equal(a.vertex_position, b.vertex_position)
    assert np.array_equal(a.attached.point_position, b.attached.point_position)
    assert np.array_equal(a.attached.point_block, b.attached.point_block)
    for name in ("hinge_rows_a", "hinge_rows_b", "hinge_block_b", "hinge_correct", "spring_rows_a",
                 "spring_rows_b", "spring_stiffness", "spring_damping", "spring_rest", "spring_offset",
                 "spring_axial", "prescribed_rows", "prescribed_mask", "prescribed_multiplier"):
        assert np.array_equal(getattr(a.links, name), getattr(b.links, name)), name
    assert np.allclose(a.block_density, b.block_density) and np.allclose(a.block_elasticity, b.block_elasticity)


@pytest.mark.parametrize(("file", "module"), [("nunchaku.toml", nunchaku), ("sine-wave.toml", sine_wave)])
def test_paper_files_match_the_builders(file, module):
    model, settings = load_model(EXAMPLES / file)
    ref_model, ref_settings = module.build("srdda")
    _same_arrays(model.arrays(), ref_model.arrays())
    assert (settings.dt, settings.n_steps, settings.penalty) == (ref_settings.dt, ref_settings.n_steps,
                                                                ref_settings.penalty)
    t = 0.37
    for h, g in zip(model.arrays().links.prescribed_histories, ref_model.arrays().links.prescribed_histories):
        assert np.allclose(h(t), g(t)) and np.allclose(h.integral(t), g.integral(t))


def test_round_trip_keeps_links(tmp_path):
    model, settings = load_model(EXAMPLES / "nunchaku.toml")
    model.add_pin((2.0, 0.0), block=1)
    model.add_spring((0.5, 0.0), (1.5, 0.0), 1e6, damping=10.0, block_a=0, block_b=1)
    model.add_prescribed_motion((0.2, 0.0), [[0, 0, 0], [1, 0.1, 0]], quantity="velocity", by="penalty",
                                stiffness=1e9, block=0)
    model.set_base_acceleration((0.5, 0.0))
    path = tmp_path / "m.toml"
    save_model(model, settings, path)
    again, _ = load_model(path)
    _same_arrays(again.arrays(), model.arrays())
    assert np.allclose(again.arrays().links.base_acceleration(0.0), [0.5, 0.0])


def _minimal(**extra):
    data = {"run": {"dt": 0.001, "steps": 1}, "materials": {"r": {"density": 1, "young": 1e9, "poisson": 0.2}},
            "blocks": [{"name": "a", "material": "r", "vertices": [[0, 0], [1, 0], [1, 1], [0, 1]]}]}
    data.update(extra)
    return data


def test_bad_links_name_the_field():
    with pytest.raises(ModelFileError, match=r"prescribed_motion\[0\]\.history"):
        model_from_dict(_minimal(prescribed_motion=[{"at": [0.5, 0.5], "history": {}}]))
    with pytest.raises(ModelFileError, match=r"springs\[0\]\.kind"):
        model_from_dict(_minimal(springs=[{"a": [0.1, 0.1], "b": [0.9, 0.9], "stiffness": 1, "kind": "coil"}]))
    with pytest.raises(ModelFileError, match="pins"):
        model_from_dict(_minimal(pins=[{"at": [0.5, 0.5], "block": "nope"}]))
    with pytest.raises(ModelFileError, match="cannot tell which blocks"):
        model_from_dict(_minimal(hinges=[{"at": [0.5, 0.5]}]))


def test_hinged_wall_example_runs_and_keeps_its_hinge():
    model, settings = load_model(USER_EXAMPLES / "constraints" / "hinged-wall.toml")
    from dataclasses import replace

    from srdda import run

    res = run(model, replace(settings, n_steps=300))
    assert res.completed
    toe = res.final_state.points[model.arrays().links.hinge_rows_a[0]]
    assert np.allclose(toe, [0.4, 0.0], atol=1e-12)  # hinge to the fixed foundation: exact
    e = res.energy[-1]
    assert e["work_loads"] != 0.0 and e["dissipated"] > 0.0
