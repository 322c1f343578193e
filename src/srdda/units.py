"""Quantities with units in model files: a number (SI) or a string "value unit".

The paper gives moduli in MPa and stiffnesses in MN/m; a model file may write
``young = "0.20e11 MPa"`` and srdda converts it to Pa explicitly. Only the
units below are accepted; anything else is an error naming the unit.
"""
from __future__ import annotations

__all__ = ["UNITS", "to_si"]

UNITS: dict[str, dict[str, float]] = {
    "pressure": {"Pa": 1.0, "kPa": 1e3, "MPa": 1e6, "GPa": 1e9, "N/m2": 1.0, "N/m^2": 1.0},
    "stiffness": {"N/m": 1.0, "kN/m": 1e3, "MN/m": 1e6, "GN/m": 1e9},
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
