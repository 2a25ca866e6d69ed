"""cablevib: tension distribution, stiffness and natural frequencies of cable-driven
parallel robots (SI units: m, N, N/m, Hz).

The compiled extension is ``cablevib._cablevib``; every name is re-exported here. The
optional ``cablevib.dask`` (``pip install ./python[dask]``) runs studies on a Dask cluster.
"""

from ._cablevib import (
    CablevibError,
    Estimate,
    Estimator,
    Scene,
    TminAnswer,
    __version__,
    analyze,
    calibrate,
    frf,
    identify,
    shape,
    simulate,
    sweep,
)

__all__ = [
    "CablevibError",
    "Estimate",
    "Estimator",
    "Scene",
    "TminAnswer",
    "analyze",
    "calibrate",
    "frf",
    "identify",
    "shape",
    "simulate",
    "sweep",
]
