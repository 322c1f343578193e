"""The constraint records (specs of hinges, springs, driven points and bolts, and their flat arrays) at their
old path: they live in :mod:`srdda.modeldata.constraints`, below the terms, so that the model's arrays can name
them without importing the constraint terms."""
from __future__ import annotations

from ..modeldata.constraints import (BoltSpec, ConstraintArrays, HingeSpec, PrescribedSpec, SpringSpec,
                                     compile_links, links_from_flat, links_to_flat)

__all__ = ["HingeSpec", "SpringSpec", "PrescribedSpec", "BoltSpec", "ConstraintArrays", "compile_links",
           "links_to_flat", "links_from_flat"]
