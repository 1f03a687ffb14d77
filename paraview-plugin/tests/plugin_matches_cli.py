"""The plugin inside ParaView against crackvis's own CLI, on one file.

pvbatch [--no-mpi] plugin_matches_cli.py PLUGIN FILE.h5 REFERENCE_DIR
pvpython plugin_matches_cli.py PLUGIN FILE.h5 REFERENCE_DIR HOST:PORT   (against a pvserver)

REFERENCE_DIR holds `crackvis extract FILE.h5 -m METHOD -s -1` of each method
(cell-cut.vtp, local-voronoi.vtp, cell-centre.vtp, cell-attribute.vtu). The
plugin's reader opens FILE.h5, each filter extracts the last step, and its
output, gathered from every rank, must have the CLI's cell and point counts
and area (volume for the cell attribute method). Prints one JSON line per
method and exits 1 on the first difference.
"""
import json
import sys

from paraview import servermanager
from paraview.simple import (Connect, IntegrateVariables, LoadPlugin, XMLPolyDataReader,
                             XMLUnstructuredGridReader)

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


def measure(source, time):
    """Cells, points and the integrated size of `source`, over all ranks."""
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
    return {"cells": info.GetNumberOfCells(), "points": info.GetNumberOfPoints(), "size": size}


filters = {
    "cell-cut": (CrackSurfaceCellCut, "vtp"),  # noqa: F821
    "local-voronoi": (CrackSurfaceLocalVoronoi, "vtp"),  # noqa: F821
    "cell-centre": (CrackSurfaceCellCentre, "vtp"),  # noqa: F821
    "cell-attribute": (CrackCellsCellAttribute, "vtu"),  # noqa: F821
}
failed = False
for method, (make_filter, extension) in filters.items():
    ours = measure(make_filter(Input=reader), last)
    path = f"{reference_dir}/{method}.{extension}"
    cli = XMLPolyDataReader(FileName=[path]) if extension == "vtp" else \
        XMLUnstructuredGridReader(FileName=[path])
    reference = measure(cli, 0.0)
    same = (ours["cells"] == reference["cells"] and ours["points"] == reference["points"]
            and abs(ours["size"] - reference["size"]) <= 1e-9 * max(1.0, abs(reference["size"])))
    print(json.dumps({"method": method, "ranks": ranks, "steps": len(times), "plugin": ours,
                      "cli": reference, "same": same}))
    failed = failed or not same or reference["cells"] == 0
# Under MPI, sys.exit on the first rank makes mpiexec kill the others
# (SIGTERM, exit status 1 for the run): only a failure exits early.
if failed:
    sys.exit(1)
