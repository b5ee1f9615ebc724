"""The standard views of a weld, rendered by ParaView to PNG files.

    pvpython tools/paraview_weld.py RESULTS [-o DIR] [--times MS [MS ...]]

RESULTS is the output folder of `rsw simulate` with its fields (fields.pvd, the default
output.fields: true), results.h5 and summary.json. Written into DIR (default
RESULTS/views):

  cross_section_<t>ms.png   the axisymmetric cross-section on the deformed mesh, mirrored
                            about the axis, coloured by temperature (degC), with the
                            sheets' solidus (white) and liquidus (black) isotherms;
  faying_surface_<t>ms.png  temperature (degC) and contact pressure (MPa) along the
                            sheet/sheet interface against the radius (mm), both sides
                            (the upper sheet's bottom, the lower sheet's top);
  nugget_growth.png         the nugget's diameter and height at the liquidus and the
                            solidus against time (results.h5 signals, mm and ms).

The times (ms) default to the end of the current and the end of the record; each is
taken at the nearest field output time. The solidus and liquidus are the sheets'
materials' (summary.json, "sheets").

Needs ParaView's Python (pvpython or pvbatch) with a display; on a headless machine run
it under xvfb-run. On Debian 12 ParaView's Python modules (python3-paraview) conflict with
python3-vtk9, which rsw's build needs; README.md, "ParaView views", gives the way around
(the modules unpacked beside the system's and named by PYTHONPATH, which this script puts
first on its module path).
"""
import argparse
import json
import os
import sys

# pvpython puts the system's dist-packages, where python3-vtk9 lives, ahead of PYTHONPATH:
# the directories the user named come first, so ParaView's own vtkmodules are imported.
for entry in reversed([p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]):
    while entry in sys.path:
        sys.path.remove(entry)
    sys.path.insert(0, entry)

from paraview import servermanager  # noqa: E402
from paraview import simple  # noqa: E402


def fail(message):
    print("paraview_weld.py: " + message, file=sys.stderr)
    sys.exit(2)


def read_inputs(results):
    pvd = os.path.join(results, "fields.pvd")
    summary_file = os.path.join(results, "summary.json")
    h5_file = os.path.join(results, "results.h5")
    for path in (pvd, summary_file, h5_file):
        if not os.path.isfile(path):
            fail(f"{path} not found: RESULTS must be the folder of `rsw simulate` with output.fields: true")
    with open(summary_file) as f:
        summary = json.load(f)
    if "sheets" not in summary:
        fail(f"{summary_file} has no 'sheets' (solidus and liquidus): written by an older rsw")
    import h5py
    with h5py.File(h5_file, "r") as h5:
        signals = {name: h5["signals"][name][()] for name in
                   ("time", "current", "d_n_liq", "h_n_liq", "d_n_sol", "h_n_sol")}
    return pvd, summary, signals


def default_times_ms(signals):
    time, current = signals["time"], signals["current"]
    flowing = [t for t, i in zip(time, current) if abs(i) > 0]
    return sorted({round(1e3 * (flowing[-1] if flowing else time[-1]), 6), round(1e3 * time[-1], 6)})


def nearest(values, target):
    return min(values, key=lambda v: abs(v - target))


def isotherms(summary):
    solidus = min(s["solidus_degC"] for s in summary["sheets"].values())
    liquidus = max(s["liquidus_degC"] for s in summary["sheets"].values())
    return solidus, liquidus


def cross_section(reader, time_s, summary, file):
    """The mirrored cross-section with the solidus and liquidus isotherms."""
    solidus, liquidus = isotherms(summary)
    warped = simple.WarpByVector(Input=reader, Vectors=["POINTS", "displacement"])
    mirrored = simple.Reflect(Input=warped, Plane="X", CopyInput=1)
    view = simple.CreateRenderView()
    view.ViewSize = [1200, 900]
    view.ViewTime = time_s
    view.OrientationAxesVisibility = 0
    view.Background = [0.2, 0.2, 0.2]
    view.UseColorPaletteForBackground = 0
    display = simple.Show(mirrored, view)
    simple.ColorBy(display, ("POINTS", "temperature"))
    lut = simple.GetColorTransferFunction("temperature")
    lut.ApplyPreset("Inferno (matplotlib)", True)
    lut.RescaleTransferFunction(20.0, liquidus + 300.0)
    lut.AutomaticRescaleRangeMode = "Never"
    bar = simple.GetScalarBar(lut, view)
    bar.Title = "temperature [degC]"
    bar.ComponentTitle = ""
    bar.TitleColor = bar.LabelColor = [1, 1, 1]
    display.SetScalarBarVisibility(view, True)
    for value, colour in ((solidus, [1, 1, 1]), (liquidus, [0, 0, 0])):
        contour = simple.Contour(Input=mirrored, ContourBy=["POINTS", "temperature"], Isosurfaces=[value])
        shown = simple.Show(contour, view)
        simple.ColorBy(shown, None)
        shown.AmbientColor = shown.DiffuseColor = colour
        shown.LineWidth = 3.0
    text = simple.Text(Text=f"t = {1e3 * time_s:.1f} ms; isotherms: solidus {solidus:.0f} degC (white), "
                            f"liquidus {liquidus:.0f} degC (black); mirrored about the axis")
    label = simple.Show(text, view)
    label.Color = [1, 1, 1]
    label.FontSize = 14
    label.WindowLocation = "Upper Center"
    simple.Render(view)  # the first render places the camera; the weld zone's view replaces it
    # The weld zone: 7 mm either side of the axis, the stack and the electrode tips.
    view.CameraPosition = [0.0, 0.0, 0.1]
    view.CameraFocalPoint = [0.0, 0.0, 0.0]
    view.CameraViewUp = [0.0, 1.0, 0.0]
    view.CameraParallelProjection = 1
    view.CameraParallelScale = 0.0055
    simple.Render(view)
    simple.SaveScreenshot(file, view, ImageResolution=[1200, 900])
    simple.Delete(view)


def boundary_profile(block, boundary_names, name):
    """(r in mm, temperature degC, contact pressure MPa) at the midpoints of the faces of one
    named boundary, on the deformed mesh; the pressure is a face value, the temperature
    the mean of the face's nodes."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    index = boundary_names.index(name)
    ids = vtk_to_numpy(block.GetCellData().GetArray("boundary_id"))
    pressure = vtk_to_numpy(block.GetCellData().GetArray("contact_pressure"))
    points = vtk_to_numpy(block.GetPoints().GetData())
    displacement = vtk_to_numpy(block.GetPointData().GetArray("displacement"))
    temperature = vtk_to_numpy(block.GetPointData().GetArray("temperature"))
    faces = []
    for cell in range(block.GetNumberOfCells()):
        if ids[cell] != index:
            continue
        point_ids = block.GetCell(cell).GetPointIds()
        nodes = [point_ids.GetId(k) for k in range(point_ids.GetNumberOfIds())]
        r = sum(points[n][0] + displacement[n][0] for n in nodes) / len(nodes)
        t = sum(temperature[n] for n in nodes) / len(nodes)
        faces.append((1e3 * r, t, 1e-6 * pressure[cell]))
    faces.sort()
    return [f[0] for f in faces], [f[1] for f in faces], [f[2] for f in faces]


def faying_surface(reader, time_s, file):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    reader.UpdatePipeline(time_s)
    data = servermanager.Fetch(reader)
    blocks = {data.GetMetaData(i).Get(data.NAME()): data.GetBlock(i) for i in range(data.GetNumberOfBlocks())}
    fig, (ax_t, ax_p) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
    found = False
    for block_name, boundary, style in (("sheet_1_boundaries", "sheet_1.bottom", "-"),
                                        ("sheet_2_boundaries", "sheet_2.top", "--")):
        block = blocks.get(block_name)
        if block is None:
            continue
        names_array = block.GetFieldData().GetAbstractArray("boundary_names")
        names = [names_array.GetValue(k) for k in range(names_array.GetNumberOfValues())]
        if boundary not in names:
            continue
        r, temperature, pressure = boundary_profile(block, names, boundary)
        ax_t.plot(r, temperature, style, label=boundary)
        ax_p.plot(r, pressure, style, label=boundary)
        found = True
    if not found:
        fail("no sheet/sheet interface (sheet_1.bottom, sheet_2.top) in the fields")
    ax_t.set_ylabel("temperature [degC]")
    ax_p.set_ylabel("contact pressure [MPa]")
    ax_p.set_xlabel("radius on the deformed mesh [mm]")
    ax_t.set_title(f"faying surface at t = {1e3 * time_s:.1f} ms")
    for ax in (ax_t, ax_p):
        ax.grid(True, alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(file, dpi=120)
    plt.close(fig)


def nugget_growth(signals, file):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    t = 1e3 * signals["time"]
    fig, ax = plt.subplots(figsize=(7, 4))
    for key, label, style in (("d_n_liq", "diameter, liquidus", "-"), ("d_n_sol", "diameter, solidus", "--"),
                              ("h_n_liq", "height, liquidus", "-"), ("h_n_sol", "height, solidus", "--")):
        ax.plot(t, 1e3 * signals[key], style, label=label)
    ax.set_xlabel("time [ms]")
    ax.set_ylabel("nugget [mm]")
    ax.set_title("nugget growth")
    ax.grid(True, alpha=0.3)
    ax.legend()
    fig.tight_layout()
    fig.savefig(file, dpi=120)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description="Standard ParaView views of a weld's results, as PNG files.")
    parser.add_argument("results", help="output folder of `rsw simulate` (with fields.pvd)")
    parser.add_argument("-o", "--output", help="folder of the PNG files (default RESULTS/views)")
    parser.add_argument("--times", type=float, nargs="+", metavar="MS",
                        help="times in ms (default: the end of the current and of the record)")
    args = parser.parse_args()
    pvd, summary, signals = read_inputs(args.results)
    out = args.output or os.path.join(args.results, "views")
    os.makedirs(out, exist_ok=True)
    reader = simple.PVDReader(FileName=pvd)
    available = list(reader.TimestepValues) or [0.0]
    for time_ms in args.times or default_times_ms(signals):
        time_s = nearest(available, 1e-3 * time_ms)
        tag = f"{1e3 * time_s:g}ms"
        for kind, draw in (("cross_section", lambda f: cross_section(reader, time_s, summary, f)),
                           ("faying_surface", lambda f: faying_surface(reader, time_s, f))):
            file = os.path.join(out, f"{kind}_{tag}.png")
            draw(file)
            print("wrote " + file)
    file = os.path.join(out, "nugget_growth.png")
    nugget_growth(signals, file)
    print("wrote " + file)


if __name__ == "__main__":
    main()
