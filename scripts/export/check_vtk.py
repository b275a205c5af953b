#!/usr/bin/python3
"""Read a `liedyn export --format vtk` series with VTK's own reader, as ParaView would.

Usage: scripts/export/check_vtk.py RUN_PVD [--frames F] [--points P] [--lines L] [--polys T]
                                          [--fields NAME,NAME,...]

Reads every DataSet file the .pvd lists (and colliders.vtp beside it, if there) with
vtkXMLPolyDataReader, and prints per file its point, line and polygon counts and each point
field's range; the last line is "check_vtk: F frames, P points, L lines, T polys, fields ...".
With the options, checks the number of frames, that every frame has P points, L lines and
T polygons, and that every frame has the named point fields. Fails (exit 1) on any error VTK
reports, on non-finite values, and on timesteps that do not increase.
Exit status: 0 passed, 1 a check failed, 2 usage error, 77 VTK's Python module is missing
(ctest's SKIP_RETURN_CODE; Debian: apt-get install -y python3-vtk9).
"""
import argparse
import math
import os
import sys
import xml.etree.ElementTree as ET

try:
    import vtk
except ImportError as error:
    print(f"check_vtk: SKIPPED: cannot import vtk ({error}); apt-get install -y python3-vtk9", file=sys.stderr)
    sys.exit(77)


class ErrorCatcher:
    """Collects the errors and warnings a VTK reader reports (otherwise only printed)."""

    def __init__(self, reader):
        self.messages = []
        for event in ("ErrorEvent", "WarningEvent"):
            reader.AddObserver(event, self.catch)
        # The reader's executive reports some errors itself.
        reader.GetExecutive().AddObserver("ErrorEvent", self.catch)

    def catch(self, caller, event):
        self.messages.append(f"{event} from {caller.GetClassName()}")


def read(path):
    reader = vtk.vtkXMLPolyDataReader()
    errors = ErrorCatcher(reader)
    reader.SetFileName(path)
    reader.Update()
    if errors.messages or not reader.GetOutput():
        sys.exit(f"check_vtk: FAIL: {path}: VTK reported: {'; '.join(errors.messages) or 'no output'}")
    return reader.GetOutput()


def describe(path, data):
    fields = {}
    point_data = data.GetPointData()
    for i in range(point_data.GetNumberOfArrays()):
        array = point_data.GetArray(i)
        ranges = [array.GetRange(c) for c in range(array.GetNumberOfComponents())]
        for c in range(array.GetNumberOfComponents()):
            for t in range(array.GetNumberOfTuples()):
                if not math.isfinite(array.GetComponent(t, c)):
                    sys.exit(f"check_vtk: FAIL: {path}: {array.GetName()} has a non-finite value at point {t}")
        fields[array.GetName()] = ranges
    text = ", ".join(f"{name} " + " ".join(f"[{lo:.6g}, {hi:.6g}]" for lo, hi in r) for name, r in fields.items())
    print(f"{os.path.basename(path)}: {data.GetNumberOfPoints()} points, {data.GetNumberOfLines()} lines, "
          f"{data.GetNumberOfPolys()} polys; {text}")
    return fields


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("pvd")
    for option in ("frames", "points", "lines", "polys"):
        parser.add_argument(f"--{option}", type=int)
    parser.add_argument("--fields", default="")
    args = parser.parse_args()
    if not os.path.isfile(args.pvd):
        print(f"check_vtk: {args.pvd}: no such file", file=sys.stderr)
        return 2
    folder = os.path.dirname(os.path.abspath(args.pvd))
    entries = ET.parse(args.pvd).getroot().findall("./Collection/DataSet")
    failed = []
    times = [float(e.get("timestep")) for e in entries]
    if any(b <= a for a, b in zip(times, times[1:])):
        failed.append("timesteps do not increase")
    counts = set()
    missing = set()
    wanted = [f for f in args.fields.split(",") if f]
    for entry in entries:
        path = os.path.join(folder, entry.get("file"))
        data = read(path)
        fields = describe(path, data)
        counts.add((data.GetNumberOfPoints(), data.GetNumberOfLines(), data.GetNumberOfPolys()))
        missing.update(f for f in wanted if f not in fields)
    colliders = os.path.join(folder, "colliders.vtp")
    if os.path.exists(colliders):
        describe(colliders, read(colliders))
    if args.frames is not None and len(entries) != args.frames:
        failed.append(f"expected {args.frames} frames, the series has {len(entries)}")
    for name, index, want in (("points", 0, args.points), ("lines", 1, args.lines), ("polys", 2, args.polys)):
        if want is not None and any(c[index] != want for c in counts):
            failed.append(f"expected {want} {name} in every frame, found {sorted(c[index] for c in counts)}")
    if missing:
        failed.append(f"frames without the point fields {sorted(missing)}")
    first = sorted(counts)[0] if counts else (0, 0, 0)
    print(f"check_vtk: {len(entries)} frames, {first[0]} points, {first[1]} lines, {first[2]} polys, "
          f"fields {','.join(wanted) or '-'}")
    for f in failed:
        print(f"check_vtk: FAIL: {f}", file=sys.stderr)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
