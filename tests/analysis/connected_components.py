#!/usr/bin/python3
"""An independent count of fragments: scipy's connected components of the
intact bond graph. Reads "N M" and then M lines "i j" (the intact bonds)
from stdin; prints the count, then the component sizes, largest first."""
import sys

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

header = sys.stdin.readline().split()
n, m = int(header[0]), int(header[1])
pairs = np.loadtxt(sys.stdin, dtype=np.int64, ndmin=2) if m > 0 else np.zeros((0, 2), np.int64)
graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
count, labels = connected_components(graph, directed=False)
sizes = sorted(np.bincount(labels, minlength=count).tolist(), reverse=True)
print(count)
print(" ".join(str(s) for s in sizes))
