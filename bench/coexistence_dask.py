"""The 60 × 40 coexistence map through the Python package on the package's lean Dask
LocalCluster of 2 worker processes of 1 thread each (bench/coexistence.sh times it); writes the
table to OUT/dask.csv. Usage: coexistence_dask.py OUT"""

import logging
import sys

import distributed

import bistable_impact as bi


def main(out: str) -> None:
    logging.getLogger("distributed").setLevel(logging.ERROR)
    # The CLI's grid values, bit for bit.
    w, v = bi.linspace(0.2, 3.5, 60), bi.linspace(0.005, 0.2, 40)
    with bi.cluster.local_cluster(n_workers=2) as cluster, distributed.Client(cluster) as client:
        df = bi.sweep.coexistence(w, v, client=client)
    df.to_csv(f"{out}/dask.csv", index=False)


if __name__ == "__main__":
    main(sys.argv[1])
