#!/usr/bin/env bash
# Fill .whl/ (git-ignored) with the wheels of srdda's dependencies that the lent GPU machine's image lacks
# (it has no network): what `import srdda`, its runs and tests/test_backends.py import there. The image has
# numpy, scipy, numba, h5py, click, tqdm, threadpoolctl, pyyaml, pytest, hypothesis and CuPy (KINDS.md of the
# device tool); pyvista/vtk (3D pictures), dask/distributed (ensembles), pyamg (cg-amg), meshio (VTU files),
# matplotlib's figures and pyarrow are imported only by the commands that use them, so they stay behind.
# Python 3.12, x86-64, manylinux; one version of each, as tested here.
set -euo pipefail
cd "$(dirname "$0")/../.."
rm -rf .whl && mkdir .whl
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
    --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
    --platform manylinux2014_x86_64 --platform manylinux1_x86_64 -d .whl \
    pydantic==2.14.4 pydantic-core==2.50.5 annotated-types==0.8.0 typing-inspection==0.4.5 \
    typing-extensions==4.16.0 shapely==2.2.0 tomli-w==1.2.0
ls -l .whl
du -sh .whl
