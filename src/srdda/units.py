"""Units: quantities in model files, and the unit systems of existing DDA input files.

Model files: a number (SI) or a string "value unit". The paper gives moduli in
MPa and stiffnesses in MN/m; a model file may write ``young = "0.20e11 MPa"``
and srdda converts it to Pa explicitly. Only the units below are accepted;
anything else is an error naming the unit.

DDA input files carry no units: their author used one consistent system
(:class:`UnitSystem`), which ``srdda convert`` detects from the gravity the
file implies or is told with ``--units``, and converts to SI.
"""
from __future__ import annotations

import typing
from dataclasses import dataclass

__all__ = ["UNITS", "to_si", "reject_boolean", "UnitSystem", "UNIT_SYSTEMS", "STANDARD_GRAVITY", "detect_unit_system"]

STANDARD_GRAVITY = 9.80665  # m/s², exact by definition (the pound-force is defined with it)

UNITS: dict[str, dict[str, float]] = {
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m2": 1.0, "N/m^2": 1.0},
    "stiffness": {"N/m": 1.0, "kN/m": 1e3, "MN/m": 1e6, "GN/m": 1e9},
    "joint stiffness": {"Pa/m": 1.0, "kPa/m": 1e3, "MPa/m": 1e6, "GPa/m": 1e9, "N/m3": 1.0, "N/m^3": 1.0},
    "density": {"kg/m3": 1.0, "kg/m^3": 1.0, "t/m3": 1e3, "t/m^3": 1e3, "g/cm3": 1e3, "g/cm^3": 1e3},
    "length": {"m": 1.0, "cm": 1e-2, "mm": 1e-3, "km": 1e3},
    "time": {"s": 1.0, "ms": 1e-3},
    "angle": {"deg": 1.0},
}


def to_si(value: object, kind: str) -> float:
    """Convert ``value`` (number, or "number unit" string) of quantity ``kind`` to SI."""
    if isinstance(value, bool):
        raise ValueError("expected a number, got a boolean")
    if isinstance(value, (int, float)):
        return float(value)
    if isinstance(value, str):
        parts = value.split()
        if len(parts) != 2:
            raise ValueError(f"expected a number or 'number unit', got {value!r}")
        try:
            number = float(parts[0])
        except ValueError as exc:
            raise ValueError(f"{parts[0]!r} is not a number") from exc
        table = UNITS[kind]
        if parts[1] not in table:
            raise ValueError(f"unit {parts[1]!r} is not a {kind} unit; use one of {', '.join(table)}")
        return number * table[parts[1]]
    raise ValueError(f"expected a number or 'number unit', got {type(value).__name__}")


def _allows_boolean(annotation: object) -> bool:
    return annotation is bool or any(_allows_boolean(a) for a in typing.get_args(annotation))


def _holds_boolean(value: object) -> bool:
    return isinstance(value, bool) or (isinstance(value, (list, tuple)) and any(_holds_boolean(v) for v in value))


def reject_boolean(value: object, annotation: object) -> object:
    """``value``, or ValueError if it holds true/false where ``annotation`` expects no boolean.

    pydantic would take ``true`` for the number 1 or the block index 1; in a
    model file that is always a mistake (``poisson = false``, ``block = true``).
    Nested tables (dicts) are left to their own models.
    """
    if _holds_boolean(value) and not _allows_boolean(annotation):
        raise ValueError("true/false is not valid here: give a number (or a name where one is expected)")
    return value


@dataclass(frozen=True)
class UnitSystem:
    """A consistent unit system: its units of length, mass and time in SI; force = mass × length / time²."""

    name: str
    units: str  # what a reader sees, e.g. "ft, slug, s; force lbf, stress lbf/ft²"
    length: float  # m per length unit
    mass: float  # kg per mass unit
    time: float = 1.0  # s per time unit

    @property
    def force(self) -> float:
        """N per force unit."""
        return self.mass * self.length / self.time**2

    @property
    def pressure(self) -> float:
        """Pa per stress unit (stresses, moduli, cohesion, tensile strength)."""
        return self.force / self.length**2

    @property
    def density(self) -> float:
        """kg/m³ per mass-per-volume unit (DDA's unit mass)."""
        return self.mass / self.length**3

    @property
    def unit_weight(self) -> float:
        """N/m³ per force-per-volume unit (DDA's unit weight)."""
        return self.force / self.length**3

    @property
    def acceleration(self) -> float:
        """m/s² per acceleration unit."""
        return self.length / self.time**2

    @property
    def velocity(self) -> float:
        """m/s per velocity unit."""
        return self.length / self.time

    @property
    def gravity(self) -> float:
        """Standard gravity in this system's units (9.80665 m/s² = 32.174 ft/s²)."""
        return STANDARD_GRAVITY / self.acceleration


_FOOT, _INCH, _POUND = 0.3048, 0.0254, 0.45359237  # m, m, kg (exact definitions)
_LBF = _POUND * STANDARD_GRAVITY  # N

UNIT_SYSTEMS: dict[str, UnitSystem] = {s.name: s for s in (
    UnitSystem("SI", "m, kg, s; force N, stress Pa", 1.0, 1.0),
    UnitSystem("kN-m-t", "m, t, s; force kN, stress kPa", 1.0, 1000.0),
    UnitSystem("ft-lbf-slug", "ft, slug, s; force lbf, stress lbf/ft²", _FOOT, _LBF / _FOOT),
    UnitSystem("in-lbf", "in, lbf·s²/in, s; force lbf, stress psi", _INCH, _LBF / _INCH),
)}

GRAVITY_TOLERANCE = 0.02  # relative: files write 9.81, 9.8, 32.2, 32.17, 386 for standard gravity


def detect_unit_system(gravity: float) -> UnitSystem | None:
    """The unit system whose standard gravity is ``gravity`` (within 2 %), else None.

    SI and kN-m-t share 9.81 m/s²; the metre-second match is taken as SI.
    """
    for system in UNIT_SYSTEMS.values():
        if system.name != "kN-m-t" and abs(gravity - system.gravity) <= GRAVITY_TOLERANCE * system.gravity:
            return system
    return None
