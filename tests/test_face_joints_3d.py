"""Joint materials per face of 3D blocks: a contact on a face takes the face's joint material
(as 2D edges do), from Model.add_polyhedron, from a cut's joint types and from the model file."""
import tomllib

import numpy as np
import pytest

import srdda
from srdda.contact import ContactModel, ContactParameters
from srdda.geometry.polyhedron import box
from srdda.io.modelfile import ModelFileError, model_from_dict

PSI = np.radians(30.0)
G = 9.81
TILTED = (G * np.sin(PSI), 0.0, -G * np.cos(PSI))  # a level plane under gravity tilted by ψ = a ψ incline


def _model(top_joint: str | None) -> srdda.Model:
    m = srdda.Model(gravity=TILTED)
    m.add_material("rock", srdda.Material(2500.0, 1e9, 0.25))
    m.add_joint_material("smooth", srdda.JointMaterial(friction_angle=20.0), between=[("rock", "rock")])
    m.add_joint_material("rough", srdda.JointMaterial(friction_angle=40.0))
    verts, faces = box([-1.0, -2.0, -1.0], [6.0, 2.0, 0.0])
    top = [k for k, f in enumerate(faces) if np.all(np.asarray(verts)[f, 2] == 0.0)]
    names = [top_joint if k in top else None for k in range(len(faces))]
    m.add_polyhedron(verts, faces, "rock", fixed=True, name="plane", face_joints=names)
    m.add_polyhedron(*box([0.0, -0.5, 0.0], [1.0, 0.5, 0.5]), "rock", name="block")
    return m


@pytest.mark.parametrize("top_joint, friction", [(None, 20.0), ("rough", 40.0)])
def test_a_contact_on_a_face_takes_the_face_joint_material(top_joint, friction):
    arrays = _model(top_joint).arrays()
    contacts = ContactModel(arrays, ContactParameters(1e10, 4e9, 0.01, np.radians(3.0), 0.004))
    step = contacts.prepare(arrays.vertex_position, None, True)
    # the block's four bottom corners touch the plane's top face: each contact's friction is the face's
    np.testing.assert_allclose(step.response.friction, np.tan(np.radians(friction)), rtol=1e-15)


@pytest.mark.slow
def test_a_rough_face_holds_the_block_that_the_material_joint_lets_slide():
    # ψ = 30°: φ = 20° slides at g(sin ψ − cos ψ tan φ) = 1.813 m/s², φ = 40° holds; 0.5 s
    settings = srdda.RunSettings(dt=1e-3, n_steps=500, contact_penalty=1e10)
    travel = {}
    for top_joint in (None, "rough"):
        r = srdda.run(_model(top_joint), settings)
        travel[top_joint] = float(r.array("centroid")[-1, 1, 0] - r.array("centroid")[0, 1, 0])
    # sliding: ½ a t² = 0.2266 m (the springs' settling adds well under 1e-3 m)
    assert abs(travel[None] - 0.5 * 1.8128 * 0.5**2) < 1e-3
    assert abs(travel["rough"]) < 1e-5  # at rest: the springs' settling only (about 1e-6 m)


CUT_MODEL = """
gravity = [0.0, 0.0, -9.81]
[run]
dt = "1 ms"
steps = 1
[materials.rock]
density = 2600.0
young = "10 GPa"
poisson = 0.25
[joint_materials.mass]
friction_angle = 30.0
between = [["rock", "rock"]]
[joint_materials.bedding]
friction_angle = 15.0
[cutting]
[[cutting.domain]]
material = "rock"
box = [[0, 0, 0], [4, 2, 2]]
[[cutting.joint_sets]]
dip = 0.0
dip_direction = 0.0
spacing = 1.0
origin = [0.0, 0.0, 0.5]
joint_type = 2
joint_material = "bedding"
[[cutting.joint_sets]]
dip = 90.0
dip_direction = 90.0
spacing = 3.0
origin = [1.0, 0.0, 0.0]
joint_type = 3
"""


def test_a_cut_joint_set_names_the_joint_material_of_its_faces():
    model, _ = model_from_dict(tomllib.loads(CUT_MODEL))
    arrays = model.arrays()
    mesh = arrays.mesh
    names = ["default", *model.joint_materials]
    normal_z = []
    for k in range(len(mesh.face_block)):
        p = mesh.vertices[mesh.face_vertex[mesh.face_ptr[k]:mesh.face_ptr[k + 1]]]
        normal_z.append(np.ptp(p[:, 2]) == 0.0 and 0.0 < p[0, 2] < 2.0)  # an inner horizontal face
    inner = np.array(normal_z)
    # the bedding planes z = 0.5 and 1.5 make every inner horizontal face; the vertical set (type 3)
    # names no material, nor do the domain's faces
    assert inner.sum() > 0
    assert {names[j] for j in arrays.face_joint[inner]} == {"bedding"}
    assert set(arrays.face_joint[~inner]) == {-1}


def test_a_joint_type_with_two_materials_is_an_error_naming_the_field():
    text = CUT_MODEL.replace("joint_type = 3", 'joint_type = 2\njoint_material = "mass"')
    with pytest.raises(ModelFileError, match=r"joint_sets\[1\]\.joint_material: joint_type 2 already has"):
        model_from_dict(tomllib.loads(text))
