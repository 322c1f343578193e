"""Model builders and closed-form or ODE references of the verification problems (``srdda verify``)."""
