"""Run a paper example under one or more methods and collect its table rows."""
from __future__ import annotations

from collections.abc import Callable, Sequence

from ...integrators.methods import MethodName
from ...results import Result
from ...simulation import run
from .registry import Row, get_example

__all__ = ["run_example", "relative_error"]


def run_example(name: str, methods: Sequence[MethodName],
                progress: Callable[[str, int, int], None] | None = None) -> tuple[dict[str, Result], list[Row]]:
    """Run example ``name`` under each method; returns the results and the table rows."""
    example = get_example(name)
    results: dict[str, Result] = {}
    for method in methods:
        model, settings = example.build(method)
        callback = None if progress is None else (lambda step, m=method, n=settings.n_steps: progress(m, step, n))
        results[method] = run(model, settings, progress=callback)
        if not results[method].completed:
            raise RuntimeError(f"{name} under {method}: {results[method].status}")
    return results, example.tables(results)


def relative_error(value: float, exact: float | None) -> float | None:
    """(value - exact) / exact, the paper's RE: positive when |value| overshoots (None without exact)."""
    if exact is None or exact == 0:
        return None
    return (value - exact) / exact
