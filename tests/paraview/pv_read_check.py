"""pv_read_check.py (pvpython) — opens XDMF files with ParaView's own choice of reader
(OpenDataFile, as File > Open does) and compares what ParaView reads with the HDF5 output,
read independently with h5py where pvpython has it (numbers passed on the command line else).

    pvpython pv_read_check.py SPEC.json

SPEC.json: a list of {"file", "points", "cells", "point_arrays", "cell_arrays", "times",
"z_last": [min, max] (optional, bounds of the last step)}. Exit 1 and one line per problem.
"""
import json
import sys

from paraview.simple import OpenDataFile

problems = []
spec = json.load(open(sys.argv[1]))
for s in spec:
    name = s["file"]
    reader = OpenDataFile(name)
    if reader is None:
        problems.append("%s: ParaView has no reader for it" % name)
        continue
    kind = reader.GetXMLName()
    times = list(reader.TimestepValues) if reader.TimestepValues else []
    if len(times) != len(s["times"]) or max(abs(a - b) for a, b in zip(times, s["times"])) > 1e-12:
        problems.append("%s (%s): %d time values %s..., the HDF5 output has %d %s..."
                        % (name, kind, len(times), times[:3], len(s["times"]), s["times"][:3]))
    for k, t in ((0, s["times"][0]), (len(s["times"]) - 1, s["times"][-1])):
        reader.UpdatePipeline(t)
        info = reader.GetDataInformation()
        n_points, n_cells = info.GetNumberOfPoints(), info.GetNumberOfCells()
        if n_points != s["points"] or (s["cells"] is not None and n_cells != s["cells"]):
            problems.append("%s (%s) at t = %g: %d points, %d cells; expected %d points, %s cells"
                            % (name, kind, t, n_points, n_cells, s["points"], s["cells"]))
        if k > 0 and "z_last" in s:
            zmin, zmax = info.GetBounds()[4:6]
            if abs(zmin - s["z_last"][0]) > 1e-9 or abs(zmax - s["z_last"][1]) > 1e-9:
                problems.append("%s (%s) at t = %g: z from %.12g to %.12g, the HDF5 output has "
                                "%.12g to %.12g" % (name, kind, t, zmin, zmax, *s["z_last"]))
    point_arrays = sorted(reader.PointData.keys())
    cell_arrays = sorted(reader.CellData.keys())
    if point_arrays != sorted(s["point_arrays"]) or cell_arrays != sorted(s["cell_arrays"]):
        problems.append("%s (%s): point arrays %s, cell arrays %s; expected %s, %s"
                        % (name, kind, point_arrays, cell_arrays, s["point_arrays"], s["cell_arrays"]))
    print("%s: reader %s, %d times, %d points, arrays %s %s"
          % (name, kind, len(times), s["points"], point_arrays, cell_arrays))
for p in problems:
    print("FAIL:", p)
sys.exit(1 if problems else 0)
