"""The applications built on the engine for a user: the ``srdda`` command, the verification manual, the paper's
examples and report, benchmarks, ensembles, the factor of safety, figures and animations (docs/architecture.md).

Nothing of the engine (``srdda.<module>`` outside ``srdda.apps``) imports from here; tests/test_architecture.py
checks it. This package imports none of its modules, so that importing one application loads only what it needs.
"""
