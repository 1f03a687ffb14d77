"""The plugin inside ParaView against crackvis's own CLI, on one file.

pvbatch [--no-mpi] plugin_matches_cli.py PLUGIN FILE.h5 REFERENCE_DIR
pvpython plugin_matches_cli.py PLUGIN FILE.h5 REFERENCE_DIR HOST:PORT   (against a pvserver)

REFERENCE_DIR holds `crackvis extract FILE.h5 -m METHOD -s -1` of each method
(cell-cut.vtp, local-voronoi.vtp, cell-centre.vtp, cell-attribute.vtu). The
plugin's reader opens FILE.h5, each filter extracts the last step, and its
output, gathered from every rank, must equal the CLI's face for face: the
same cells (type, point count, centre and spread of their points), the same
area (volume for the cell attribute method) and the same bond ids. Under MPI
every rank must contribute cells (the reader cuts the specimen into slabs
with ghost layers). Prints one JSON line per method and exits 1 on the first
difference.
"""
import json
import sys

import numpy
from paraview import servermanager
from paraview.simple import (Connect, IntegrateVariables, LoadPlugin, XMLPolyDataReader,
                             XMLUnstructuredGridReader)
from vtkmodules.vtkCommonCore import vtkIdList

plugin, data_file, reference_dir = sys.argv[1:4]
# With a server (pvpython against pvserver): the pipeline runs there; the
# server loaded the plugin from PV_PLUGIN_PATH, the client loads it here.
server = sys.argv[4] if len(sys.argv) > 4 else ""
if server:
    host, port = server.rsplit(":", 1)
    Connect(host, int(port))
LoadPlugin(plugin, remote=False, ns=globals())
ranks = servermanager.ActiveConnection.GetNumberOfDataPartitions()

reader = crackvisdemreader(FileName=data_file)  # noqa: F821 (made by LoadPlugin)
times = reader.TimestepValues
last = times[-1] if times else 0.0


def signatures(data):
    """Each cell as order-free integers: type, point count, and the mean and
    spread of its points on a grid far finer than a face and far coarser than
    rounding noise (the ranks sum in another order)."""
    ids = vtkIdList()
    rows = []
    for c in range(data.GetNumberOfCells()):
        data.GetCellPoints(c, ids)
        points = numpy.array([data.GetPoint(ids.GetId(k)) for k in range(ids.GetNumberOfIds())])
        mean = points.mean(axis=0)
        spread = numpy.abs(points - mean).sum()
        grid = numpy.rint(numpy.append(mean, spread) / SCALE * 1e7).astype(numpy.int64)
        rows.append((data.GetCellType(c), ids.GetNumberOfIds(), *grid.tolist()))
    return rows


def bond_ids(data):
    """The bond ids the output names (cell or point data)."""
    ids = set()
    for attributes in (data.GetCellData(), data.GetPointData()):
        array = attributes.GetArray("bond_id")
        if array is not None:
            ids.update(array.GetValue(k) for k in range(array.GetNumberOfTuples()))
    return ids


def measure(source, time):
    """Cells and size of `source` over all ranks, its cells' signatures and
    bond ids gathered rank by rank (ParaView 5.11's gathering append drops a
    rank's unstructured grid), and how many ranks produced cells."""
    source.UpdatePipeline(time)
    info = source.GetDataInformation()
    integrated = IntegrateVariables(Input=source, DivideCellDataByVolume=0)
    integrated.UpdatePipeline(time)
    result = servermanager.Fetch(integrated)
    size = 0.0
    for name in ("Volume", "Area", "Length"):
        array = result.GetCellData().GetArray(name)
        if array is not None and array.GetNumberOfTuples() > 0:
            size = array.GetValue(0)
            break
    cells, bonds, ranks_with_cells = [], set(), 0
    for rank in range(ranks):
        piece = servermanager.Fetch(source, rank)
        cells += signatures(piece)
        bonds |= bond_ids(piece)
        ranks_with_cells += 1 if piece.GetNumberOfCells() > 0 else 0
    return {"cells": info.GetNumberOfCells(), "size": size,
            "ranks_with_cells": ranks_with_cells}, sorted(cells), sorted(bonds)


# The grid the cells' centres are rounded to: the specimen's size.
reader.UpdatePipeline(last)
_bounds = reader.GetDataInformation().GetBounds()
SCALE = max(_bounds[1] - _bounds[0], _bounds[3] - _bounds[2], _bounds[5] - _bounds[4])

filters = {
    "cell-cut": (CrackSurfaceCellCut, "vtp"),  # noqa: F821
    "local-voronoi": (CrackSurfaceLocalVoronoi, "vtp"),  # noqa: F821
    "cell-centre": (CrackSurfaceCellCentre, "vtp"),  # noqa: F821
    "cell-attribute": (CrackCellsCellAttribute, "vtu"),  # noqa: F821
}
failed = False
for method, (make_filter, extension) in filters.items():
    ours, our_cells, our_bonds = measure(make_filter(Input=reader), last)
    path = f"{reference_dir}/{method}.{extension}"
    cli = XMLPolyDataReader(FileName=[path]) if extension == "vtp" else \
        XMLUnstructuredGridReader(FileName=[path])
    reference, cli_cells, cli_bonds = measure(cli, 0.0)
    same = (ours["cells"] == reference["cells"]
            and abs(ours["size"] - reference["size"]) <= 1e-9 * max(1.0, abs(reference["size"]))
            and our_cells == cli_cells and our_bonds == cli_bonds)
    differing = len(set(our_cells) ^ set(cli_cells))
    every_rank = ours["ranks_with_cells"] == ranks
    # Cell attribute's cells right side out: Integrate Variables sums a
    # positive volume (inside-out cells once made it negative).
    positive = method != "cell-attribute" or ours["size"] > 0.0
    print(json.dumps({"method": method, "ranks": ranks, "steps": len(times), "plugin": ours,
                      "cli": reference, "cells_differing": differing, "same": same,
                      "every_rank_has_cells": every_rank, "positive_volume": positive}))
    failed = failed or not same or not every_rank or not positive or reference["cells"] == 0
# Under MPI, sys.exit on the first rank makes mpiexec kill the others
# (SIGTERM, exit status 1 for the run): only a failure exits early.
if failed:
    sys.exit(1)
