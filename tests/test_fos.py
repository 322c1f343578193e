"""Factor of safety by shear strength reduction (srdda.apps.fos) and the closed forms it is checked against."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

from srdda import JointMaterial, Material, Model, RunSettings
from srdda.apps.verify.cases.plane_failure import (BASE_LENGTH, PLANE_DIP, PLANE_FAILURE, plane_failure_factor,
                                       plane_failure_model, plane_failure_water_forces, set_hoek_bray_water,
                                       wet_plane_forces, wet_plane_model)
from srdda.apps.verify.cases.slope3d import (WEDGE_PLANES, HoekBrayAngles, hoek_bray_wedge_angles,
                                 hoek_bray_wedge_factor_of_safety, wedge_faces, wedge_friction_for, wedge_model,
                                 wedge_solution, wedge_vertices, wedge_water_forces, wet_wedge_factor_of_safety)
from srdda.constraints.water import UNIT_WEIGHT
from srdda.geometry.jointsets3d import plane_normal
from srdda.apps.cli import main
from srdda.apps.fos import FailureCriterion, FosError, factor_of_safety, judge, reduce_strength, settle_dt, try_factor
from srdda.io.modelfile import save_model
from srdda.apps.verify import run_case


# -- the closed forms ----------------------------------------------------------------------------------
def test_plane_failure_with_water_against_a_hand_computation():
    # W = 2e6 N/m, A = 20 m, ψ = 30°, φ = 25°, c = 20 kPa, crack filled to z_w = 2 m (γ_w = 9810 N/m³):
    # U = ½·9810·2·20 = 196,200 N/m, V = ½·9810·4 = 19,620 N/m;
    # FS = [20e3·20 + (2e6·0.8660254 − 196,200 − 19,620·0.5)·0.4663077] / (2e6·0.5 + 19,620·0.8660254)
    #    = [400,000 + 1,526,040.8·0.4663077] / 1,016,991.4 = 1,111,604.5 / 1,016,991.4 = 1.093032
    u, v = plane_failure_water_forces(20.0, 2.0)
    assert (u, v) == pytest.approx((196_200.0, 19_620.0), rel=1e-12)
    fs = plane_failure_factor(2e6, 30.0, 25.0, u, v, cohesion=20e3, area=20.0)
    assert fs == pytest.approx(1.093032, rel=2e-6)  # the hand computation's 7 digits


def test_plane_failure_dry_is_resisting_over_driving():
    # dry, no cohesion: FS = tan φ / tan ψ exactly
    assert plane_failure_factor(1.0, 30.0, 25.0) == pytest.approx(
        math.tan(math.radians(25)) / math.tan(math.radians(30)), rel=1e-14)


# Hoek & Bray's worked wedge (1981, ch. 8): planes 45/105 and 70/235, face 65/185, upper surface 12/195; their
# angles as read from the stereonet. With H = 40 m, γ = 25 kN/m³, γ_w = 10 kN/m³, c_A = 24 kPa, c_B = 48 kPa,
# φ_A = 20°, φ_B = 30° by hand:
#   X = sin 65/(sin 25 cos 50) = 0.906308/(0.422618·0.642788) = 3.33626
#   Y = sin 62/(sin 31 cos 60) = 0.882948/(0.515038·0.5) = 3.42867
#   A = (cos 45 − cos 70 cos 101)/(sin 31.2 sin² 101) = (0.707107 + 0.342020·0.190809)/(0.517951·0.963592) = 1.54731
#   B = (cos 70 − cos 45 cos 101)/(same) = (0.342020 + 0.707107·0.190809)/0.499093 = 0.95548
#   FS = 3/(25e3·40)(24e3·3.33626 + 48e3·3.42867) + (1.54731 − 0.2·3.33626) tan 20 + (0.95548 − 0.2·3.42867) tan 30
#      = 3e-6·244,646.4 + 0.880058·0.363970 + 0.269746·0.577350 = 0.733939 + 0.320315 + 0.155738 = 1.209992
BOOK_ANGLES = HoekBrayAngles(dip_a=45.0, dip_b=70.0, plunge=31.2, na_nb=101.0, t24=65.0, t45=25.0, t2_na=50.0,
                             t13=62.0, t35=31.0, t1_nb=60.0)


def test_hoek_bray_wedge_against_a_hand_computation():
    fs = hoek_bray_wedge_factor_of_safety(BOOK_ANGLES, 40.0, 20.0, 30.0, 24e3, 48e3, 25e3, 10e3)
    assert fs == pytest.approx(1.209992, rel=1e-5)  # the hand computation's 6 digits


def test_hoek_bray_angles_from_the_geometry_match_the_book():
    # the angles that do not depend on the upper surface (12/195 in the book, horizontal here); the book reads
    # them to the degree (ψ5 to 0.1°) from a stereonet
    a = hoek_bray_wedge_angles((45.0, 105.0), (70.0, 235.0), (65.0, 185.0))
    assert a.plunge == pytest.approx(31.2, abs=0.05)
    for ours, book in ((a.na_nb, 101.0), (a.t2_na, 50.0), (a.t1_nb, 60.0)):
        assert ours == pytest.approx(book, abs=0.5)


def test_hoek_bray_wedge_dry_frictional_equals_the_wedge_solution():
    # two derivations of the same equilibrium (A tan φ_A + B tan φ_B against the normal reactions N_A, N_B)
    angles = hoek_bray_wedge_angles()
    for phi_a, phi_b in ((30.0, 30.0), (20.0, 40.0)):
        assert hoek_bray_wedge_factor_of_safety(angles, 6.0, phi_a, phi_b) == pytest.approx(
            wedge_solution(*WEDGE_PLANES, phi_a, phi_b).factor_of_safety, rel=1e-12)


def test_hoek_bray_wedge_with_cohesion_and_water_equals_the_tetrahedron():
    # direct: FS = [c_A S_A + c_B S_B + (N_A − U_A) tan φ_A + (N_B − U_B) tan φ_B] / (W sin ψ5), with the faces'
    # areas S, the volume, N from the wedge solution and U = γ_w H S / 6 (pressure rising linearly from the
    # faces' outer edges to ½ γ_w H on the line of intersection: a pyramid of volume ⅓ S · ½ γ_w H)
    h, gamma, gamma_w, ca, cb, pa, pb = 6.0, 2600 * 9.81, 9810.0, 20e3, 10e3, 30.0, 35.0
    v = wedge_vertices(h)

    def area(p: np.ndarray, q: np.ndarray, r: np.ndarray) -> float:
        return 0.5 * float(np.linalg.norm(np.cross(q - p, r - p)))

    sa, sb = area(v["toe"], v["top"], v["crest A"]), area(v["toe"], v["top"], v["crest B"])
    weight = gamma * abs(float(np.dot(v["top"], np.cross(v["crest A"], v["crest B"])))) / 6.0
    s = wedge_solution(*WEDGE_PLANES, pa, pb)
    ua, ub = gamma_w * h * sa / 6.0, gamma_w * h * sb / 6.0
    direct = (ca * sa + cb * sb + (s.normal_a * weight - ua) * math.tan(math.radians(pa))
              + (s.normal_b * weight - ub) * math.tan(math.radians(pb))) / (weight * math.sin(math.radians(s.plunge)))
    ours = hoek_bray_wedge_factor_of_safety(hoek_bray_wedge_angles(), h, pa, pb, ca, cb, gamma, gamma_w)
    assert ours == pytest.approx(direct, rel=1e-12)
    # the wet wedge's closed form with Hoek & Bray's uplift (its γ is the wedge model's rock, 2600 × 9.81)
    assert wet_wedge_factor_of_safety(pa, pb, ua, ub, h, ca, cb) == pytest.approx(ours, rel=1e-12)
    assert wedge_faces(h) == pytest.approx((sa, sb, weight / gamma), rel=1e-12)


def test_wet_wedge_against_the_force_equilibrium():
    # independent route: the wedge's equilibrium solved as 3 equations, R_A n_A + R_B n_B − S l = W e_z (R: the
    # planes' whole normal reactions, S: the shear along the line of intersection l, pointing down), the
    # effective normal forces R − U; with cohesion and unequal friction: the same numbers to round-off
    h, pa, pb, ca, cb, level = 6.0, 30.0, 40.0, 3e3, 8e3, 2.5
    sa, sb, volume = wedge_faces(h)
    weight = 2600.0 * 9.81 * volume
    na, nb = plane_normal(*WEDGE_PLANES[0]), plane_normal(*WEDGE_PLANES[1])
    line = np.cross(na, nb)
    line = -line / np.linalg.norm(line) if line[2] > 0 else line / np.linalg.norm(line)
    ra, rb, shear = np.linalg.solve(np.column_stack([na, nb, -line]), [0.0, 0.0, weight])
    ua, ub = wedge_water_forces(level, h)
    resisting = (ra - ua) * math.tan(math.radians(pa)) + (rb - ub) * math.tan(math.radians(pb)) + ca * sa + cb * sb
    direct = resisting / shear
    assert wet_wedge_factor_of_safety(pa, pb, ua, ub, h, ca, cb) == pytest.approx(direct, rel=1e-12)


def test_wedge_water_forces_by_hand():
    # H = 6 m; a face's corners at z = 0 (toe), 6, 6: its centroid at z = 4. Level 9 m (above the face):
    # U = γ_w S (9 − 4) = 5 γ_w S. Level 3 m: the wet triangle is the face scaled by ½ (area S/4, centroid at
    # z = 2): U = γ_w (S/4)(3 − 2) = γ_w S/4. At the level of the top both give γ_w S·2. Dry below the toe.
    sa, sb, _ = wedge_faces(6.0)
    for level, head in ((9.0, 5.0), (3.0, 0.25), (6.0, 2.0)):
        assert wedge_water_forces(level, 6.0) == pytest.approx((UNIT_WEIGHT * sa * head, UNIT_WEIGHT * sb * head),
                                                               rel=1e-14)
    assert wedge_water_forces(-1.0, 6.0) == (0.0, 0.0)


def test_plane_failure_model_takes_hoek_bray_water_up_to_the_crack_depth():
    model = plane_failure_model(PLANE_FAILURE, water_depth=1.0)
    assert model.water is not None and model.water.cracks[0].depth == 1.0
    with pytest.raises(ValueError, match="water_depth"):
        plane_failure_model(PLANE_FAILURE, water_depth=PLANE_FAILURE.crack_depth * 1.01)


# -- strength reduction and the criterion ----------------------------------------------------------------
def test_reduce_strength_divides_the_named_joints_only():
    m = Model(gravity=(0.0, -9.81))
    m.add_material("rock", Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_joint_material("a", JointMaterial(friction_angle=30.0, cohesion=1e4, tensile_strength=2e3))
    m.add_joint_material("b", JointMaterial(friction_angle=40.0, cohesion=5e3, tensile_strength=1e3))
    m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
    arrays = m.arrays()
    reduced = reduce_strength(arrays, np.array([1]), 2.0).joints  # row 1: joint "a"
    assert reduced.friction_angle[1] == pytest.approx(math.atan(math.tan(math.radians(30.0)) / 2.0), rel=1e-15)
    assert (reduced.cohesion[1], reduced.tensile_strength[1]) == (5e3, 1e3)
    assert reduced.friction_angle[2] == arrays.joints.friction_angle[2]
    assert (reduced.cohesion[2], reduced.tensile_strength[2]) == (5e3, 1e3)  # "b" untouched
    assert arrays.joints.cohesion[1] == 1e4  # the model's arrays are not changed


def test_criterion_on_synthetic_displacements():
    c = FailureCriterion(steps=30)  # window 10; at rest below a growth of 1e-6 m (the threshold given below)
    steps = np.arange(31)
    sliding = 1e-4 * steps  # a steady rate: fails
    settled = 1e-3 * (1.0 - 0.5**steps)  # geometric settling: stable
    accelerating = 1e-5 * steps**2.0  # fails
    slowing = 1e-3 * np.sqrt(steps)  # growth 7.9e-4 then 9.5e-4: ratio 0.84 ≥ 0.5, fails (does not decay fast)
    assert judge(1.0, sliding, "completed", c, 1e-6).failed
    assert not judge(1.0, settled, "completed", c, 1e-6).failed
    assert judge(1.0, accelerating, "completed", c, 1e-6).failed
    assert judge(1.0, slowing, "completed", c, 1e-6).failed
    assert judge(1.0, sliding[:5], "stopped: time step below minimum", c, 1e-6).failed  # a stopped run fails
    # creep below the threshold is rest even at a steady rate
    assert not judge(1.0, 1e-8 * steps, "completed", c, 1e-6).failed
    with pytest.raises(FosError, match="steps"):
        FailureCriterion(steps=3)


def test_a_model_that_cannot_fail_is_an_error():
    m = Model(gravity=(0.0, -9.81))  # a block on flat ground: no F makes it slide
    m.add_material("rock", Material(density=2500.0, young=1e9, poisson=0.25))
    m.add_joint_material("j", JointMaterial(friction_angle=30.0), [("rock", "rock")])
    m.add_block([[-5, -1], [5, -1], [5, 0], [-5, 0]], "rock", fixed=True)
    m.add_block([[0, 0], [1, 0], [1, 0.5], [0, 0.5]], "rock")
    with pytest.raises(FosError, match="does not rest on the joints reduced"):
        factor_of_safety(m, RunSettings(dt=1e-3, n_steps=1), criterion=FailureCriterion(steps=9))


# -- the acceptance: verify cases ------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["fos-plane-2d", "fos-wedge-3d", "fos-plane-wet-2d", "fos-wedge-wet-3d"])
def test_verify_case_passes(name):
    rows = run_case(name)
    checked = [r for r in rows if r["passed"] is not None]
    assert checked and all(r["passed"] for r in checked), [r for r in checked if not r["passed"]]


def test_same_trials_on_one_and_two_dask_workers():
    # the trials depend on ``points`` only: here, in-process, and on two worker processes, bit for bit
    model = plane_failure_model(PLANE_FAILURE, young=1e12)
    settings = RunSettings(dt=1e-3, n_steps=1, contact_penalty=1e10)
    here = factor_of_safety(model, settings, tolerance=0.05, points=2)
    on_dask = factor_of_safety(model, settings, tolerance=0.05, points=2, workers=2)
    strip = [(t.factor, t.failed, t.growth, t.previous, t.displacement) for t in here.trials]
    assert strip == [(t.factor, t.failed, t.growth, t.previous, t.displacement) for t in on_dask.trials]
    assert (here.stable, here.failed) == (on_dask.stable, on_dask.failed)


def test_cli_fos(tmp_path):
    path = tmp_path / "plane.toml"
    save_model(plane_failure_model(PLANE_FAILURE, young=1e12), RunSettings(dt=1e-3, n_steps=1, contact_penalty=1e10),
               path)
    result = CliRunner().invoke(main, ["fos", str(path), "--tolerance", "0.02", "--json"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.output)
    assert data["stable"] < PLANE_FAILURE.factor_of_safety() * 1.02 and data["failed"] > data["stable"]
    assert data["failed"] - data["stable"] <= 0.02 * data["stable"]
    bad = CliRunner().invoke(main, ["fos", str(path), "--joint", "nope"])
    assert bad.exit_code == 2 and "unknown joint material 'nope'" in bad.output and "Traceback" not in bad.output


def test_cli_fos_of_a_wet_model_file(tmp_path):
    # water-plane-2d's block (φ = 40°) with Hoek & Bray's water, the crack 0.5 m deep, through a model file with
    # [water]: FS = 1.182 by the closed form (1.453 dry), and srdda fos finds it within the acceptance's 2 %
    model = wet_plane_model(40.0)
    set_hoek_bray_water(model, 0.5)
    path = tmp_path / "wet.toml"
    save_model(model, RunSettings(dt=1e-3, n_steps=1, penalty=1e10), path)
    assert "[water]" in path.read_text() and "[[water.cracks]]" in path.read_text()
    weight, _, _, _ = wet_plane_forces(None, 0.0)
    exact = plane_failure_factor(weight, PLANE_DIP, 40.0, *plane_failure_water_forces(BASE_LENGTH, 0.5))
    result = CliRunner().invoke(main, ["fos", str(path), "--tolerance", "0.01", "--json"])
    assert result.exit_code == 0, result.output
    assert json.loads(result.output)["factor_of_safety"] == pytest.approx(exact, rel=0.02)


def test_a_failing_wedge_moves_half_its_unbalanced_acceleration_per_static_step():
    # the basis of the rest threshold: a static step from rest moves a sliding block ½ a Δt², so the growth
    # over the last window is w · ½ a Δt² with the wedge's unbalanced acceleration a = g sin ψ_i (1 − FS/F)
    # (Hoek & Bray's wedge, friction reduced by F). Measured 3e-6 at F = 1.25, 2e-9 at 1.5: the contact
    # springs' settling is in the first window only
    phi = wedge_friction_for(1.2)
    model = wedge_model(phi)
    arrays, settings, criterion = model.arrays(), RunSettings(dt=1e-3, n_steps=1, penalty=1e11), FailureCriterion()
    dt = settle_dt(arrays, settings, criterion)
    plunge = math.radians(wedge_solution(*WEDGE_PLANES, phi).plunge)
    for factor in (1.25, 1.5):
        trial = try_factor(arrays, settings, np.arange(2), factor, criterion)
        acceleration = trial.growth / (criterion.window * 0.5 * dt * dt)
        assert acceleration == pytest.approx(9.81 * math.sin(plunge) * (1.0 - 1.2 / factor), rel=1e-5)


def test_the_bracket_is_found_from_above_and_below():
    # from F = 4 the search halves, from F = 0.3 it doubles: both end in a bracket holding the closed form's FS
    # (within the 2 % of the acceptance) no wider than the tolerance
    model = plane_failure_model(PLANE_FAILURE, young=1e12)
    settings = RunSettings(dt=1e-3, n_steps=1, contact_penalty=1e10)
    exact = PLANE_FAILURE.factor_of_safety()
    for initial in (4.0, 0.3):
        fos = factor_of_safety(model, settings, tolerance=0.01, initial=initial)
        assert fos.failed - fos.stable <= 0.01 * fos.stable
        assert fos.stable * 0.98 < exact < fos.failed * 1.02
        assert fos.trials[0].failed == (initial > exact)
    with pytest.raises(FosError, match="joints: unknown joint material 'nope'; the model's are: 'plane'"):
        factor_of_safety(model, settings, joints=["nope"])
