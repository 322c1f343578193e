"""The names of the energies terms store and of the work the ledger books (:mod:`srdda.ledger`), and of
the causes of step cuts (``State.cuts`` counts them).

A leaf module: the term interface, the state and the ledger all read these
names, and it imports nothing of theirs.
"""
from __future__ import annotations

__all__ = ["ENERGY_KINDS", "LEDGER", "ENERGY_NAMES", "CUT_CAUSES"]

# what a term's ``energy`` may report (srdda.term.Term.energy_kind)
ENERGY_KINDS = ("kinetic", "gravity", "elastic", "spring", "contact")
# work that enters or leaves over the run (J per m in 2D, J in 3D): the columns of State.ledger (new ones go at
# the end: a checkpoint's shorter ledger is read with them at zero)
LEDGER = ("work_loads", "work_prescribed", "work_constraints", "dissipated", "dissipated_friction",
          "dissipated_contact", "dissipated_springs", "dissipated_impact", "work_water", "dissipated_damping",
          "work_stages")
# the energies of a run's records: the stored ones, their total, the ledger and the balance
ENERGY_NAMES = (*ENERGY_KINDS, "total", *LEDGER, "balance")
# Why a step is cut: a term's iteration did not settle within its solves, a vertex moved further than the
# contacts allow (g2·w0), a contact penetrated deeper than allowed. Only the first says the solve gave up.
CUT_CAUSES = ("iteration", "displacement", "penetration")
