"""ParaView peer of crackvis's render benchmark (run by tools/bench/paraview-peer.sh).

Connects ParaView 5.11's pvpython to a pvserver already listening on localhost,
builds crackvis's default scene (particles as spheres, the crack surface as a
surface, reset camera) in a render view that the server renders (remote
rendering), and times what a ParaView user waits for: the data load, the first
frame, still renders and a drag of the camera. Writes one JSON object to the
file given by --json-out; progress goes to stderr.

Every time is measured on the client around a synchronous call, so it includes
the server's render, its image compression, the transfer over loopback and the
client's decompression and display: the same end-to-end path as crackvis's
render -> encode -> stream.
"""

import argparse
import json
import math
import os
import sys
import time

from paraview import servermanager
from paraview import simple

# crackvis's default view (pipeline/.../pipeline_description.hpp):
# background #1e1e28, particles solid #b0b0b0, cracks solid #e03c31.
BACKGROUND = [0x1E / 255, 0x1E / 255, 0x28 / 255]
PARTICLE_COLOUR = [0xB0 / 255, 0xB0 / 255, 0xB0 / 255]
CRACK_COLOUR = [0xE0 / 255, 0x3C / 255, 0x31 / 255]
RADIUS_ARRAY = "radius"  # the point array `crackvis export --particles` writes
STILL_AZIMUTH = 0.5  # degrees between still frames: a new image, no cache hit
DRAG_AZIMUTH = 1.8  # degrees per mouse-move event of the simulated drag


def log(message):
    print("paraview_peer: " + message, file=sys.stderr, flush=True)


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--port", type=int, required=True, help="pvserver's port on localhost")
    parser.add_argument("--particles", help="particles .pvd (crackvis export)")
    parser.add_argument("--crack", help="crack surface .vtp (crackvis extract); omit for none")
    parser.add_argument("--h5", help="read this crackvis-dem file on pvserver through the crackvis "
                        "plugin (its reader and local Voronoi filter) instead of --particles/--crack")
    parser.add_argument("--plugin", help="the plugin (Crackvis.so) for the client, with --h5")
    parser.add_argument("--work", required=True, help="a folder for the radius check's files")
    parser.add_argument("--step", type=int, required=True, help="the step shown (reported only)")
    parser.add_argument("--size", default="1280x720", help="view size WxH")
    parser.add_argument("--frames", type=int, default=20, help="timed frames per measurement")
    parser.add_argument("--warmup", type=int, default=2, help="untimed frames before each")
    parser.add_argument("--colour-by", choices=["solid", "radius"], default="solid")
    parser.add_argument("--fxaa", action="store_true", help="keep ParaView's FXAA (crackvis has none)")
    parser.add_argument("--no-radius-check", action="store_true")
    parser.add_argument("--screenshot", help="save the still view at the first frame's camera")
    parser.add_argument("--ranks", type=int, default=1, help="pvserver's MPI ranks (reported only)")
    parser.add_argument("--render-path", default="", help="how pvserver gets GL (reported only)")
    parser.add_argument("--package-version", default="", help="Debian version (reported only)")
    parser.add_argument("--json-out", required=True)
    args = parser.parse_args()
    if bool(args.h5) == bool(args.particles) or (args.h5 and not args.plugin):
        parser.error("give --particles (and --crack), or --h5 with --plugin")
    try:
        width, height = (int(v) for v in args.size.lower().split("x"))
    except ValueError:
        parser.error("--size must be WxH, e.g. 1280x720")
    if width < 16 or height < 16 or args.frames < 1:
        parser.error("--size must be at least 16x16 and --frames at least 1")
    args.width, args.height = width, height
    return args


def percentile(sorted_values, fraction):
    """Linear interpolation between closest ranks (numpy's default)."""
    position = (len(sorted_values) - 1) * fraction
    lower = math.floor(position)
    upper = min(lower + 1, len(sorted_values) - 1)
    return sorted_values[lower] + (sorted_values[upper] - sorted_values[lower]) * (position - lower)


def summary(samples_ms):
    ordered = sorted(samples_ms)
    return {
        "p50": round(percentile(ordered, 0.5), 2),
        "p90": round(percentile(ordered, 0.9), 2),
        "mean": round(sum(ordered) / len(ordered), 2),
        "min": round(ordered[0], 2),
        "max": round(ordered[-1], 2),
        "count": len(ordered),
        "samples": [round(v, 2) for v in samples_ms],
    }


def timed_ms(call):
    start = time.perf_counter()
    call()
    return (time.perf_counter() - start) * 1000.0


def server_opengl():
    """Vendor, renderer and version of the GL context pvserver renders with."""
    from paraview.modules.vtkRemotingCore import vtkPVSession
    from paraview.modules.vtkRemotingViews import vtkPVOpenGLInformation

    info = vtkPVOpenGLInformation()
    session = servermanager.ActiveConnection.Session
    session.GatherInformation(vtkPVSession.RENDER_SERVER_ROOT, info, 0)
    return {"vendor": info.GetVendor(), "renderer": info.GetRenderer(), "version": info.GetVersion()}


def reduction_in_client_image(view):
    """The image reduction factor visible in the image the client shows now:
    the largest f in (8, 4, 2) for which the image is made of f x f blocks
    of one colour (the server's smaller image scaled up), else 1.

    Measured rather than read from the settings because ParaView applies
    ImageReductionFactor only through its parallel (IceT) compositor, which a
    single-rank pvserver does not create (vtkPVSynchronizedRenderer::
    Initialize): with one rank the factor is configured but has no effect."""
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    grab = vtkWindowToImageFilter()
    grab.SetInput(view.GetRenderWindow())
    grab.ShouldRerenderOff()  # the image as delivered, not a new render
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput()
    width, height, _ = image.GetDimensions()
    components = image.GetNumberOfScalarComponents()
    pixels = bytes(memoryview(image.GetPointData().GetScalars()))

    def pixel(x, y):
        start = (y * width + x) * components
        return pixels[start : start + 3]

    for factor in (8, 4, 2):
        pairs = equal = 0
        for y in range(0, height - 1, 3):
            for x in range(0, width - 1, 3):
                if x % factor != factor - 1:
                    pairs += 1
                    equal += pixel(x, y) == pixel(x + 1, y)
                if y % factor != factor - 1:
                    pairs += 1
                    equal += pixel(x, y) == pixel(x, y + 1)
        if pairs and equal >= 0.99 * pairs:
            return factor
    return 1


def show_spheres(source, view, colour_by):
    """Point Gaussian with the sphere shader, each splat scaled to its particle's radius."""
    display = simple.Show(source, view)
    display.SetRepresentationType("Point Gaussian")
    display.Emissive = 0
    display.ShaderPreset = "Sphere"
    display.ScaleByArray = 1
    display.SetScaleArray = ["POINTS", RADIUS_ARRAY]
    display.UseScaleFunction = 0
    # The splat's radius is GaussianRadius x the array value: 1 gives the
    # particle's own radius (checked by radius_check below).
    display.GaussianRadius = 1.0
    if colour_by == "radius":
        simple.ColorBy(display, ("POINTS", RADIUS_ARRAY))
        display.RescaleTransferFunctionToDataRange(True, False)
        simple.GetColorTransferFunction(RADIUS_ARRAY).ApplyPreset("Viridis (matplotlib)", True)
    else:
        # ColorBy(display, None) fails in 5.11 on a fresh display ("NONE").
        display.ColorArrayName = ["POINTS", ""]
        display.AmbientColor = PARTICLE_COLOUR
        display.DiffuseColor = PARTICLE_COLOUR
    return display


def show_surface(source, view):
    display = simple.Show(source, view)
    display.SetRepresentationType("Surface")
    display.ColorArrayName = ["CELLS", ""]
    display.AmbientColor = CRACK_COLOUR
    display.DiffuseColor = CRACK_COLOUR
    return display


def radius_check(folder):
    """Renders one particle of radius 1 (a .vtp read like the real data) beside
    a true sphere of radius 1, parallel projection at 100 px per unit, and
    returns both diameters in pixels along the middle row: equal when the
    splats have the particles' true radii."""
    from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkPoints
    from vtkmodules.vtkCommonDataModel import vtkCellArray, vtkPolyData
    from vtkmodules.vtkIOImage import vtkPNGReader
    from vtkmodules.vtkIOXML import vtkXMLPolyDataWriter

    points = vtkPoints()
    points.InsertNextPoint(0, 0, 0)
    verts = vtkCellArray()
    verts.InsertNextCell(1)
    verts.InsertCellPoint(0)
    radius = vtkDoubleArray()
    radius.SetName(RADIUS_ARRAY)
    radius.InsertNextValue(1.0)
    particle = vtkPolyData()
    particle.SetPoints(points)
    particle.SetVerts(verts)
    particle.GetPointData().AddArray(radius)
    data_path = os.path.join(folder, "radius-check.vtp")
    writer = vtkXMLPolyDataWriter()
    writer.SetInputData(particle)
    writer.SetFileName(data_path)
    writer.Write()

    view = simple.CreateView("RenderView")
    view.ViewSize = [800, 400]
    view.RemoteRenderThreshold = 0
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = [1.0, 1.0, 1.0]
    splat = show_spheres(simple.XMLPolyDataReader(FileName=[data_path]), view, "solid")
    sphere = simple.Sphere(Radius=1.0, Center=[3, 0, 0], ThetaResolution=128, PhiResolution=128)
    solid = show_surface(sphere, view)
    for display in (splat, solid):
        display.AmbientColor = [0, 0, 0]
        display.DiffuseColor = [0, 0, 0]
    view.StillRender()
    view.CameraParallelProjection = 1
    view.CameraPosition = [1.5, 0, 10]
    view.CameraFocalPoint = [1.5, 0, 0]
    view.CameraViewUp = [0, 1, 0]
    view.CameraParallelScale = 2.0  # 4 units over 400 px
    view.StillRender()
    image_path = os.path.join(folder, "radius-check.png")
    simple.SaveScreenshot(image_path, view, ImageResolution=[800, 400])
    reader = vtkPNGReader()
    reader.SetFileName(image_path)
    reader.Update()
    image = reader.GetOutput()
    width, height, _ = image.GetDimensions()
    dark = [x for x in range(width) if image.GetScalarComponentAsDouble(x, height // 2, 0, 0) < 128]
    simple.Delete(view)
    return {
        "point_gaussian_px": sum(1 for x in dark if x < width / 2),
        "true_sphere_px": sum(1 for x in dark if x >= width / 2),
        "expected_px": 200,
    }


def main():
    args = parse_args()
    load_before = os.getloadavg()
    simple.Connect("localhost", args.port)
    sm = servermanager.vtkSMProxyManager
    version = "%d.%d.%d" % (sm.GetVersionMajor(), sm.GetVersionMinor(), sm.GetVersionPatch())
    if not servermanager.ActiveConnection.IsRemote():
        raise SystemExit("paraview_peer: not connected to a remote pvserver")
    log("connected to pvserver %s on port %d" % (version, args.port))

    view = simple.CreateView("RenderView")
    view.ViewSize = [args.width, args.height]
    # 0 MB: the server renders every frame and ships the image (remote rendering).
    view.RemoteRenderThreshold = 0
    view.OrientationAxesVisibility = 0
    view.UseColorPaletteForBackground = 0
    view.Background = BACKGROUND
    view.UseFXAA = 1 if args.fxaa else 0
    simple.SetActiveView(view)

    # Load: the server reads both files (the readers run on pvserver); with
    # the plugin it reads the crackvis-dem file and extracts the crack itself.
    sources = []

    def load():
        if args.h5:
            simple.LoadPlugin(args.plugin, remote=False, ns=globals())
            reader = globals()["crackvisdemreader"](FileName=args.h5)
            times = reader.TimestepValues or [0.0]
            view.ViewTime = times[args.step] if args.step < len(times) else times[-1]
            sources.append(reader)
            sources.append(globals()["CrackSurfaceLocalVoronoi"](Input=reader))
        else:
            sources.append(simple.PVDReader(FileName=args.particles))
            if args.crack:
                sources.append(simple.XMLPolyDataReader(FileName=[args.crack]))
        for source in sources:
            source.UpdatePipeline(view.ViewTime)

    load_ms = timed_ms(load)
    particles = sources[0]
    particle_count = particles.GetDataInformation().GetNumberOfPoints()
    if particle_count == 0:
        raise SystemExit("paraview_peer: no particles in " + (args.h5 or args.particles))
    if RADIUS_ARRAY not in particles.PointData.keys():
        raise SystemExit("paraview_peer: %s has no point array '%s'"
                         % (args.h5 or args.particles, RADIUS_ARRAY))
    crack_cells = sources[1].GetDataInformation().GetNumberOfCells() if len(sources) > 1 else 0
    geometry_mb = sum(s.GetDataInformation().GetMemorySize() for s in sources) / 1024.0
    log("loaded %d particles, %d crack polygons in %.0f ms" % (particle_count, crack_cells, load_ms))

    # First frame: representations built and data moved to the renderer,
    # VTK's reset camera (looking down -z, view up +y) on the whole scene, the
    # shaders compiled, the first image on the client.
    def first_frame():
        show_spheres(particles, view, args.colour_by)
        if len(sources) > 1:
            show_surface(sources[1], view)
        view.CameraPosition = [0, 0, 1]
        view.CameraFocalPoint = [0, 0, 0]
        view.CameraViewUp = [0, 1, 0]
        view.ResetCamera()
        view.StillRender()

    first_frame_ms = timed_ms(first_frame)
    log("first frame %.0f ms" % first_frame_ms)
    camera = view.GetActiveCamera()
    initial = (camera.GetPosition(), camera.GetFocalPoint(), camera.GetViewUp())
    if args.screenshot:
        simple.SaveScreenshot(args.screenshot, view, ImageResolution=[args.width, args.height])

    # Still renders: full resolution (StillRenderImageReductionFactor 1), the
    # camera moved a little before each so that every frame is a new image.
    still = []
    for i in range(args.warmup + args.frames):
        camera.Azimuth(STILL_AZIMUTH)
        ms = timed_ms(view.StillRender)
        if i >= args.warmup:
            still.append(ms)
    log("still p50 %.1f ms" % percentile(sorted(still), 0.5))

    # Interactive: what the GUI does on each mouse-move of a rotation drag,
    # vtkSMViewProxy::InteractiveRender(): lossy image compression, LOD
    # geometry above LODThreshold, and 1/ImageReductionFactor of the size
    # scaled up by the client, but the last only with an IceT compositor
    # (pvserver on 2+ ranks); the factor in effect is measured below.
    camera.SetPosition(initial[0])
    camera.SetFocalPoint(initial[1])
    camera.SetViewUp(initial[2])
    interactive = []
    for i in range(args.warmup + args.frames):
        camera.Azimuth(DRAG_AZIMUTH)
        ms = timed_ms(view.InteractiveRender)
        if i >= args.warmup:
            interactive.append(ms)
    effective_reduction = reduction_in_client_image(view)
    # The GUI follows a drag with one still render (on release); not timed.
    view.StillRender()
    still_reduction = reduction_in_client_image(view)
    log(
        "interactive p50 %.1f ms, image reduction %d (configured %d)"
        % (percentile(sorted(interactive), 0.5), effective_reduction, view.ImageReductionFactor)
    )

    check = None if args.no_radius_check else radius_check(args.work)
    load_after = os.getloadavg()

    lod_threshold_mb = float(view.LODThreshold)
    result = {
        "tool": "paraview",
        "version": version,
        "debian_package": args.package_version,
        "size": "%dx%d" % (args.width, args.height),
        "particles": particle_count,
        "crack_polygons": crack_cells,
        "step": args.step,
        "still_render_ms": dict(summary(still), image_reduction_factor=still_reduction),
        "interactive_ms": dict(
            summary(interactive),
            image_reduction_factor=effective_reduction,
            image_reduction_factor_configured=int(view.ImageReductionFactor),
            lod_used=geometry_mb >= lod_threshold_mb,
            lod_threshold_mb=lod_threshold_mb,
            geometry_mb=round(geometry_mb, 2),
            azimuth_per_event_deg=DRAG_AZIMUTH,
        ),
        "first_frame_ms": round(first_frame_ms, 1),
        "load_ms": round(load_ms, 1),
        "representation": "Point Gaussian, Sphere shader (Emissive off, scale by '%s', "
        "GaussianRadius 1) + crack surface" % RADIUS_ARRAY,
        "data_path": "pvserver reads the .h5 through the crackvis plugin and extracts the crack "
        "(local Voronoi)" if args.h5 else "crackvis export/extract files read by ParaView's XML readers",
        "colouring": (
            "particles solid #b0b0b0, crack solid #e03c31 (crackvis defaults)"
            if args.colour_by == "solid"
            else "particles by radius (Viridis), crack solid #e03c31"
        ),
        "background": "#1e1e28 (crackvis default)",
        "camera": "VTK reset camera on the whole scene, looking down -z, view up +y; "
        "still: Azimuth(%g) per frame" % STILL_AZIMUTH,
        "fxaa": bool(args.fxaa),
        "remote_render_threshold_mb": 0,
        "image_compression": "%s: LZ4, lossless for still renders, lossy (colour "
        "reduction) for interactive ones" % view.CompressorConfig,
        "pvserver_ranks": args.ranks,
        "opengl": server_opengl(),
        "render_path": args.render_path,
        "lp_num_threads": os.environ.get("LP_NUM_THREADS", "unset (llvmpipe: one per CPU)"),
        "cpus": os.cpu_count(),
        "loadavg_before": [round(v, 2) for v in load_before],
        "loadavg_after": [round(v, 2) for v in load_after],
    }
    if check is not None:
        check["ok"] = abs(check["point_gaussian_px"] - check["true_sphere_px"]) <= 2
        result["radius_check"] = check
        if not check["ok"]:
            # Seen with --ranks 2: IceT compositing drops the lone splat.
            log("WARNING: Point Gaussian spheres are not drawn at the particles' radii: %s" % check)
    with open(args.json_out, "w") as out:
        json.dump(result, out, indent=2)
        out.write("\n")


if __name__ == "__main__":
    main()
