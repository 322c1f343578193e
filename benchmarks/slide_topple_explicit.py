"""An independent check of verify's block that slides and topples: how far does its pivot slip?

srdda.apps.verify.cases.slope3d's "slides and topples" block (b × h = 0.3 × 1 m, ψ = 30°, φ = 20°, 2600 kg/m³) in the
plane of its dip, as a rigid body on two corner contacts, integrated explicitly with a small step: penalty
springs k_n and k_s = 0.4 k_n as srdda's (shear_ratio), Coulomb friction on a shear spring whose anchor
follows the slip, 5 % of critical damping on the normal springs (to calm the landing), symplectic Euler.
Prints the down-dip corner's slip and the turn after 0.5 s (srdda verify's slide-topple-3d measures the
same; docs/dev/contact-solve.md has the figures).

    python benchmarks/slide_topple_explicit.py [k_n N/m [Δt s]]      (default 1e10, 5e-6)
"""
from __future__ import annotations

import sys

import numpy as np

PSI, PHI, BASE, HEIGHT, DENSITY, G, DURATION = np.radians(30.0), np.radians(20.0), 0.3, 1.0, 2600.0, 9.81, 0.5


def pivot_slip(kn: float, dt: float) -> tuple[float, float]:
    """(slip of the down-dip corner along the dip (m), turn (rad)) after DURATION."""
    mass = DENSITY * BASE * HEIGHT
    inertia = mass * (BASE**2 + HEIGHT**2) / 12.0
    gravity = np.array([G * np.sin(PSI), -G * np.cos(PSI)])  # x down the dip, y normal to the plane
    ks, mu, damping = 0.4 * kn, np.tan(PHI), 2.0 * 0.05 * np.sqrt(kn * mass)
    corners = np.array([[BASE / 2, -HEIGHT / 2], [-BASE / 2, -HEIGHT / 2]])  # down-dip corner first
    centre, velocity, angle, spin = np.array([0.0, HEIGHT / 2]), np.zeros(2), 0.0, 0.0
    anchor: list[float | None] = [None, None]
    start = centre[0] + corners[0, 0]
    for _ in range(int(round(DURATION / dt))):
        c, s = np.cos(angle), np.sin(angle)
        arms = corners @ np.array([[c, -s], [s, c]]).T
        force, torque = mass * gravity, 0.0
        for j in range(2):
            px, py = centre + arms[j]
            if py >= 0.0:
                anchor[j] = None
                continue
            vy = velocity[1] + spin * arms[j, 0]
            normal = max(0.0, -kn * py - damping * vy)
            if anchor[j] is None:
                anchor[j] = px
            shear = -ks * (px - anchor[j])
            if abs(shear) > mu * normal:  # slips: the anchor follows, the spring holds the friction force
                shear = np.sign(shear) * mu * normal
                anchor[j] = px + shear / ks
            force = force + np.array([shear, normal])
            torque += arms[j, 0] * normal - arms[j, 1] * shear
        velocity = velocity + dt * force / mass
        spin += dt * torque / inertia
        centre = centre + dt * velocity
        angle += dt * spin
    c, s = np.cos(angle), np.sin(angle)
    return float(centre[0] + c * corners[0, 0] - s * corners[0, 1] - start), abs(angle)


if __name__ == "__main__":
    kn = float(sys.argv[1]) if len(sys.argv) > 1 else 1e10
    dt = float(sys.argv[2]) if len(sys.argv) > 2 else 5e-6
    slip, turn = pivot_slip(kn, dt)
    print(f"k_n = {kn:g} N/m, Δt = {dt:g} s: pivot slip {slip:.4g} m, turn {turn:.4g} rad in {DURATION:g} s")
