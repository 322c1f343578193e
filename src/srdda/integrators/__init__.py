"""Time integrators and the DDA0 / DDA1 / SRDDA method presets."""
from .methods import METHODS, Method, method_preset
from .schemes import SCHEMES, SchemeCoefficients, TimeScheme, alpha_parameters

__all__ = ["METHODS", "Method", "method_preset", "SCHEMES", "SchemeCoefficients", "TimeScheme", "alpha_parameters"]
