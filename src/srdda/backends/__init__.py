"""Where a step's linear solve runs: the CPU (numpy and numba) or a CUDA GPU (CuPy), issue 34.

* :mod:`srdda.backends.arrays`: an :class:`~srdda.backends.arrays.ArrayBackend` is an array module
  (numpy or CuPy) with its sparse module (scipy.sparse or cupyx.scipy.sparse); CuPy is imported only
  when a GPU is asked for (the optional extra ``srdda[gpu]``); the choice of ``RunSettings.device``.
* the block-Jacobi conjugate gradient written once on an array backend is a solver
  (:func:`srdda.solvers.gpu_solver`, ``get_solver(name, tolerance, device="gpu")``). On numpy it
  is what the tests run in CI; on CuPy it is the GPU solver.

The step's assembly and contact work stay on the CPU: the solver receives the step's
:class:`~srdda.assembly.system.BlockSystem` and returns the increment as a numpy array.
"""
