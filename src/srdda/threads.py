"""How srdda's compiled parallel loops share the cores with other work: imported first by the package.

numba runs the loops of systems of more than 500 blocks on its OpenMP threads
(GNU libgomp on Linux). At a barrier, libgomp's waiting threads by default spin
300,000 times before they sleep. When more threads want the cores than there
are, a spinning thread holds the core that the thread it waits for needs, and
every barrier then waits a time slice of the scheduler. Two runs at once, or an
ensemble's worker per core, are enough: two 1,041-block walls run together
took 317 s each, against 1.4 s for one alone.

``GOMP_SPINCOUNT`` = 1,000 puts a waiting thread to sleep after a few
microseconds. The two runs then take 3.4 s each, and a run alone 1.45-1.48 s,
within its run-to-run spread (docs/performance.md, "Two runs at once"). A
value the user has set wins. libgomp reads it when numba first starts its
threads, which is after this import, unless that process had run a parallel
numba function before importing srdda.
"""
from __future__ import annotations

import os

__all__ = ["GOMP_SPIN_COUNT"]

GOMP_SPIN_COUNT = "1000"

os.environ.setdefault("GOMP_SPINCOUNT", GOMP_SPIN_COUNT)
