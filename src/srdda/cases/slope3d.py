"""The classical 3D rock-slope checks: closed forms and the models that reproduce them.

Orientation convention as :mod:`srdda.geometry.jointsets3d`: x east, y north,
z up; dip (0-90°) and dip direction (clockwise from north) in degrees;
gravity (0, 0, -g). Angles in the functions below are in degrees.

* **Block on an incline** (plane dipping ψ, joint friction φ, no cohesion):
  at rest iff tan φ >= tan ψ; otherwise it slides down the dip with
  a = g (sin ψ - cos ψ tan φ).
* **Sliding and toppling** of a block of base b (along the dip) and height h
  on the incline (A. M. Ashby, *Sliding and toppling modes of failure in
  models and jointed rock slopes*, M.Sc. thesis, Imperial College, 1971;
  E. Hoek & J. W. Bray, *Rock Slope Engineering*, 3rd ed., IMM, London,
  1981, ch. 9; R. E. Goodman & J. W. Bray, "Toppling of rock slopes", ASCE
  Specialty Conference on Rock Engineering for Foundations and Slopes,
  Boulder, 1976, vol. 2, 201-234): it slides when tan ψ > tan φ, topples when
  b/h < tan ψ (the weight's line of action falls outside the base); four
  regions: stable, slides, topples, slides and topples.
* **Tetrahedral wedge** on two joint planes A and B (Hoek & Bray 1981,
  ch. 8): with no cohesion and no water, the normal reactions N_A, N_B
  balance the weight's component perpendicular to the line of intersection
  (plunge ψ_i); FS = (N_A tan φ_A + N_B tan φ_B) / (W sin ψ_i). When FS < 1
  the wedge slides along the line of intersection keeping contact with both
  planes, so N_A and N_B stay and a = g sin ψ_i (1 - FS).

The builders return :class:`~srdda.model.Model` s with real inclined
geometry (no tilted gravity) and fixed joint-plane blocks; they need 3D
contacts to run.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry.cutting3d import halfspace_polyhedron
from ..geometry.jointsets3d import plane_normal
from ..geometry.polyhedron import box
from ..model import JointMaterial, Material, Model

__all__ = ["G", "SLIDE_TOPPLE_CASES", "SlideToppleCase", "WedgeSolution", "block_on_incline_model",
           "incline_acceleration", "slide_topple_mode", "slide_topple_model", "toppling_angular_acceleration",
           "wedge_friction_for", "wedge_model", "wedge_solution", "WEDGE_PLANES", "WEDGE_FACE"]

G = 9.81  # m/s²
ROCK = Material(density=2600.0, young=10e9, poisson=0.25)


# -- block on an incline, sliding and toppling ----------------------------------------------------------
def incline_acceleration(psi: float, phi: float, g: float = G) -> float:
    """Acceleration down the dip of a block on a plane dipping ψ with friction φ: 0 when tan φ >= tan ψ."""
    p, f = np.radians(psi), np.radians(phi)
    return 0.0 if np.tan(f) >= np.tan(p) else float(g * (np.sin(p) - np.cos(p) * np.tan(f)))


def slide_topple_mode(psi: float, phi: float, base: float, height: float) -> str:
    """The region of the sliding / toppling chart: "stable", "slides", "topples" or "slides and topples"."""
    t = np.tan(np.radians(psi))
    slides = t > np.tan(np.radians(phi))
    topples = base / height < t
    return {(False, False): "stable", (True, False): "slides", (False, True): "topples",
            (True, True): "slides and topples"}[(bool(slides), bool(topples))]


def toppling_angular_acceleration(psi: float, base: float, height: float, g: float = G) -> float:
    """Initial angular acceleration (rad/s²) of a rectangular block toppling about its down-dip base edge.

    Moment of the weight about the edge m g (h sin ψ - b cos ψ)/2 over the
    moment of inertia about the edge m (b² + h²)/3 (the edge does not slip:
    the "topples" region). Negative: the block does not topple.
    """
    p = np.radians(psi)
    return float(1.5 * g * (height * np.sin(p) - base * np.cos(p)) / (base**2 + height**2))


@dataclass(frozen=True)
class SlideToppleCase:
    """One block on an incline: dip ψ, friction φ (degrees), base b along the dip and height h (m)."""

    name: str
    psi: float
    phi: float
    base: float
    height: float

    @property
    def mode(self) -> str:
        return slide_topple_mode(self.psi, self.phi, self.base, self.height)


# one case in each region of the chart, every criterion off its boundary by at least 0.2 in tan ψ - tan φ
# or b/h - tan ψ (tan 30° = 0.577)
SLIDE_TOPPLE_CASES = (
    SlideToppleCase("stable", psi=30.0, phi=40.0, base=1.0, height=1.0),
    SlideToppleCase("slides", psi=30.0, phi=20.0, base=1.0, height=1.0),
    SlideToppleCase("topples", psi=30.0, phi=40.0, base=0.3, height=1.0),
    SlideToppleCase("slides and topples", psi=30.0, phi=20.0, base=0.3, height=1.0),
)


def _rotation_about_y(psi: float) -> np.ndarray:
    """Rotation taking the local x axis to the dip vector of a plane dipping ψ towards east (+x)."""
    p = np.radians(psi)
    return np.array([[np.cos(p), 0.0, np.sin(p)], [0.0, 1.0, 0.0], [-np.sin(p), 0.0, np.cos(p)]])


def block_on_incline_model(psi: float, phi: float, base: float = 1.0, height: float = 1.0, width: float = 1.0,
                           length: float | None = None, thickness: float = 0.5,
                           material: Material = ROCK) -> Model:
    """A box (base along the dip, width, height) resting on a fixed slab whose top dips ψ towards east.

    Local frame of the incline: x down the dip, z along its upward normal;
    the block's base is [0, base] x [0, width] at z = 0, the slab's top
    [-base/2, length - base/2] x [-width/2, 1.5 width] (``length`` default
    5 x base + 2 m), ``thickness`` deep. Block and slab are blocks "block"
    and "incline" of materials of the same name, the joint between them
    has friction φ; a measured point at the block's centroid.
    """
    length = 5.0 * base + 2.0 if length is None else length
    rot = _rotation_about_y(psi)
    model = Model(gravity=(0.0, 0.0, -G))
    model.add_material("block", material)
    model.add_material("incline", material)
    model.add_joint_material("joint", JointMaterial(friction_angle=phi), [("block", "incline")])
    v, faces = box((0.0, 0.0, 0.0), (base, width, height), "block")
    model.add_polyhedron(v @ rot.T, faces, "block", name="block")
    v, faces = box((-0.5 * base, -0.5 * width, -thickness), (length - 0.5 * base, 1.5 * width, 0.0), "incline")
    model.add_polyhedron(v @ rot.T, faces, "incline", name="incline", fixed=True)
    model.add_measured_point(rot @ np.array([0.5 * base, 0.5 * width, 0.5 * height]), block=0)
    return model


def slide_topple_model(case: SlideToppleCase, width: float = 1.0) -> Model:
    """The block of one chart case on its incline (:func:`block_on_incline_model`)."""
    return block_on_incline_model(case.psi, case.phi, case.base, case.height, width)


# -- the tetrahedral wedge -------------------------------------------------------------------------------
WEDGE_PLANES = ((40.0, 130.0), (60.0, 220.0))  # (dip, dip direction) of joint planes A and B
WEDGE_FACE = (70.0, 160.0)  # the slope face; the top of the slope is horizontal


@dataclass(frozen=True)
class WedgeSolution:
    """Limit equilibrium of a wedge on planes A and B (Hoek & Bray 1981, ch. 8), per unit weight."""

    line: np.ndarray  # unit vector along the line of intersection, pointing down
    plunge: float  # ψ_i, degrees
    trend: float  # degrees clockwise from north
    normal_a: float  # N_A / W
    normal_b: float  # N_B / W
    factor_of_safety: float
    acceleration: float  # m/s² along ``line`` when FS < 1, else 0

    @property
    def is_wedge(self) -> bool:
        """Both planes carry the wedge (N_A, N_B > 0); otherwise it slides on one plane only."""
        return self.normal_a > 0 and self.normal_b > 0


def _line_of_intersection(na: np.ndarray, nb: np.ndarray) -> np.ndarray:
    line = np.cross(na, nb)
    norm = np.linalg.norm(line)
    if norm < 1e-12:
        raise ValueError("the two joint planes are parallel: they form no wedge")
    line /= norm
    return -line if line[2] > 0 else line


def wedge_solution(plane_a: tuple[float, float], plane_b: tuple[float, float], phi_a: float,
                   phi_b: float | None = None, g: float = G) -> WedgeSolution:
    """Normal reactions, factor of safety and sliding acceleration of a wedge on planes A and B.

    ``plane_a``, ``plane_b``: (dip, dip direction) in degrees; friction
    angles φ_A, φ_B (φ_B defaults to φ_A); no cohesion, no water. In the
    plane perpendicular to the line of intersection the weight's component
    W cos ψ_i along the upward unit vector u is balanced by N_A n_A + N_B n_B;
    with a, b the signed angles of the normals from u (sine rule, Hoek &
    Bray 1981 ch. 8; the symmetric case gives their wedge factor
    K = sin β / sin(ξ/2)):

        N_A = W cos ψ_i sin b / sin(b - a),   N_B = -W cos ψ_i sin a / sin(b - a).
    """
    phi_b = phi_a if phi_b is None else phi_b
    na, nb = plane_normal(*plane_a), plane_normal(*plane_b)
    line = _line_of_intersection(na, nb)
    sin_plunge = -line[2]
    cos_plunge = np.sqrt(max(0.0, 1.0 - sin_plunge**2))
    up = (np.array([0.0, 0.0, 1.0]) + sin_plunge * line) / cos_plunge  # ⊥ line, in the vertical plane

    def signed_angle(n: np.ndarray) -> float:
        return float(np.arctan2(np.dot(np.cross(up, n), line), np.dot(up, n)))

    a, b = signed_angle(na), signed_angle(nb)
    n_a = cos_plunge * np.sin(b) / np.sin(b - a)
    n_b = -cos_plunge * np.sin(a) / np.sin(b - a)
    resisting = n_a * np.tan(np.radians(phi_a)) + n_b * np.tan(np.radians(phi_b))
    fs = resisting / sin_plunge if sin_plunge > 0 else np.inf
    acc = g * (sin_plunge - resisting) if fs < 1 else 0.0
    trend = float(np.degrees(np.arctan2(line[0], line[1])) % 360.0)
    return WedgeSolution(line, float(np.degrees(np.arcsin(sin_plunge))), trend, float(n_a), float(n_b), float(fs),
                         float(acc))


def wedge_friction_for(factor_of_safety: float, plane_a: tuple[float, float] = WEDGE_PLANES[0],
                       plane_b: tuple[float, float] = WEDGE_PLANES[1]) -> float:
    """The friction angle (degrees, the same on both planes) giving the wedge this factor of safety.

    FS is proportional to tan φ: tan φ = FS sin ψ_i / (N_A/W + N_B/W).
    """
    s = wedge_solution(plane_a, plane_b, 45.0)
    if not s.is_wedge:
        raise ValueError("the planes do not form a wedge (one normal reaction is not positive)")
    return float(np.degrees(np.arctan(factor_of_safety * np.sin(np.radians(s.plunge)) / (s.normal_a + s.normal_b))))


def wedge_model(phi: float, height: float = 6.0, depth: float = 2.0, plane_a: tuple[float, float] = WEDGE_PLANES[0],
                plane_b: tuple[float, float] = WEDGE_PLANES[1], face: tuple[float, float] = WEDGE_FACE,
                material: Material = ROCK) -> Model:
    """The tetrahedral wedge and the two fixed joint-plane blocks under it.

    Planes A, B and the slope face pass through the origin (where the line of
    intersection daylights); the top of the slope is z = ``height``. The
    wedge is {n_A·x >= 0, n_B·x >= 0, n_F·x <= 0, z <= height}. The rock under
    plane A (under B) is a block ``depth`` thick below it, on A's (B's) side of
    the vertical plane through the line of intersection, spanning the wedge's
    extent with a margin of half its size (so the wedge can slide on it out of
    the face), below the top. Blocks: "wedge" (material "wedge"), "plane A"
    and "plane B" (material "rock", fixed); the joint between the materials
    has friction φ on both planes; a measured point at the wedge's centroid.
    """
    na, nb, nf = plane_normal(*plane_a), plane_normal(*plane_b), plane_normal(*face)
    line = _line_of_intersection(na, nb)
    ez = np.array([0.0, 0.0, 1.0])
    reach = 4.0 * height / max(np.sin(np.radians(plane_a[0])), 1e-3)  # a box surely holding the wedge
    lo, hi = np.array([-reach, -reach, -reach]), np.array([reach, reach, height])
    wedge = halfspace_polyhedron([-na, -nb, nf], [0.0, 0.0, 0.0], lo, hi, "wedge")
    wv = wedge[0]
    side = np.cross(line, ez)  # horizontal normal of the vertical plane through the line of intersection
    a_side = np.sign(np.dot(side, wv[np.argmax(np.abs(wv @ nb))]))  # A's side holds the wedge's corner far from B
    size = np.ptp(wv, axis=0)
    blo, bhi = wv.min(axis=0) - 0.5 * size.max(), wv.max(axis=0) + 0.5 * size.max()
    blo[2] -= depth
    bhi[2] = height
    slab_a = halfspace_polyhedron([na, -na, -a_side * side], [0.0, depth, 0.0], blo, bhi, "plane A")
    slab_b = halfspace_polyhedron([nb, -nb, a_side * side], [0.0, depth, 0.0], blo, bhi, "plane B")
    model = Model(gravity=(0.0, 0.0, -G))
    model.add_material("wedge", material)
    model.add_material("rock", material)
    model.add_joint_material("joint", JointMaterial(friction_angle=phi), [("wedge", "rock")])
    model.add_polyhedron(*wedge, "wedge", name="wedge")
    model.add_polyhedron(*slab_a, "rock", name="plane A", fixed=True)
    model.add_polyhedron(*slab_b, "rock", name="plane B", fixed=True)
    arrays = model.arrays()
    model.add_measured_point(arrays.moments(arrays.vertices).centroid[0], block=0)
    return model
