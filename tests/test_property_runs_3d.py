"""Property-based drop test in 3D (hypothesis; issue 15's drop test, the 3D half).

Random convex blocks (the convex hull of 6 to 12 random points on a randomly
stretched sphere), dropped at random orientations, speeds and spins on a
fixed base under srdda and dda1: the mechanical energy plus what friction
dissipated so far (kinetic + potential + strain + contact springs + the
ledger's ``dissipated_friction``) never rises above its initial value by more
than 1e-6 of the block's energy above the base (measured: rounding, below
1e-13). Contacts dissipate or store energy; they never create it. Under srdda
the whole balance, with the penalty's loss ``dissipated_contact`` booked too,
keeps that bound; dda1's post-adjusted rotation moves the contact points off
the linear motion the ledger books the springs' work over, so its balance
moves by up to about 1e-4 of the impact's loss in single steps.
"""
from __future__ import annotations

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from scipy.spatial import ConvexHull

import srdda
from srdda.geometry.polyhedron import box
from srdda.kinematics.shape3d import rotation_matrix_3d

G = -9.81


@st.composite
def convex_polyhedron(draw):
    n = draw(st.integers(6, 12))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(n, 3))
    points /= np.linalg.norm(points, axis=1)[:, None]
    points *= np.array([1.0, draw(st.floats(0.4, 1.0)), draw(st.floats(0.4, 1.0))]) * draw(st.floats(0.15, 0.5))
    hull = ConvexHull(points)
    assume(len(hull.vertices) == n)  # every point a corner
    tri = points[hull.simplices]
    area = 0.5 * np.linalg.norm(np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]), axis=1)
    size = np.ptp(points, axis=0).max()
    assume(area.min() > 1e-3 * size**2)  # no sliver faces
    normals = hull.equations[:, :3]
    # no two neighbouring triangles (nearly) coplanar: they would be one face with an edge of 180°
    assume(np.all(np.einsum("ij,ikj->ik", normals, normals[hull.neighbors]) < 0.999))
    return points, hull.simplices


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(block=convex_polyhedron(), height=st.floats(0.02, 0.3),
       v=st.tuples(st.floats(-2, 2), st.floats(-2, 2), st.floats(-1, 0)),
       omega=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
       turn=st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
       method=st.sampled_from(["dda1", "srdda"]))
def test_a_dropped_polyhedron_never_creates_energy(block, height, v, omega, turn, method):
    points, faces = block
    points = points @ rotation_matrix_3d(np.array([turn]))[0].T
    points = points - [0.0, 0.0, points[:, 2].min() - height]  # lowest vertex `height` above the base
    m = srdda.Model(gravity=(0.0, 0.0, G))
    m.add_material("rock", srdda.Material(2600.0, 1e10, 0.25))
    m.add_joint_material("j", srdda.JointMaterial(friction_angle=30.0), between=[("rock", "rock")])
    m.add_polyhedron(*box((-4, -4, -1), (4, 4, 0)), "rock", fixed=True)
    m.add_polyhedron(points, faces, "rock", velocity=v, angular_velocity=omega)
    result = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=400, method=method, penalty=1e11))
    assert result.completed, result.status
    names = list(result.energy[0])
    energy = result.array("energy")
    balance = energy[:, names.index("balance")]
    not_booked = balance - energy[:, names.index("dissipated_contact")]  # the penalty's loss counted as a loss
    arrays = m.arrays()
    centroid_height = arrays.moments(arrays.vertex_position).centroid[1, 2]
    scale = energy[0, names.index("kinetic")] + abs(G) * arrays.block_mass[1] * centroid_height
    assert np.max(not_booked - not_booked[0]) <= 1e-6 * scale
    if method == "srdda":
        assert np.max(balance - balance[0]) <= 1e-6 * scale
