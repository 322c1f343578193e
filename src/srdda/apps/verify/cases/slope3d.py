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
* **Wedge with cohesion and water** (Hoek & Bray 1981, ch. 8, and their
  appendix 1, the "short" solution; Wyllie & Mah 2004, appendix III): with
  the wedge fully drained at its outcropping edges and the water pressure
  rising to ½ γ_w H on the line of intersection (H: the wedge's height),
  FS = 3/(γH) (c_A X + c_B Y) + (A − γ_w/(2γ) X) tan φ_A + (B − γ_w/(2γ) Y) tan φ_B
  (:func:`hoek_bray_wedge_factor_of_safety`, the angles from the wedge's
  geometry by :func:`hoek_bray_wedge_angles`).

The builders return :class:`~srdda.model.Model` s with real inclined
geometry (no tilted gravity) and fixed joint-plane blocks; they need 3D
contacts to run.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from srdda.constraints.water import UNIT_WEIGHT
from srdda.geometry.cutting3d import halfspace_polyhedron
from srdda.geometry.jointsets3d import plane_normal
from srdda.geometry.polyhedron import box
from srdda.model import JointMaterial, Material, Model
from srdda.stages import Stage

__all__ = ["G", "HoekBrayAngles", "hoek_bray_wedge_angles", "hoek_bray_wedge_factor_of_safety",
           "wedge_vertices", "wedge_faces", "wedge_water_forces", "wet_wedge_factor_of_safety", "SLIDE_TOPPLE_CASES",
           "SlideToppleCase", "WedgeSolution", "block_on_incline_model",
           "incline_acceleration", "slide_topple_mode", "slide_topple_model", "toppling_angular_acceleration",
           "wedge_friction_for", "wedge_model", "wedge_solution", "WEDGE_PLANES", "WEDGE_FACE", "wedge_cut_model"]

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
    model.add_measured_point(arrays.moments(arrays.vertex_position).centroid[0], block=0)
    return model


def wedge_cut_model(peak_fs: float = 1.2, residual_fs: float = 0.8, height: float = 6.0, toe: float = 2.0) -> Model:
    """The wedge of :func:`wedge_model` above a cut slope, staged (examples/stages/wedge_cut.py).

    The "toe" (fixed, as intact rock) fills the space in front of the face above planes A and B up to
    ``toe`` above the daylight point, over the joint-plane blocks' extent: before the cut the line of
    intersection does not daylight. The joints' friction gives the daylighting wedge the factor of safety
    ``peak_fs``. Stages: "gravity" (equilibrium), "cut" (the toe removed, displacements reset),
    "residual" (the joint's friction lowered to give ``residual_fs``); the dynamic stages run the
    settings' steps.
    """
    model = wedge_model(wedge_friction_for(peak_fs), height=height)
    na, nb, nf = (plane_normal(*p) for p in (*WEDGE_PLANES, WEDGE_FACE))
    arrays = model.arrays()
    slabs = arrays.vertex_position[arrays.block_ptr[1]:]  # the two joint-plane blocks: the toe spans their extent
    lo, hi = slabs.min(axis=0), slabs.max(axis=0)
    hi[2] = toe
    vertices, faces = halfspace_polyhedron([-na, -nb, -nf], [0.0, 0.0, 0.0], lo.tolist(), hi.tolist(), "toe")
    model.add_polyhedron(vertices.tolist(), [f.tolist() for f in faces], "rock", name="toe", fixed=True)
    model.add_stage(Stage("gravity", kind="equilibrium"))
    model.add_stage(Stage("cut", remove_blocks=["toe"], reset_displacements=True))
    model.add_stage(Stage("residual", joint_materials={"joint": JointMaterial(friction_angle=wedge_friction_for(residual_fs))}))
    return model


# -- the wedge with cohesion and water (Hoek & Bray's short solution) ----------------------------------
@dataclass(frozen=True)
class HoekBrayAngles:
    """The angles (degrees) of Hoek & Bray's wedge solution. Lines: 1 = A ∩ face, 2 = B ∩ face,
    3 = A ∩ upper surface, 4 = B ∩ upper surface, 5 = A ∩ B; n_A, n_B the planes' normals."""

    dip_a: float  # ψ_a
    dip_b: float  # ψ_b
    plunge: float  # ψ_5, of the line of intersection
    na_nb: float  # θ_na.nb
    t24: float  # θ_24, between lines 2 and 4 (on plane B)
    t45: float  # θ_45
    t2_na: float  # θ_2.na, between line 2 and n_A
    t13: float  # θ_13 (on plane A)
    t35: float  # θ_35
    t1_nb: float  # θ_1.nb


def hoek_bray_wedge_factor_of_safety(angles: HoekBrayAngles, height: float, phi_a: float, phi_b: float,
                                     cohesion_a: float = 0.0, cohesion_b: float = 0.0, gamma: float = 2600.0 * G,
                                     gamma_water: float = 0.0) -> float:
    """Hoek & Bray's factor of safety of a wedge with cohesion and water (module doc).

    ``height`` H of the wedge (m), friction φ (°), cohesion c (Pa), unit
    weights γ of the rock and γ_w of water (N/m³; γ_w = 0: dry, else the
    wedge is saturated, the pressure peaking at ½ γ_w H on the line of
    intersection):

        X = sin θ24 / (sin θ45 cos θ2.na),  Y = sin θ13 / (sin θ35 cos θ1.nb),
        A = (cos ψa − cos ψb cos θna.nb) / (sin ψ5 sin² θna.nb),
        B = (cos ψb − cos ψa cos θna.nb) / (sin ψ5 sin² θna.nb),
        FS = 3/(γH) (c_A X + c_B Y) + (A − γw/(2γ) X) tan φ_A + (B − γw/(2γ) Y) tan φ_B.
    """
    d = {k: np.radians(v) for k, v in asdict(angles).items()}
    x = np.sin(d["t24"]) / (np.sin(d["t45"]) * np.cos(d["t2_na"]))
    y = np.sin(d["t13"]) / (np.sin(d["t35"]) * np.cos(d["t1_nb"]))
    denominator = np.sin(d["plunge"]) * np.sin(d["na_nb"]) ** 2
    a = (np.cos(d["dip_a"]) - np.cos(d["dip_b"]) * np.cos(d["na_nb"])) / denominator
    b = (np.cos(d["dip_b"]) - np.cos(d["dip_a"]) * np.cos(d["na_nb"])) / denominator
    water = gamma_water / (2.0 * gamma)
    return float(3.0 / (gamma * height) * (cohesion_a * x + cohesion_b * y) + (a - water * x) * np.tan(np.radians(phi_a))
                 + (b - water * y) * np.tan(np.radians(phi_b)))


def wedge_vertices(height: float, plane_a: tuple[float, float] = WEDGE_PLANES[0],
                   plane_b: tuple[float, float] = WEDGE_PLANES[1], face: tuple[float, float] = WEDGE_FACE
                   ) -> dict[str, np.ndarray]:
    """The corners of the wedge under a horizontal top at ``height`` above the daylight point (the origin):
    "toe" (where the line of intersection daylights), "top" (where it meets the top), "crest A", "crest B"
    (where plane A, B meets the face and the top)."""
    na, nb, nf = plane_normal(*plane_a), plane_normal(*plane_b), plane_normal(*face)
    line = _line_of_intersection(na, nb)
    ez = np.array([0.0, 0.0, 1.0])

    def meet(n: np.ndarray) -> np.ndarray:  # the point of plane n and the face at the top
        return np.linalg.solve(np.array([n, nf, ez]), np.array([0.0, 0.0, height]))

    return {"toe": np.zeros(3), "top": line * (height / line[2]), "crest A": meet(na), "crest B": meet(nb)}


def wedge_faces(height: float, plane_a: tuple[float, float] = WEDGE_PLANES[0],
                plane_b: tuple[float, float] = WEDGE_PLANES[1], face: tuple[float, float] = WEDGE_FACE
                ) -> tuple[float, float, float]:
    """(S_A, S_B, V): the areas (m²) of the wedge's faces on planes A (toe, top, crest A) and B (toe, top,
    crest B) and its volume (m³), from :func:`wedge_vertices`."""
    v = wedge_vertices(height, plane_a, plane_b, face)
    toe, top = v["toe"], v["top"]

    def area(crest: np.ndarray) -> float:
        return 0.5 * float(np.linalg.norm(np.cross(top - toe, crest - toe)))

    volume = abs(float(np.dot(top - toe, np.cross(v["crest A"] - toe, v["crest B"] - toe)))) / 6.0
    return area(v["crest A"]), area(v["crest B"]), volume


def wedge_water_forces(level: float, height: float = 6.0, plane_a: tuple[float, float] = WEDGE_PLANES[0],
                       plane_b: tuple[float, float] = WEDGE_PLANES[1], face: tuple[float, float] = WEDGE_FACE,
                       gamma_water: float = UNIT_WEIGHT) -> tuple[float, float]:
    """(U_A, U_B) (N): the hydrostatic water forces on the wedge's faces on planes A and B under a horizontal
    water ``level`` (m above the toe), each normal to its plane.

    Each face is a triangle with its corner at the toe (z = 0) and its other two
    corners at the top (z = H). Under a level L ≥ H the whole face is wet and
    U = γ_w·S·(L − z_c), z_c = 2H/3 its centroid's height; under L < H the wet
    part is the triangle at the toe cut by the level, similar to the face in the
    ratio L/H, of area S·(L/H)² and centroid height 2L/3: U = γ_w·S·L³/(3H²).
    """
    if level <= 0.0:
        return 0.0, 0.0
    s_a, s_b, _ = wedge_faces(height, plane_a, plane_b, face)
    head = level - 2.0 * height / 3.0 if level >= height else level**3 / (3.0 * height**2)
    return gamma_water * s_a * head, gamma_water * s_b * head


def wet_wedge_factor_of_safety(phi_a: float, phi_b: float, uplift_a: float, uplift_b: float, height: float = 6.0,
                               cohesion_a: float = 0.0, cohesion_b: float = 0.0,
                               plane_a: tuple[float, float] = WEDGE_PLANES[0],
                               plane_b: tuple[float, float] = WEDGE_PLANES[1],
                               face: tuple[float, float] = WEDGE_FACE, density: float = ROCK.density,
                               g: float = G) -> float:
    """FS of the wedge with the water forces ``uplift_a`` U_A and ``uplift_b`` U_B (N) on its faces on A and B.

    U_A and U_B act normal to planes A and B, which both contain the line of
    intersection, so they have no component along it: the driving force
    W sin ψ_i is unchanged and each plane carries the effective normal force
    N_i − U_i, N_A and N_B the dry normal reactions (:func:`wedge_solution`):

        FS = [(N_A − U_A) tan φ_A + (N_B − U_B) tan φ_B + c_A S_A + c_B S_B] / (W sin ψ_i).
    """
    s_a, s_b, volume = wedge_faces(height, plane_a, plane_b, face)
    weight = density * g * volume
    s = wedge_solution(plane_a, plane_b, phi_a, phi_b, g)
    resisting = ((s.normal_a * weight - uplift_a) * np.tan(np.radians(phi_a))
                 + (s.normal_b * weight - uplift_b) * np.tan(np.radians(phi_b)) + cohesion_a * s_a + cohesion_b * s_b)
    return float(resisting / (weight * np.sin(np.radians(s.plunge))))


def _angle(u: np.ndarray, v: np.ndarray) -> float:
    return float(np.degrees(np.arccos(np.clip(np.dot(u, v) / (np.linalg.norm(u) * np.linalg.norm(v)), -1.0, 1.0))))


def hoek_bray_wedge_angles(plane_a: tuple[float, float] = WEDGE_PLANES[0],
                           plane_b: tuple[float, float] = WEDGE_PLANES[1],
                           face: tuple[float, float] = WEDGE_FACE) -> HoekBrayAngles:
    """Hoek & Bray's angles of the wedge under a horizontal top (:func:`wedge_vertices`).

    The angles between lines are the corners of the wedge's faces on A
    (toe, top, crest A) and B; θ_na.nb is the angle between the planes'
    upward normals (:func:`~srdda.geometry.jointsets3d.plane_normal`: 101° for
    Hoek & Bray's example planes 45/105 and 70/235, as they give it); θ2.na and
    θ1.nb are the acute angles between a line and a normal.
    """
    na, nb = plane_normal(*plane_a), plane_normal(*plane_b)
    v = wedge_vertices(1.0, plane_a, plane_b, face)
    toe, top, ca, cb = v["toe"], v["top"], v["crest A"], v["crest B"]
    line = _line_of_intersection(na, nb)
    return HoekBrayAngles(
        dip_a=plane_a[0], dip_b=plane_b[0], plunge=float(np.degrees(np.arcsin(-line[2]))),
        na_nb=_angle(na, nb), t24=_angle(toe - cb, top - cb), t45=_angle(cb - top, toe - top),
        t2_na=min(_angle(cb - toe, na), _angle(toe - cb, na)), t13=_angle(toe - ca, top - ca),
        t35=_angle(ca - top, toe - top), t1_nb=min(_angle(ca - toe, nb), _angle(toe - ca, nb)))
