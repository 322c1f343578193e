"""srdda: Discontinuous Deformation Analysis with the strain-rotation decomposition.

The three methods of Fan, Zheng & Zhao (2017): Shi's DDA (``dda0``), DDA with
post-adjusted rotations (``dda1``) and SRDDA (``srdda``). SI units throughout.

```python
>>> import srdda
>>> m = srdda.Model(gravity=(0.0, -9.81))
>>> _ = m.add_material("rock", srdda.Material(density=2500.0, young=1e9, poisson=0.25))
>>> b = m.add_block([[0, 0], [1, 0], [1, 1], [0, 1]], "rock")
>>> res = srdda.run(m, srdda.RunSettings(dt=1e-3, n_steps=10))
>>> res.completed
True

```
"""
from . import threads as _threads  # first: how numba's threads wait, before they start (srdda.threads)
from ._version import __version__
from . import _aliases
from .constraints import MotionHistory, hinge_forces
from .constraints.water import TensionCrack, WaterTable
from .history import TimeHistory
from .contact import ContactSet
from .geometry import PolygonError, block_moments
from .integrators import METHODS, Method, TimeScheme, method_preset
from .model import JointMaterial, Load, Material, Model, ModelError
from .results import Result
from .settings import RunSettings
from .simulation import Settled, run, settle
from .stages import Stage
from .state import State
from .solvers import available_solvers, get_solver
from .io.results_store import ResultsStore, StoredResult, read_results, resume
from .geometry.cutting2d import BlockCut, CuttingError, cut_blocks
from .geometry.jointsets2d import JointSet, circular_opening, joint_traces, polygonal_opening
from .cutmodel import add_cut_blocks, add_cut_polyhedra
from .geometry.cutting3d import PolyhedralCut, convex_hull_polyhedron, cut_polyhedra
from .geometry.jointsets3d import JointPlanes, JointSet3D, joint_planes
from .apps.fos import FactorOfSafety, FailureCriterion, factor_of_safety

_aliases.install()  # the module paths of srdda 0.1 that moved (srdda.cli, srdda.verify, ...), for one release

__all__ = [
    "METHODS", "ContactSet", "JointMaterial", "Load", "Material", "Method", "Model", "ModelError",
    "MotionHistory", "PolygonError", "TimeHistory", "hinge_forces", "TensionCrack", "WaterTable",
    "Result", "RunSettings", "State", "TimeScheme", "available_solvers", "block_moments",
    "get_solver", "method_preset", "run", "__version__", "ResultsStore", "StoredResult", "read_results", "resume",
    "BlockCut", "CuttingError", "JointSet", "add_cut_blocks", "circular_opening", "cut_blocks", "joint_traces",
    "polygonal_opening",
    "JointPlanes", "JointSet3D", "PolyhedralCut", "add_cut_polyhedra", "convex_hull_polyhedron", "cut_polyhedra",
    "joint_planes", "FactorOfSafety", "FailureCriterion", "factor_of_safety", "Stage", "Settled", "settle",
]
