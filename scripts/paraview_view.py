#!/usr/bin/env pvpython
"""paraview_view.py — a picture (or an animation) of a netcouple run folder, made with ParaView.

    xvfb-run -a pvpython scripts/paraview_view.py RUN_DIR [--out FILE.png] [--time T]
                        [--animation DIR] [--size W H] [--azimuth DEG] [--zoom F]
                        [--tube-scale F]

Opens what the folder holds with ParaView's default reader: fem.xdmf (the net, drawn as tubes
coloured by axial_force in N), particles.xdmf (each rock a sphere of its true radius: Glyph of
a unit-diameter sphere scaled by 2 x radius) and, without fem.xdmf, dem_net.xdmf (the DEM's
copy of the net). --time picks the output time shown (default: when the net's largest
displacement occurred, fem.h5 /output/displacement attribute max_time, else the last step);
--animation DIR also writes one PNG per output step into DIR (frame_0000.png, ...).
The camera looks obliquely from the side the rock comes from (-y), z up; --azimuth turns it
about the vertical through the scene's centre, --zoom moves it closer (2: half the distance;
a long barrier with far anchors needs it to show its net); --tube-scale thins (< 1) or
thickens the ropes' tubes (radius 0.4 % of the scene by default).
Needs Debian's python3-paraview (and xvfb for xvfb-run on a machine without a display).
"""
import argparse
import os
import sys

from paraview.simple import (AnnotateTime, ColorBy, CreateView, ExtractSurface, GetAnimationScene, GetColorTransferFunction,
                             GetScalarBar, Glyph, OpenDataFile, SaveAnimation, SaveScreenshot,
                             Render, SetActiveView, Show, Text, Tube, UpdatePipeline)


def largest_displacement_time(run_dir):
    try:
        import h5py
        with h5py.File(os.path.join(run_dir, "fem.h5"), "r") as f:
            return float(f["/output/displacement"].attrs["max_time"])
    except (ImportError, OSError, KeyError):
        return None


def nearest(times, t):
    return min(times, key=lambda x: abs(x - t)) if times else t


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[1])
    ap.add_argument("run_dir")
    ap.add_argument("--out", help="PNG file (default RUN_DIR/paraview.png)")
    ap.add_argument("--time", type=float, help="output time to show")
    ap.add_argument("--animation", help="folder for one PNG per output step")
    ap.add_argument("--size", type=int, nargs=2, default=[1200, 700], metavar=("W", "H"))
    ap.add_argument("--azimuth", type=float, default=0.0, help="turn the camera about z (degrees)")
    ap.add_argument("--zoom", type=float, default=1.0, help="> 1 moves the camera closer")
    ap.add_argument("--tube-scale", type=float, default=1.0, help="tube radius factor")
    args = ap.parse_args()
    d = args.run_dir
    files = {name: os.path.join(d, name) for name in ("fem.xdmf", "particles.xdmf", "dem_net.xdmf")
             if os.path.isfile(os.path.join(d, name))}
    if not files:
        sys.exit("paraview_view: %s holds no fem.xdmf, particles.xdmf or dem_net.xdmf" % d)
    view = CreateView("RenderView")
    SetActiveView(view)
    view.ViewSize = args.size
    view.Background = [1, 1, 1]
    view.OrientationAxesVisibility = 1
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    times = []
    net_file = files.get("fem.xdmf") or files.get("dem_net.xdmf")
    sources = []
    shown_sources = []
    lut = tube = None
    if net_file:
        net = OpenDataFile(net_file)
        times = list(net.TimestepValues or [])
        sources.append(net)
        tube = Tube(Input=ExtractSurface(Input=net))   # Tube needs polydata
        tube.NumberofSides = 12
        shown = Show(tube, view)
        shown_sources.append(tube)
        if net_file.endswith("fem.xdmf"):
            ColorBy(shown, ("CELLS", "axial_force"))
            lut = GetColorTransferFunction("axial_force")
            lut.ApplyPreset("Cool to Warm", True)
            bar = GetScalarBar(lut, view)
            bar.Title = "axial force [N]"
            bar.ComponentTitle = ""
            bar.TitleColor = bar.LabelColor = [0, 0, 0]
            shown.SetScalarBarVisibility(view, True)
        else:
            shown.DiffuseColor = [0.3, 0.3, 0.3]
    if "particles.xdmf" in files:
        rocks = OpenDataFile(files["particles.xdmf"])
        if not times:
            times = list(rocks.TimestepValues or [])
        sources.append(rocks)
        glyph = Glyph(Input=rocks, GlyphType="Sphere")
        glyph.ScaleArray = ["POINTS", "radius"]
        glyph.ScaleFactor = 2.0          # the sphere source has diameter 1: scale 2 r = true size
        glyph.GlyphMode = "All Points"
        glyph.GlyphType.ThetaResolution = 32
        glyph.GlyphType.PhiResolution = 32
        g = Show(glyph, view)
        shown_sources.append(glyph)
        ColorBy(g, None)
        g.DiffuseColor = [0.55, 0.45, 0.35]
    t = args.time
    if t is None:
        t = largest_displacement_time(d)
    if t is None:
        t = times[-1] if times else 0.0
    t = nearest(times, t)
    scene = GetAnimationScene()
    scene.UpdateAnimationUsingDataTimeSteps()
    view.ViewTime = t
    scene.AnimationTime = t
    for src in shown_sources:
        UpdatePipeline(t, src)
    if lut is not None:
        # the colour range over the shown step: tension is what the designer looks for
        lo, hi = tube.CellData["axial_force"].GetRange() if "axial_force" in tube.CellData.keys() else (0, 1)
        lut.RescaleTransferFunction(lo, hi if hi > lo else lo + 1.0)
    Render(view)   # the first render resets the camera: place it after
    # oblique view from the side the rock comes from, z up
    b = [1e300, -1e300] * 3
    for src in shown_sources:
        sb = src.GetDataInformation().GetBounds()
        for i in range(3):
            b[2 * i] = min(b[2 * i], sb[2 * i])
            b[2 * i + 1] = max(b[2 * i + 1], sb[2 * i + 1])
    c = [(b[2 * i] + b[2 * i + 1]) / 2 for i in range(3)]
    size = max(b[1] - b[0], b[3] - b[2], b[5] - b[4], 1e-3)
    if tube is not None:
        # a tube radius of 0.4 % of the scene keeps thin ropes visible at any scale
        tube.Radius = 0.004 * size * args.tube_scale
        UpdatePipeline(t, tube)
    view.CameraFocalPoint = c
    view.CameraPosition = [c[0] + 0.6 * size, c[1] - 1.6 * size, c[2] + 0.7 * size]
    view.CameraViewUp = [0, 0, 1]
    view.ResetCamera()
    camera = view.GetActiveCamera()
    if args.azimuth:
        camera.Azimuth(args.azimuth)
    if args.zoom != 1.0:
        camera.Dolly(args.zoom)
    label = Text(Text=os.path.basename(os.path.abspath(d)))
    lr = Show(label, view)
    lr.Color = [0, 0, 0]
    lr.WindowLocation = "Upper Left Corner"
    clock = AnnotateTime(Format="t = {time:.4f} s")   # follows the frame in an animation
    cr = Show(clock, view)
    cr.Color = [0, 0, 0]
    cr.WindowLocation = "Upper Right Corner"
    out = args.out or os.path.join(d, "paraview.png")
    SaveScreenshot(out, view, ImageResolution=args.size)
    print("paraview_view: %s at t = %g s -> %s" % (", ".join(sorted(files)), t, out))
    if args.animation:
        os.makedirs(args.animation, exist_ok=True)
        SaveAnimation(os.path.join(args.animation, "frame.png"), view, ImageResolution=args.size)
        frames = [f for f in os.listdir(args.animation) if f.startswith("frame.")]
        print("paraview_view: %d frames in %s" % (len(frames), args.animation))


if __name__ == "__main__":
    main()
