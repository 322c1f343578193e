"""Polygon integrals against closed forms, and polygon validation."""
import numpy as np
import pytest

from srdda.geometry import PolygonError, block_moments, normalize_polygon


def _moments(*polys):
    v = np.concatenate(polys)
    ptr = np.concatenate([[0], np.cumsum([len(p) for p in polys])])
    return block_moments(v, ptr)


def test_rectangle_closed_form():
    # b x h rectangle: A = bh, Ixx about centroid = h b³/12 (∫x²), Iyy = b h³/12, Ixy = 0.
    b, h = 3.0, 0.5
    rect = np.array([[10, 20], [10 + b, 20], [10 + b, 20 + h], [10, 20 + h]], float)
    m = _moments(rect)
    # exact arithmetic up to round-off of O(1e-16 * 10²) from the offset
    assert m.area[0] == pytest.approx(b * h, rel=1e-14)
    assert m.centroid[0] == pytest.approx([10 + b / 2, 20 + h / 2], rel=1e-14)
    assert m.sxx[0] == pytest.approx(h * b**3 / 12, rel=1e-12)
    assert m.syy[0] == pytest.approx(b * h**3 / 12, rel=1e-12)
    assert abs(m.sxy[0]) < 1e-12


def test_right_triangle_closed_form():
    # legs a (x) and c (y) at the origin: A = ac/2, centroid (a/3, c/3),
    # central ∫x² = c a³/36, ∫y² = a c³/36, ∫xy = -a² c²/72.
    a, c = 2.0, 1.0
    tri = np.array([[0, 0], [a, 0], [0, c]], float)
    m = _moments(tri)
    assert m.area[0] == pytest.approx(a * c / 2, rel=1e-15)
    assert m.centroid[0] == pytest.approx([a / 3, c / 3], rel=1e-15)
    assert m.sxx[0] == pytest.approx(c * a**3 / 36, rel=1e-14)
    assert m.syy[0] == pytest.approx(a * c**3 / 36, rel=1e-14)
    assert m.sxy[0] == pytest.approx(-(a**2) * c**2 / 72, rel=1e-14)


def test_concave_l_shape_is_sum_of_rectangles():
    # L-shape = 2x1 rectangle + 1x1 square; moments add about the global origin.
    L = np.array([[0, 0], [2, 0], [2, 1], [1, 1], [1, 2], [0, 2]], float)
    r1 = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    r2 = np.array([[0, 1], [1, 1], [1, 2], [0, 2]], float)
    m = _moments(L, r1, r2)
    assert m.area[0] == pytest.approx(m.area[1] + m.area[2], rel=1e-15)
    c = (m.area[1] * m.centroid[1] + m.area[2] * m.centroid[2]) / m.area[0]
    assert m.centroid[0] == pytest.approx(c, rel=1e-15)
    # parallel-axis theorem for the union
    sxx = sum(m.sxx[i] + m.area[i] * (m.centroid[i, 0] - c[0]) ** 2 for i in (1, 2))
    sxy = sum(m.sxy[i] + m.area[i] * (m.centroid[i, 0] - c[0]) * (m.centroid[i, 1] - c[1]) for i in (1, 2))
    assert m.sxx[0] == pytest.approx(sxx, rel=1e-14)
    assert m.sxy[0] == pytest.approx(sxy, rel=1e-14)


def test_regular_polygon_approaches_disc():
    # A regular n-gon of circumradius R has area n R² sin(2π/n)/2 (exact).
    n, R = 64, 2.0
    ang = 2 * np.pi * np.arange(n) / n
    poly = np.column_stack([R * np.cos(ang), R * np.sin(ang)])
    m = _moments(poly)
    assert m.area[0] == pytest.approx(n * R**2 * np.sin(2 * np.pi / n) / 2, rel=1e-14)
    assert m.sxx[0] == pytest.approx(m.syy[0], rel=1e-13)  # rotational symmetry


def test_normalize_orientation_and_closing_vertex():
    cw = [[0, 0], [0, 1], [1, 1], [1, 0], [0, 0]]
    v = normalize_polygon(cw, "b")
    assert len(v) == 4
    x, y = v[:, 0], v[:, 1]
    assert 0.5 * np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y) > 0


@pytest.mark.parametrize(
    "verts, message",
    [
        ([[0, 0], [1, 1], [1, 0], [0, 1]], "not simple"),  # bow-tie
        ([[0, 0], [1, 0], [2, 0]], "zero area"),  # collinear
        ([[0, 0], [1, 0]], "at least 3"),
        ([[0, 0], [1, 0], [float("nan"), 1]], "finite"),
    ],
)
def test_bad_polygons_are_rejected_with_the_block_name(verts, message):
    with pytest.raises(PolygonError, match=message) as info:
        normalize_polygon(verts, "block 7")
    assert "block 7" in str(info.value)
