"""A pvpython client against deploy/pvserver-beside-data.sh: the server reads
a crackvis-dem file through the plugin, extracts the last step's crack and
renders it (server-side, forced); the screenshot must show it.

pvpython pvserver_renders.py PLUGIN FILE.h5 HOST:PORT OUT.png
"""
import json
import sys

from paraview.simple import (Connect, GetActiveViewOrCreate, LoadPlugin, Render, ResetCamera,
                             SaveScreenshot, Show)
from vtkmodules.vtkIOImage import vtkPNGReader

plugin, data_file, server, out = sys.argv[1:5]
host, port = server.rsplit(":", 1)
Connect(host, int(port))
LoadPlugin(plugin, remote=False, ns=globals())
reader = crackvisdemreader(FileName=data_file)  # noqa: F821 (made by LoadPlugin)
crack = CrackSurfaceLocalVoronoi(Input=reader)  # noqa: F821
view = GetActiveViewOrCreate("RenderView")
view.ViewSize = [480, 360]
view.RemoteRenderThreshold = 0.0  # render on the server, beside the data
view.ViewTime = reader.TimestepValues[-1]
view.UseColorPaletteForBackground = 0  # ParaView 5.11: else the palette's wins
view.Background = [0.0, 0.0, 0.0]
view.OrientationAxesVisibility = 0
Show(crack, view)
ResetCamera(view)
Render(view)
SaveScreenshot(out, view, ImageResolution=[480, 360])

image = vtkPNGReader()
image.SetFileName(out)
image.Update()
pixels = image.GetOutput().GetPointData().GetScalars()
lit = sum(1 for i in range(pixels.GetNumberOfTuples()) if max(pixels.GetTuple(i)[:3]) > 0)
cells = crack.GetDataInformation().GetNumberOfCells()
print(json.dumps({"cells": cells, "lit_pixels": lit, "pixels": pixels.GetNumberOfTuples()}))
if cells == 0 or lit < 500:
    sys.exit(1)
