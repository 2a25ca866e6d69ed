"""pyOMA2's SSI-cov with its default clustering on a CSV record `t,c1,...` (the reference
beside `cablevib identify`): the record decimated by Q (as `cablevib identify` decimates to
its band), BR block rows, orders up to ORDMAX, then pyOMA2's default three clustering steps
(Step1(), Step2(), Step3() with the band as freqlim). Prints one JSON object:
{"frequency_hz", "damping_ratio" (ascending), "seconds" (decimation, SSI and clustering;
not the import or the CSV read), "version"}.
Usage: pyoma2_ssi_cov.py IN.csv Q BR ORDMAX FROM_HZ TO_HZ."""

import importlib.metadata
import json
import logging
import os
import sys
import time

os.environ.setdefault("TQDM_DISABLE", "1")

import numpy as np  # noqa: E402
from pyoma2.algorithms import SSI  # noqa: E402
from pyoma2.algorithms.data.run_params import Clustering, Step1, Step2, Step3  # noqa: E402
from pyoma2.setup import SingleSetup  # noqa: E402


def main() -> None:
    path, q, br, ordmax = sys.argv[1], int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
    band = (float(sys.argv[5]), float(sys.argv[6]))
    logging.disable(logging.WARNING)
    d = np.loadtxt(path, delimiter=",", skiprows=1)
    fs = 1.0 / float(np.median(np.diff(d[:, 0])))
    t0 = time.perf_counter()
    ss = SingleSetup(d[:, 1:], fs=fs)
    if q > 1:
        ss.decimate_data(q=q)
    ssi = SSI(name="SSIcov", method="cov", br=br, ordmax=ordmax)
    ss.add_algorithms(ssi)
    ss.run_all()
    ssi.add_clustering(
        Clustering(name="default", steps=(Step1(), Step2(), Step3(freqlim=band)))
    )
    ssi.run_all_clustering()
    r = ssi.result.clustering_results["default"]
    seconds = time.perf_counter() - t0
    o = np.argsort(r.Fn)
    print(
        json.dumps(
            {
                "frequency_hz": [float(x) for x in np.asarray(r.Fn)[o]],
                "damping_ratio": [float(x) for x in np.asarray(r.Xi)[o]],
                "seconds": seconds,
                "version": importlib.metadata.version("pyOMA-2"),
            }
        )
    )


if __name__ == "__main__":
    main()
