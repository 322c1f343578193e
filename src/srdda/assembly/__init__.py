"""Assembly of block sub-matrices into the global sparse system."""
from .system import BlockSystem, PenaltyPairs, add_penalty_pairs

__all__ = ["BlockSystem", "PenaltyPairs", "add_penalty_pairs"]
