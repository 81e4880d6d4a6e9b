"""Benchmarks: `make bench` (or `python -m bench`). They print figures; nothing is asserted.

BLAS runs on one thread (a shared 2-core machine): set here, before any benchmark imports numpy.
"""

import os

for _name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")
