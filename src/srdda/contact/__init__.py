"""Contacts between blocks in 2D and 3D: one pipeline over a detector per dimension (docs/contacts.md).

detector (:mod:`.detect2d`, :mod:`.detect3d`) → :class:`ContactRecord` →
:class:`ContactSet` / :class:`ContactStep` / :class:`ContactTerm` (:mod:`.pipeline`)
→ the joints' :class:`ContactLaw` (:class:`MohrCoulomb`).
"""
from .impact import ImpactWarning
from .law import ContactLaw, ContactStiffness, JointResponse, MohrCoulomb
from .openclose import LOCKED, OPEN, SLIDING, next_states
from .pipeline import CONTACT_KINDS, ContactKind, ContactModel, ContactParameters, ContactSet, ContactStep, ContactTerm
from .record import ContactRecord

__all__ = ["ContactRecord", "ContactLaw", "ContactStiffness", "JointResponse", "MohrCoulomb", "OPEN", "SLIDING",
           "LOCKED", "next_states", "ContactModel", "ContactParameters", "ContactSet", "ContactStep", "ContactTerm",
           "ContactKind", "CONTACT_KINDS", "ImpactWarning"]
