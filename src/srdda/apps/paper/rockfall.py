"""Paper example 4.5: a stone falling onto a rocky slope (Tables 6 and 7, Figs. 14-15).

The paper gives the slope's segment lengths and angles, the stone's initial
velocities, Δt, E, ν, g, ρ∞, the penalty (50E), the maximum step-displacement
ratio (0.001) and 4000 steps; it does not give the stone's shape, size, start
position or density, the slope's friction, or where the slope ends. Our
reconstruction (docs/contacts.md, "Rockfall"):

* slope profile from the top: a horizontal ledge L1 = 1 m, then L2 = 2 m at
  α = 60°, L3 = 3 m at β = 45°, L4 = 5 m at γ = 15°; the slope is one fixed
  block whose base is the line y = 0 and whose toe is 0.5 m high (the paper
  pins P3, P4, P5 of the slope: a fixed block does the same);
* the stone is a 0.4 × 0.3 m rectangle (density 2600 kg/m³, same E and ν as
  the slope), its centroid P1 starts above the ledge's edge with its base 5 cm
  above the ledge, so that in rigid free flight it first touches the 45°
  face at t ≈ 0.70 s (step ≈ 1400; the paper's first contact is at CS 1382);
  P2 is its initially lower-right corner;
* slope-stone joint: φ = 30°, no cohesion, no tensile strength;
* plane stress; the initial ω0 = -1 rad/s is the third generalized velocity.

So Table 6 (free flight, exact ω = -1) is a quantitative comparison; Table 7
and the contact steps depend on the assumed geometry and are qualitative.
"""
from __future__ import annotations

import numpy as np

from ...integrators.methods import MethodName
from ...model import JointMaterial, Material, Model
from ...results import Result
from ...settings import RunSettings
from .registry import Example, Row, register

__all__ = ["build", "tables", "slope_profile", "contact_events", "ROCKFALL"]

E = 1.0e13
NU = 0.35
DT = 0.0005
N_STEPS = 4000
LEDGE = 1.0
SEGMENTS = ((2.0, 60.0), (3.0, 45.0), (5.0, 15.0))  # (L, angle below horizontal in degrees)
TOE_HEIGHT = 0.5
STONE_SIZE = (0.4, 0.3)
STONE_CLEARANCE = 0.05
STONE_DENSITY = 2600.0
SLOPE_FRICTION = 30.0
FREE_FLIGHT_STEPS = 20  # a contact event starts after at least this many steps without a closed contact

PAPER_TABLE6 = {  # step: {method: ω}
    100: {"dda0": -1.00000146, "dda1": -1.00000146, "srdda": -1.00000033},
    200: {"dda0": -1.00000271, "dda1": -1.00000271, "srdda": -1.00000064},
    500: {"dda0": -1.00000229, "dda1": -1.00000229, "srdda": -1.00000055},
    800: {"dda0": -1.00000217, "dda1": -1.00000217, "srdda": -1.00000043},
    1000: {"dda0": -1.00000203, "dda1": -1.00000203, "srdda": -1.00000040},
}
# Contact steps (CS) and ω right after each contact (CS + 1), from the paper's text on Table 7;
# the paper does not print DDA0's ω after its second contact.
PAPER_CONTACT_STEPS = {"dda0": (1382, 1973, 2912), "dda1": (1382, 2005, 2593), "srdda": (1382, 2005, 2821)}
PAPER_OMEGA_AFTER = {"dda0": (-10.25734346, None, 2.77335470), "dda1": (-8.85281450, -18.34628241, -23.45725286),
                     "srdda": (-8.85595077, -18.55805717, 14.49043619)}


def slope_profile() -> np.ndarray:
    """The slope's surface points from the ledge's start to the toe, (5, 2)."""
    drop = sum(length * np.sin(np.radians(a)) for length, a in SEGMENTS)
    top = TOE_HEIGHT + drop
    points = [np.array([0.0, top]), np.array([LEDGE, top])]
    for length, angle in SEGMENTS:
        a = np.radians(angle)
        points.append(points[-1] + length * np.array([np.cos(a), -np.sin(a)]))
    return np.array(points)


def build(method: MethodName) -> tuple[Model, RunSettings]:
    """The rockfall model and its run settings for ``method``."""
    profile = slope_profile()
    model = Model(gravity=(0.0, -10.0))
    model.add_material("rock", Material(density=STONE_DENSITY, young=E, poisson=NU))
    model.add_joint_material("slope", JointMaterial(friction_angle=SLOPE_FRICTION), between=[("rock", "rock")])
    toe = profile[-1]
    slope = [[0.0, 0.0], [toe[0], 0.0], *profile[::-1].tolist()]
    model.add_block(slope, "rock", fixed=True, name="slope")
    w, h = STONE_SIZE
    cx, cy = profile[1][0], profile[1][1] + STONE_CLEARANCE + 0.5 * h
    stone = [[cx - w / 2, cy - h / 2], [cx + w / 2, cy - h / 2], [cx + w / 2, cy + h / 2], [cx - w / 2, cy + h / 2]]
    model.add_block(stone, "rock", velocity=(2.5, 0.0), angular_velocity=-1.0, name="stone")
    model.add_measured_point([cx, cy], block=1)  # P1, the centroid
    model.add_measured_point([cx + w / 2, cy - h / 2], block=1)  # P2, a vertex
    settings = RunSettings(dt=DT, n_steps=N_STEPS, method=method, rho_inf=1.0, penalty=50.0 * E,
                           max_displacement_ratio=0.001, open_close_tolerance=0.0,
                           open_close_force_tolerance=0.0, open_close_settle_after=8)
    return model, settings


def contact_events(result: Result) -> list[int]:
    """Steps at which the stone touches the slope after at least FREE_FLIGHT_STEPS steps in the air."""
    closed = np.asarray(result.closed_contacts) > 0
    steps = np.asarray(result.step)
    events: list[int] = []
    free = FREE_FLIGHT_STEPS
    for k in range(len(closed)):
        if closed[k] and free >= FREE_FLIGHT_STEPS:
            events.append(int(steps[k]))
        free = 0 if closed[k] else free + 1
    return events


def _row(table: str, quantity: str, step: int | None, method: str, ours: float | None, paper: float | None,
         exact: float | None) -> Row:
    return {"table": table, "quantity": quantity, "step": step, "method": method,
            "ours": None if ours is None else float(ours), "paper": paper, "exact": exact,
            "unit": "step" if quantity.endswith("_step") else "s" if quantity.endswith("_time") else "rad/s"}


def tables(results: dict[str, Result]) -> list[Row]:
    """Table 6 (ω before the first contact), Table 7 (ω right after contacts 1-3) and the contact steps."""
    rows: list[Row] = []
    for step, per_method in PAPER_TABLE6.items():
        for method, res in results.items():
            k = list(res.step).index(step)
            rows.append(_row("Table 6", "omega", step, method, res.velocity[k][1, 2], per_method.get(method), -1.0))
    for method, res in results.items():
        events = contact_events(res)
        steps = list(res.step)
        for i in range(3):
            paper_step = PAPER_CONTACT_STEPS.get(method, (None,) * 3)[i]
            paper_omega = PAPER_OMEGA_AFTER.get(method, (None,) * 3)[i]
            ours_step = events[i] if i < len(events) else None
            ours_omega = None
            if ours_step is not None and ours_step + 1 in steps:
                ours_omega = res.velocity[steps.index(ours_step + 1)][1, 2]
            rows.append(_row("Table 7", f"contact_{i + 1}_step", None, method, ours_step, paper_step, None))
            rows.append(_row("Table 7", f"contact_{i + 1}_time", None, method,
                             None if ours_step is None else res.time[steps.index(ours_step)],
                             None if paper_step is None else round(paper_step * DT, 9), None))
            # ω at the step after the contact: that step differs per method (contact_i_step), so the
            # row carries no CS and the three methods share one line of the table
            rows.append(_row("Table 7", f"omega_after_contact_{i + 1}", None, method, ours_omega, paper_omega, None))
    return rows


ROCKFALL = register(Example(
    "rockfall", "4.5 Rockfall", tables, builder=build, point_names=("P1", "P2"),
    notes="The paper gives neither the stone's shape, size and start nor the joint's friction: ours is a "
          "0.4 × 0.3 m stone above the ledge, φ = 30°. Table 6 (free flight) compares exactly; Table 7 and "
          "the contact steps only qualitatively. Steps are accepted steps (g2 = 0.001 cuts them). "
          "docs/contacts.md, Rockfall."))
