"""One run of tools/bench/mpi-ranks.sh, under pvbatch (R MPI ranks or none).

The crackvis plugin's reader and local Voronoi filter on FILE, the crack
shown in a render view of SIZE: the first update at step FIRST (the reader
finds its piece, reads it and the step, the filter extracts), its first
frame, then each following step of COUNT: update (read + extract), frame
(render + composite across ranks). With "baseline" as FILE it loads the
plugin and renders an empty view: the fixed part of a rank's memory.
Writes the timings (ms) as JSON to OUT.

    pvbatch mpi_ranks.py PLUGIN FILE first=FIRST COUNT WIDTHxHEIGHT OUT [ghost=W]

ghost=W sets the reader's GhostWidth (ghost=default: the reader's own).

FIRST comes as first=FIRST: pvbatch takes a bare negative number of two
digits (-10) for one of its own options.
"""
import json
import sys
import time

from paraview.simple import (CreateRenderView, GetActiveCamera, LoadPlugin, Render, ResetCamera,
                             Show)
from paraview import servermanager

plugin, path, first, count, size, out = sys.argv[1:7]
ghost = sys.argv[7].removeprefix("ghost=") if len(sys.argv) > 7 else "default"
first, count = int(first.removeprefix("first=")), int(count)
width, height = (int(v) for v in size.split("x"))
LoadPlugin(plugin, ns=globals())
view = CreateRenderView()
view.ViewSize = [width, height]
view.OrientationAxesVisibility = 0
result = {"ranks": servermanager.ActiveConnection.GetNumberOfDataPartitions()}

def ms_since(start):
    return 1000.0 * (time.perf_counter() - start)


def resident_mib():
    """This process's (rank 0's) resident memory, MiB: what each part of the run adds."""
    with open("/proc/self/status") as status:
        for line in status:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    return -1.0

if path == "baseline":
    start = time.perf_counter()
    Render(view)
    result["first_frame_ms"] = ms_since(start)
else:
    reader = crackvisdemreader(FileName=path)  # noqa: F821 (the plugin defines it)
    if ghost != "default":
        reader.GhostWidth = float(ghost)
        result["ghost_width"] = float(ghost)
    times = list(reader.TimestepValues) if len(reader.TimestepValues) > 1 else [reader.TimestepValues]
    first = first if first >= 0 else len(times) + first
    steps = list(range(first, min(first + 1 + count, len(times))))
    crack = CrackSurfaceLocalVoronoi(Input=reader)  # noqa: F821
    # The first update before Show: Show updates the pipeline at the view's
    # time when it has no data yet, which would do the piece's preparation
    # (open, find and read the piece, triangulate) outside the timer.
    result["rss_mib"] = {"before": resident_mib()}
    start = time.perf_counter()
    crack.UpdatePipeline(times[steps[0]])
    result["first_update_ms"] = ms_since(start)
    result["rss_mib"]["first_update"] = resident_mib()
    view.ViewTime = times[steps[0]]
    start = time.perf_counter()
    Show(crack, view)
    result["show_ms"] = ms_since(start)
    result["rss_mib"]["show"] = resident_mib()
    ResetCamera(view)
    GetActiveCamera().Azimuth(30)
    start = time.perf_counter()
    Render(view)
    result["first_frame_ms"] = ms_since(start)
    result["rss_mib"]["first_frame"] = resident_mib()
    result["cells"] = crack.GetDataInformation().GetNumberOfCells()
    result["steps"] = []
    for step in steps[1:]:
        start = time.perf_counter()
        crack.UpdatePipeline(times[step])
        update = ms_since(start)
        # On the clock of the plugin's CRACKVIS_VTK_TIMINGS lines (CLOCK_MONOTONIC).
        update_span = [1000.0 * start, 1000.0 * start + update]
        view.ViewTime = times[step]
        start = time.perf_counter()
        Render(view)
        result["steps"].append({"step": step, "update_ms": update, "frame_ms": ms_since(start),
                                "update_span": update_span, "rss_mib": resident_mib()})
with open(out, "w") as handle:
    json.dump(result, handle)
