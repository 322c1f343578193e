"""Polyhedral blocks: exact integrals against closed forms, orientation repair, validation, meshio input."""
import meshio
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from srdda.geometry import (
    PolyhedronError,
    PolyhedronMesh,
    box,
    normalize_polyhedron,
    polyhedra_from_meshio,
    polyhedron_moments,
    prism,
)

L_SHAPE = [[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]]


def _moments(*blocks):
    mesh = PolyhedronMesh.from_blocks(list(blocks))
    return polyhedron_moments(mesh.vertices, mesh)


def _box_second(dims, volume):
    """Central ∫X_i X_j dV of a box with side lengths ``dims``: diag(V a²/12)."""
    return np.diag(volume * np.asarray(dims, float) ** 2 / 12)


def _inertia(second):
    """Inertia tensor per unit density, ∫(|X|² I - X Xᵀ) dV, from the second moments."""
    return np.trace(second) * np.eye(3) - second


def _directed_edges(faces):
    return [(int(f[i]), int(f[(i + 1) % len(f)])) for f in faces for i in range(len(f))]


def test_box_closed_form():
    # a x b x c box far from the origin: V = abc, centroid the middle, central ∫X² = V a²/12, no products.
    lo, dims = np.array([100.0, -50.0, 20.0]), np.array([1.5, 2.0, 0.25])
    m = _moments(box(lo, lo + dims))
    V = np.prod(dims)
    # the corners are exact binary numbers; 1e-14 allows round-off of the sums of 12 tetrahedra
    assert m.volume[0] == pytest.approx(V, rel=1e-14)
    assert np.allclose(m.centroid[0], lo + dims / 2, rtol=1e-14, atol=0)
    assert np.allclose(m.second[0], _box_second(dims, V), rtol=0, atol=1e-14 * V * dims.max() ** 2)


def test_tetrahedron_closed_form():
    # corner tetrahedron O, a e1, b e2, c e3: V = abc/6, centroid (a, b, c)/4 and central second
    # moments V/80 [[3a², -ab, -ac], [-ab, 3b², -bc], [-ac, -bc, 3c²]] (from ∫x² = V a²/10, ∫xy = V ab/20).
    a, b, c = 2.0, 3.0, 0.5
    v = np.array([[0, 0, 0], [a, 0, 0], [0, b, 0], [0, 0, c]])
    faces = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]
    m = _moments((v, faces))
    V = a * b * c / 6
    expected = V / 80 * np.array([[3 * a * a, -a * b, -a * c], [-a * b, 3 * b * b, -b * c], [-a * c, -b * c, 3 * c * c]])
    # a few ulps of the sums of order V·a²
    assert m.volume[0] == pytest.approx(V, rel=1e-14)
    assert np.allclose(m.centroid[0], [a / 4, b / 4, c / 4], rtol=1e-14, atol=1e-15)
    assert np.allclose(m.second[0], expected, rtol=0, atol=1e-14 * V * b * b)


def test_triangular_prism_closed_form():
    # right triangle with legs a (x), b (y) extruded over h: in-plane moments are the triangle's times h
    # (∫X² = h b a³/36, ∫Y² = h a b³/36, ∫XY = -h a² b²/72) and ∫Z² = A h³/12.
    a, b, z0, h = 2.0, 1.0, -1.0, 3.0
    m = _moments(prism([[0, 0], [a, 0], [0, b]], z0, z0 + h))
    area = a * b / 2
    expected = np.array([[h * b * a**3 / 36, -h * a * a * b * b / 72, 0],
                         [-h * a * a * b * b / 72, h * a * b**3 / 36, 0],
                         [0, 0, area * h**3 / 12]])
    assert m.volume[0] == pytest.approx(area * h, rel=1e-14)  # round-off only
    assert np.allclose(m.centroid[0], [a / 3, b / 3, z0 + h / 2], rtol=1e-14, atol=1e-15)
    assert np.allclose(m.second[0], expected, rtol=0, atol=1e-14 * area * h**3)


def test_concave_l_prism_closed_form():
    # The L-prism is the union of the boxes [0,2]x[0,1] and [0,1]x[1,2] (height h): volume and first
    # moments add, and second moments follow from the parallel-axis theorem. Closed form with h = 1:
    # V = 3, centroid (5/6, 5/6, 1/2), ∫X² = ∫Y² = 11/12, ∫XY = -1/3, ∫Z² = 1/4, so the inertia
    # tensor is Ixx = Iyy = 11/12 + 1/4 = 7/6, Izz = 11/6, Ixy = +1/3.
    h = 1.0
    m = _moments(prism(L_SHAPE, 0.0, h))
    parts = [(np.array([1.0, 0.5, 0.5]), np.array([2.0, 1.0, h])), (np.array([0.5, 1.5, 0.5]), np.array([1.0, 1.0, h]))]
    V = sum(np.prod(d) for _, d in parts)
    c = sum(np.prod(d) * ctr for ctr, d in parts) / V
    S = sum(_box_second(d, np.prod(d)) + np.prod(d) * np.outer(ctr - c, ctr - c) for ctr, d in parts)
    assert V == 3.0 and np.allclose(c, [5 / 6, 5 / 6, 0.5]) and np.allclose(S[0, 1], -1 / 3)
    # the L's faces are fanned into overlapping signed triangles; the sums stay exact to round-off
    assert m.volume[0] == pytest.approx(V, rel=1e-14)
    assert np.allclose(m.centroid[0], c, rtol=1e-14, atol=0)
    assert np.allclose(m.second[0], S, rtol=0, atol=1e-14)
    assert np.allclose(_inertia(m.second[0]), [[7 / 6, 1 / 3, 0], [1 / 3, 7 / 6, 0], [0, 0, 11 / 6]],
                       rtol=0, atol=1e-14)


def test_mesh_layout_and_fan():
    # two blocks: a box (6 quads -> 12 fan triangles) and the L-prism (2 hexagons + 6 quads -> 20)
    mesh = PolyhedronMesh.from_blocks([box([0, 0, 0], [1, 1, 1]), prism(L_SHAPE, 0, 1)], labels=["a", "b"])
    assert mesh.n_blocks == 2
    assert mesh.block_ptr.tolist() == [0, 8, 20]
    assert mesh.vertex_block.tolist() == [0] * 8 + [1] * 12
    assert len(mesh.face_ptr) - 1 == 14 and mesh.face_block.tolist() == [0] * 6 + [1] * 8
    assert mesh.tri_ptr.tolist() == [0, 12, 32] and len(mesh.tri) == 32
    assert np.all(mesh.tri_block == mesh.face_block[mesh.tri_face])
    # every fan triangle uses vertices of its own block, starting at its face's first vertex
    assert np.all(mesh.vertex_block[mesh.tri] == mesh.tri_block[:, None])
    assert np.all(mesh.tri[:, 0] == mesh.face_vertex[mesh.face_ptr[mesh.tri_face]])


def _box_faces():
    return box([0, 0, 0], [1, 2, 3])


def test_inward_faces_are_turned_outward():
    v, faces = _box_faces()
    inward = [f[::-1] for f in faces]
    _, fixed = normalize_polyhedron(v, inward, "B1")
    assert [f.tolist() for f in fixed] == [f.tolist() for f in faces]


def test_mixed_orientation_is_made_consistent():
    v, faces = _box_faces()
    mixed = [f[::-1] if k in (1, 2, 4) else np.roll(f, k) for k, f in enumerate(faces)]
    _, fixed = normalize_polyhedron(v, mixed, "B1")
    edges = _directed_edges(fixed)
    assert len(set(edges)) == len(edges)  # no edge twice in the same direction ...
    assert all((b, a) in set(edges) for a, b in edges)  # ... and every edge once the other way
    mesh = PolyhedronMesh.from_blocks([(v, mixed)])
    assert polyhedron_moments(mesh.vertices, mesh).volume[0] == pytest.approx(6.0, rel=1e-14)


def test_concave_prism_given_inward_is_repaired():
    v, faces = prism(L_SHAPE, 0, 1)
    m = _moments((v, [f[::-1] for f in faces]))
    assert m.volume[0] == pytest.approx(3.0, rel=1e-14)


def _pinched_torus():
    """A square ring around the z axis whose cross-section at 180° is shrunk to one point."""
    section = [(2, -0.5), (3, -0.5), (3, 0.5), (2, 0.5)]  # (radius, z) corners of a cross-section
    v = []
    for phi in (0.0, 0.5 * np.pi, 1.5 * np.pi):
        v += [[r * np.cos(phi), r * np.sin(phi), z] for r, z in section]
    v.append([-2.5, 0.0, 0.0])
    s0, s1, s3, p = [0, 1, 2, 3], [4, 5, 6, 7], [8, 9, 10, 11], 12
    faces = []
    for a, b in ((s0, s1), (s3, s0)):
        faces += [[a[i], a[(i + 1) % 4], b[(i + 1) % 4], b[i]] for i in range(4)]
    for a in (s1, s3):
        faces += [[a[i], a[(i + 1) % 4], p] for i in range(4)]
    return np.array(v), faces


def _tetrahemihexahedron():
    """A non-orientable closed surface of planar faces (the projective plane; octahedron vertices)."""
    v = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [-1, 0, 0], [0, -1, 0], [0, 0, -1]], float)
    faces = [[0, 1, 3, 4], [1, 2, 4, 5], [2, 0, 5, 3], [0, 1, 2], [0, 4, 5], [3, 1, 5], [3, 4, 2]]
    return v, faces


CUBE_V, CUBE_F = box([0, 0, 0], [1, 1, 1])
CUBE_F = [f.tolist() for f in CUBE_F]
TET_V = [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]
TET_F = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]


@pytest.mark.parametrize("vertices, faces, message", [
    (TET_V[:3], TET_F, "needs at least 4 vertices, got 3"),
    ([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, np.nan]], TET_F, "must be finite"),
    ([[0, 0], [1, 0], [0, 1], [1, 1]], TET_F, "list of [x, y, z] triples"),
    (TET_V, "abc", "faces must be a list"),
    (TET_V, TET_F[:3], "needs at least 4 faces, got 3"),
    (TET_V, [[0, 2], *TET_F[1:]], "face 0 has 2 vertices"),
    (TET_V, [[0, 2, 1.5], *TET_F[1:]], "face 0 must be a list of integer vertex indices"),
    (TET_V, [[0, 2, 4], *TET_F[1:]], "face 0 refers to vertex 4, but the block has 4 vertices"),
    (TET_V, [[0, 2, 2], *TET_F[1:]], "face 0 repeats a vertex"),
    ([*TET_V, [1, 0, 0]], TET_F, "vertices 1 and 4 coincide"),
    ([*TET_V, [5, 5, 5]], TET_F, "vertex 4 is on no face"),
    (np.vstack([CUBE_V[:6], CUBE_V[6] + [0, 0, 0.01], CUBE_V[7]]), CUBE_F, "is not planar (vertex"),
    ([*TET_V, [0.5, 0, 0]], [*TET_F, [0, 4, 1]], "face 4 has zero area"),
    (CUBE_V, [[0, 2, 3, 1] if k == 0 else f for k, f in enumerate(CUBE_F)], "face 0 has zero area"),  # bow-tie
    (*prism(L_SHAPE, 0, 1)[:1], [[6, 8, 7, 9, 10, 11] if k == 1 else f for k, f in enumerate(prism(L_SHAPE, 0, 1)[1])],
     "face 1 is not a simple polygon (Self-intersection"),
    (CUBE_V, CUBE_F[:5], "edge (0, 3) is used by 1 face, the surface is not closed"),
    (CUBE_V, [*CUBE_F, [0, 1, 6, 7]], "is used by 3 faces, the surface is not manifold"),
    (np.vstack([TET_V, np.add(TET_V, 5)]), TET_F + [[a + 4, b + 4, c + 4] for a, b, c in TET_F],
     "the faces form 2 separate closed surfaces"),
    (*_pinched_torus(), "the surface touches itself at vertex 12 (not manifold)"),
    (*_tetrahemihexahedron(), "the surface is not orientable"),
    ([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], [[0, 1, 2], [0, 2, 3], [0, 3, 1], [1, 3, 2]],
     "zero volume (it is flat)"),
])
def test_invalid_block_is_one_clear_error(vertices, faces, message):
    with pytest.raises(PolyhedronError) as err:
        normalize_polyhedron(vertices, faces, "B3")
    assert str(err.value).startswith("block 'B3': ")
    assert message in str(err.value)


def test_mesh_errors_name_the_block():
    good = box([0, 0, 0], [1, 1, 1])
    with pytest.raises(PolyhedronError, match="block 'second': edge"):
        PolyhedronMesh.from_blocks([good, (CUBE_V, CUBE_F[:5])], labels=["first", "second"])
    with pytest.raises(PolyhedronError, match="at least one block"):
        PolyhedronMesh.from_blocks([])
    with pytest.raises(PolyhedronError, match="got 1 labels for 2 blocks"):
        PolyhedronMesh.from_blocks([good, good], labels=["first"])


def test_constructor_errors():
    with pytest.raises(PolyhedronError, match="hi > lo"):
        box([0, 0, 0], [1, 0, 1])
    with pytest.raises(PolyhedronError, match="z0 < z1"):
        prism(L_SHAPE, 1.0, 1.0)
    with pytest.raises(PolyhedronError, match="not simple"):
        prism([[0, 0], [1, 1], [1, 0], [0, 1]], 0, 1)


def _triangulated(faces):
    return np.array([[f[0], f[i], f[i + 1]] for f in faces for i in range(1, len(f) - 1)])


def test_meshio_round_trip(tmp_path):
    # a box as quads and an L-prism as polygons/quads in one surface file; each surface is one block
    bv, bf = box([5, 0, 0], [6, 2, 1])
    lv, lf = prism(L_SHAPE, 0, 1)
    points = np.vstack([bv, lv])
    quads = np.array([f for f in bf] + [f + len(bv) for f in lf if len(f) == 4])
    hexagons = np.array([f + len(bv) for f in lf if len(f) == 6])
    path = tmp_path / "blocks.vtu"
    meshio.write(path, meshio.Mesh(points, [("quad", quads), ("polygon", hexagons)]))
    blocks = polyhedra_from_meshio(meshio.read(path), label="blocks.vtu")
    assert len(blocks) == 2
    m = _moments(*blocks)
    expected = _moments((bv, bf), (lv, lf))
    # the file stores float64 coordinates exactly; the same surfaces give the same integrals
    assert np.allclose(m.volume, expected.volume, rtol=1e-14)
    assert np.allclose(m.centroid, expected.centroid, rtol=1e-14)
    assert np.allclose(m.second, expected.second, rtol=0, atol=1e-14)


def test_meshio_interleaved_surfaces():
    # two boxes whose points and faces are shuffled together: each surface is found and renumbered
    rng = np.random.default_rng(5)
    (av, af), (bv, bf) = box([0, 0, 0], [1, 1, 1]), box([3, 0, 0], [5, 1, 2])
    points = np.vstack([av, bv])
    quads = np.array([*af, *(f + 8 for f in bf)])
    perm = rng.permutation(16)  # new position of each point
    shuffled = np.empty_like(points)
    shuffled[perm] = points
    blocks = polyhedra_from_meshio(meshio.Mesh(shuffled, [("quad", perm[quads][rng.permutation(12)])]))
    m = _moments(*blocks)
    assert sorted(m.volume.tolist()) == [1.0, 4.0]  # exact: unit and 2x1x2 boxes
    assert sorted(m.centroid[:, 0].tolist()) == [0.5, 4.0]


def test_meshio_stl_triangles(tmp_path):
    # STL stores triangles with repeated coordinates; meshio merges them, and the box is one block
    v, f = box([0, 0, 0], [1, 2, 3])
    path = tmp_path / "box.stl"
    meshio.write(path, meshio.Mesh(v, [("triangle", _triangulated(f))]), binary=True)
    (block,) = polyhedra_from_meshio(meshio.read(path))
    m = _moments(block)
    assert m.volume[0] == pytest.approx(6.0, rel=1e-14)  # binary STL is float32: these corners are exact
    assert np.allclose(m.second[0], _box_second([1, 2, 3], 6.0), rtol=0, atol=1e-13)


def test_meshio_open_or_volume_mesh_is_an_error():
    v, f = box([0, 0, 0], [1, 1, 1])
    with pytest.raises(PolyhedronError, match="'cube surface 0': edge .* not closed"):
        polyhedra_from_meshio(meshio.Mesh(v, [("quad", np.array(f[:5]))]), label="cube")
    with pytest.raises(PolyhedronError, match="'tetra' are not surface polygons"):
        polyhedra_from_meshio(meshio.Mesh(v[:4], [("tetra", np.array([[0, 1, 2, 4 - 1]]))]))
    with pytest.raises(PolyhedronError, match="no triangle, quad or polygon cells"):
        polyhedra_from_meshio(meshio.Mesh(v, [("line", np.array([[0, 1]]))]))


def _rotation(q):
    """Proper rotation from a (non-zero) quaternion."""
    w, x, y, z = np.asarray(q) / np.linalg.norm(q)
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


_REFERENCE = PolyhedronMesh.from_blocks([prism(L_SHAPE, 0, 1.5), box([0, 0, 0], [0.5, 1, 2]),
                                         (TET_V, TET_F)])
_REFERENCE_MOMENTS = polyhedron_moments(_REFERENCE.vertices, _REFERENCE)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-1, 1), min_size=4, max_size=4).filter(lambda q: np.linalg.norm(q) > 0.1),
       st.lists(st.floats(-100, 100), min_size=3, max_size=3))
def test_moments_invariant_under_rigid_motion(q, shift):
    R, t = _rotation(q), np.array(shift)
    moved = _REFERENCE.vertices @ R.T + t
    m = polyhedron_moments(moved, _REFERENCE)
    ref = _REFERENCE_MOMENTS
    # Blocks of size ~2 moved up to 100 away: the per-block shift to the vertex mean keeps the sums
    # exact to round-off of the moved coordinates (~1e-14 relative to the block size).
    assert np.allclose(m.volume, ref.volume, rtol=1e-12, atol=0)
    assert np.allclose(m.centroid, ref.centroid @ R.T + t, rtol=0, atol=1e-12)
    rotated = R @ ref.second @ R.T
    assert np.allclose(m.second, rotated, rtol=0, atol=1e-12 * np.abs(ref.second).max())
