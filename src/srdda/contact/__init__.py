"""Contacts between blocks: detection, penalty springs, Mohr-Coulomb joints, open-close."""
from .broadphase import block_boxes, candidate_pairs
from .narrowphase import VERTEX_EDGE, VERTEX_VERTEX, detect_contacts
from .openclose import LOCKED, OPEN, SLIDING, next_states
from .term import ContactModel, ContactParameters, ContactSet, ContactTerm

__all__ = ["block_boxes", "candidate_pairs", "detect_contacts", "VERTEX_EDGE", "VERTEX_VERTEX", "OPEN", "SLIDING",
           "LOCKED", "next_states", "ContactModel", "ContactParameters", "ContactSet", "ContactTerm"]
