"""Ensembles: many runs of one model with sampled parameters, on Dask, with rockfall statistics.

``srdda ensemble SPEC`` (docs/ensembles.md): :func:`load_spec` reads a spec,
:func:`sample` draws run i's values from (seed, i), :func:`apply_values` sets
them in the base model, :func:`run_one` runs one sample and measures it,
:func:`run_ensemble` runs them all on a Dask cluster into a folder (resumable)
and writes the tables, summary, figures and report.
"""
from .runner import EnsembleRun, run_ensemble, run_one
from .sampling import ApplyError, apply_values, load_spec, sample
from .spec import EnsembleSpec, SpecError

__all__ = ["EnsembleRun", "EnsembleSpec", "SpecError", "ApplyError", "load_spec", "sample", "apply_values",
           "run_one", "run_ensemble"]
