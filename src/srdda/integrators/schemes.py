"""Time-stepping schemes in incremental form.

Every scheme turns one block's dynamic equation into

    (c_k·K + c_p·P + c_m·M) Δd = F_ext(t_load) - f_int(t) - P·g
                                 + M (m_v V + m_a A) + K (k_v V + k_a A)

where K is the elastic stiffness (Bᵀ D B, Eq. 60), P the penalty and spring
stiffness with its current gap g, M = ρ ∫ TᵀT (Eq. 60) and (V, A) the
generalized velocity and acceleration at time t. After the solve, (V, A) at
t + Δt follow from Δd.

* ``shi``: Shi's DDA (1988): c_k = c_p = 1, c_m = 2/Δt², m_v = 2/Δt,
  V(t+Δt) = 2Δd/Δt - V(t).
* ``paper``: the paper's generalized-α (Eqs. 60, 64-69): the elastic term is
  Δt·K·V(t+Δt-αf), inertia M·A(t+Δt-αm), penalties at the end of the step
  (Eq. 61). At ρ∞ = 1 it is identical to ``shi``.
* ``chung-hulbert``: the textbook generalized-α of Chung & Hulbert (1993):
  M·A(t+Δt-αm) + f_int(d(t+Δt-αf)) = F_ext(t+Δt-αf), elastic and penalty
  forces at the α_f-point. At ρ∞ = 1 it is the trapezoidal rule.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, get_args

__all__ = ["SchemeCoefficients", "SchemeName", "TimeScheme", "alpha_parameters", "SCHEMES"]

SchemeName = Literal["shi", "paper", "chung-hulbert"]
SCHEMES: tuple[SchemeName, ...] = get_args(SchemeName)


def alpha_parameters(rho_inf: float) -> tuple[float, float, float, float]:
    """(αm, αf, β, γ) of the generalized-α method for spectral radius ρ∞ (Eqs. 68-69)."""
    if not 0.0 <= rho_inf <= 1.0:
        raise ValueError(f"rho_inf must lie in [0, 1], got {rho_inf}")
    am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
    af = rho_inf / (rho_inf + 1.0)
    beta = 0.25 * (1.0 - am + af) ** 2
    gamma = 0.5 - am + af
    return am, af, beta, gamma


@dataclass(frozen=True)
class SchemeCoefficients:
    """Coefficients of the incremental equation for one Δt (see module doc)."""

    c_k: float
    c_p: float
    c_m: float
    m_v: float
    m_a: float
    k_v: float
    k_a: float
    load_time_fraction: float  # external loads taken at t + fraction·Δt
    # V(t+Δt) = v_d Δd + v_v V + v_a A ;  A(t+Δt) = a_d Δd + a_v V + a_a A
    v_d: float
    v_v: float
    v_a: float
    a_d: float
    a_v: float
    a_a: float


@dataclass(frozen=True)
class TimeScheme:
    """A time-stepping scheme: ``name`` in SCHEMES, ``rho_inf`` for the α schemes."""

    name: str = "shi"
    rho_inf: float = 1.0

    def __post_init__(self) -> None:
        if self.name not in SCHEMES:
            raise ValueError(f"time scheme must be one of {SCHEMES}, got {self.name!r}")
        alpha_parameters(self.rho_inf)

    @property
    def is_shi(self) -> bool:
        """Whether the step is Shi's: the ``shi`` scheme, or ``paper`` at ρ∞ = 1 (the same coefficients)."""
        return self.name == "shi" or (self.name == "paper" and self.rho_inf == 1.0)

    def coefficients(self, dt: float) -> SchemeCoefficients:
        """The incremental-equation coefficients for time step ``dt``."""
        if self.name == "shi":
            return SchemeCoefficients(
                c_k=1.0, c_p=1.0, c_m=2.0 / dt**2, m_v=2.0 / dt, m_a=0.0, k_v=0.0, k_a=0.0,
                load_time_fraction=1.0,
                v_d=2.0 / dt, v_v=-1.0, v_a=0.0,
                a_d=4.0 / dt**2, a_v=-4.0 / dt, a_a=-1.0,
            )
        am, af, beta, gamma = alpha_parameters(self.rho_inf)
        # Newmark end-of-step updates (Eqs. 64, 65)
        v_d, v_v, v_a = gamma / (beta * dt), -(gamma - beta) / beta, -(gamma - 2 * beta) / (2 * beta) * dt
        a_d, a_v, a_a = 1.0 / (beta * dt**2), -1.0 / (beta * dt), -(1 - 2 * beta) / (2 * beta)
        # A(t+Δt-αm) = (1-αm) A(t+Δt) + αm A(t)  (Eq. 67)
        c_m = (1 - am) * a_d
        m_v = -(1 - am) * a_v
        m_a = -((1 - am) * a_a + am)
        if self.name == "paper":
            # Δt K V(t+Δt-αf), V(t+Δt-αf) = (1-αf) V(t+Δt) + αf V(t)  (Eq. 66)
            c_k = dt * (1 - af) * v_d
            k_v = -dt * ((1 - af) * v_v + af)
            k_a = -dt * (1 - af) * v_a
            c_p = 1.0
            load_fraction = 1.0
        else:
            # K d(t+Δt-αf) = K d(t) + (1-αf) K Δd
            c_k = 1.0 - af
            k_v = k_a = 0.0
            c_p = 1.0 - af
            load_fraction = 1.0 - af
        return SchemeCoefficients(
            c_k=c_k, c_p=c_p, c_m=c_m, m_v=m_v, m_a=m_a, k_v=k_v, k_a=k_a,
            load_time_fraction=load_fraction,
            v_d=v_d, v_v=v_v, v_a=v_a, a_d=a_d, a_v=a_v, a_a=a_a,
        )
