#!/usr/bin/env python3
"""Reference VTK files written by VTK itself, for chisel's VTK readers.

Writes small files with known content into tests/data/vtk/ with VTK's own
writers (vtkXMLImageDataWriter, vtkXMLPolyDataWriter,
vtkStructuredPointsWriter) in every data mode chisel reads, and
tests/data/vtk/expected.json with what VTK's own readers report for each
file. The Rust unit tests in src/io/vtk/ and src/io/vtk_xml/ read every
file with chisel's readers and compare.

Usage: python scripts/make_vtk_references.py [--check-chisel DIR]
  (needs the `vtk` and `numpy` packages; made with VTK 9.7.2)

With --check-chisel DIR it instead reads every .vti/.vtp/.vtk file in DIR
(files written by chisel's writers, e.g. by the ignored unit test
`io::vtk_xml::tests::write_files_for_vtk` with CHISEL_VTK_OUT=DIR) with
VTK's readers and prints what they report, for comparison with
expected.json.

Image content: 5x4x3 samples of `short`, value = i + 10 j + 100 k - 50,
spacing (0.5, 0.75, 2), origin (-3, 4, 5), Direction a 90 degree rotation
about z (or a reflection, `image_reflect.vti`). Poly content: a low
resolution sphere (triangles) plus a quad, a pentagon, one triangle strip
of 6 points, one vertex and one line, with a point scalar `height` and a
3-component point array `normal3` that chisel skips.
"""

import json
import math
import os
import sys

import numpy as np
import vtk
from vtk.util import numpy_support

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "tests", "data", "vtk")

DIMS = (5, 4, 3)
SPACING = (0.5, 0.75, 2.0)
ORIGIN = (-3.0, 4.0, 5.0)
# Row-major 3x3; physical = origin + D . (index * spacing), so the columns
# are the directions of the index axes.
ROT_Z90 = (0, -1, 0, 1, 0, 0, 0, 0, 1)
REFLECT = (0, 1, 0, 1, 0, 0, 0, 0, 1)


def image(kind="short", direction=ROT_Z90, extra=False):
    img = vtk.vtkImageData()
    img.SetDimensions(*DIMS)
    img.SetSpacing(*SPACING)
    img.SetOrigin(*ORIGIN)
    img.SetDirectionMatrix(*direction)
    nx, ny, nz = DIMS
    vals = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                if kind == "short":
                    vals.append(i + 10 * j + 100 * k - 50)
                else:
                    vals.append(math.sqrt(i + 1) * 1.5 + j * 0.1 - k / 3.0)
    dtype = np.int16 if kind == "short" else np.float64
    arr = numpy_support.numpy_to_vtk(np.array(vals, dtype=dtype), deep=True)
    arr.SetName("density")
    img.GetPointData().AddArray(arr)
    img.GetPointData().SetActiveScalars("density")
    if extra:
        second = numpy_support.numpy_to_vtk(np.array(vals, dtype=np.float32) * 2.0, deep=True)
        second.SetName("doubled")
        img.GetPointData().AddArray(second)
        vec = numpy_support.numpy_to_vtk(
            np.array([[v, -v, 0.5] for v in vals], dtype=np.float32), deep=True
        )
        vec.SetName("gradient")
        img.GetPointData().AddArray(vec)
        cell = numpy_support.numpy_to_vtk(np.arange(24, dtype=np.int32), deep=True)
        cell.SetName("cellid")
        img.GetCellData().AddArray(cell)
    return img


def add_cell(cells, ids):
    cells.InsertNextCell(len(ids))
    for i in ids:
        cells.InsertCellPoint(i)


def poly(storage32=False):
    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(8)
    sphere.SetPhiResolution(6)
    sphere.SetRadius(2.0)
    sphere.SetCenter(0.5, -1.0, 3.0)
    sphere.Update()
    s = sphere.GetOutput()
    pts = vtk.vtkPoints()
    pts.SetDataTypeToFloat()
    for i in range(s.GetNumberOfPoints()):
        pts.InsertNextPoint(s.GetPoint(i))
    base = s.GetNumberOfPoints()
    extra = [(5, 0, 0), (6, 0, 0), (6, 1, 0), (5, 1, 0),  # quad
             (8, 0, 0), (9, 0, 0), (9.5, 1, 0), (8.5, 2, 0), (7.5, 1, 0),  # pentagon
             (0, 5, 0), (0, 6, 0), (1, 5, 0), (1, 6, 0), (2, 5, 0), (2, 6, 0)]  # strip
    for p in extra:
        pts.InsertNextPoint(p)
    polys = vtk.vtkCellArray()
    it = s.GetPolys().NewIterator()
    it.GoToFirstCell()
    while not it.IsDoneWithTraversal():
        ids = it.GetCurrentCell()
        add_cell(polys, [ids.GetId(i) for i in range(ids.GetNumberOfIds())])
        it.GoToNextCell()
    add_cell(polys, [base + 0, base + 1, base + 2, base + 3])
    add_cell(polys, [base + 4, base + 5, base + 6, base + 7, base + 8])
    strips = vtk.vtkCellArray()
    add_cell(strips, [base + 9 + i for i in range(6)])
    verts = vtk.vtkCellArray()
    add_cell(verts, [0])
    lines = vtk.vtkCellArray()
    add_cell(lines, [0, 1, 2])
    if storage32:  # VTK < 9 wrote Int32 connectivity; 9.x does for 32-bit storage
        for cells in (polys, strips, verts, lines):
            cells.ConvertTo32BitStorage()
    out = vtk.vtkPolyData()
    out.SetPoints(pts)
    out.SetPolys(polys)
    out.SetStrips(strips)
    out.SetVerts(verts)
    out.SetLines(lines)
    n = pts.GetNumberOfPoints()
    h = numpy_support.numpy_to_vtk(
        np.array([pts.GetPoint(i)[2] * 1.25 + i for i in range(n)], dtype=np.float32), deep=True
    )
    h.SetName("height")
    out.GetPointData().AddArray(h)
    out.GetPointData().SetActiveScalars("height")
    nrm = numpy_support.numpy_to_vtk(np.array([pts.GetPoint(i) for i in range(n)]), deep=True)
    nrm.SetName("normal3")
    out.GetPointData().AddArray(nrm)
    return out


def configure(w, mode):
    """mode: ascii | binary | appended-raw | appended-b64, with options."""
    data, *opts = mode.split("+")
    if data == "ascii":
        w.SetDataModeToAscii()
    elif data == "binary":
        w.SetDataModeToBinary()
    elif data == "appended-raw":
        w.SetDataModeToAppended()
        w.EncodeAppendedDataOff()
    elif data == "appended-b64":
        w.SetDataModeToAppended()
        w.EncodeAppendedDataOn()
    w.SetCompressorTypeToNone()
    w.SetHeaderTypeToUInt64()
    w.SetByteOrderToLittleEndian()
    for o in opts:
        if o == "zlib":
            w.SetCompressorTypeToZLib()
        elif o == "zlib64":  # several blocks, the last one partial
            w.SetCompressorTypeToZLib()
            w.SetBlockSize(64)
        elif o == "u32":
            w.SetHeaderTypeToUInt32()
        elif o == "be":
            w.SetByteOrderToBigEndian()
        elif o == "id32":
            w.SetIdTypeToInt32()
        elif o == "pieces2":
            w.SetNumberOfPieces(2)
        else:
            raise ValueError(o)


MODES = [
    ("ascii", "ascii"),
    ("binary", "binary"),
    ("binary_u32", "binary+u32"),
    ("binary_zlib", "binary+zlib"),
    ("binary_zlib_u32", "binary+zlib+u32"),
    ("binary_zlib_blocks", "binary+zlib64"),
    ("appended_raw", "appended-raw"),
    ("appended_raw_u32", "appended-raw+u32"),
    ("appended_raw_zlib", "appended-raw+zlib"),
    ("appended_raw_zlib_blocks_u32", "appended-raw+zlib64+u32"),
    ("appended_b64", "appended-b64"),
    ("appended_b64_zlib", "appended-b64+zlib"),
    ("appended_raw_be", "appended-raw+be"),
    ("binary_zlib_be_u32", "binary+zlib+be+u32"),
]


def summary_image(path):
    r = vtk.vtkXMLImageDataReader() if path.endswith(".vti") else vtk.vtkStructuredPointsReader()
    r.SetFileName(path)
    r.Update()
    img = r.GetOutput()
    pd = img.GetPointData()
    s = pd.GetScalars()
    arrays = [pd.GetArrayName(i) for i in range(pd.GetNumberOfArrays())]
    vals = numpy_support.vtk_to_numpy(s).astype(np.float64).ravel()
    m = img.GetDirectionMatrix()
    return {
        "kind": "image",
        "dims": list(img.GetDimensions()),
        "spacing": list(img.GetSpacing()),
        "origin": list(img.GetOrigin()),
        "direction": [m.GetElement(i, j) for i in range(3) for j in range(3)],
        "scalars": s.GetName(),
        "type": s.GetDataTypeAsString(),
        "components": s.GetNumberOfComponents(),
        "range": list(s.GetRange()),
        "sum": float(vals.sum()),
        "values": [float(v) for v in vals],
        "point_arrays": arrays,
        "cell_arrays": [
            img.GetCellData().GetArrayName(i) for i in range(img.GetCellData().GetNumberOfArrays())
        ],
        "bounds": list(img.GetBounds()),
    }


def summary_poly(path):
    r = vtk.vtkXMLPolyDataReader()
    r.SetFileName(path)
    r.Update()
    pd = r.GetOutput()
    tri = vtk.vtkTriangleFilter()
    tri.SetInputData(pd)
    tri.PassVertsOff()
    tri.PassLinesOff()
    tri.Update()
    pts = numpy_support.vtk_to_numpy(pd.GetPoints().GetData()).astype(np.float64)
    return {
        "kind": "poly",
        "points": pd.GetNumberOfPoints(),
        "polys": pd.GetNumberOfPolys(),
        "strips": pd.GetNumberOfStrips(),
        "verts": pd.GetNumberOfVerts(),
        "lines": pd.GetNumberOfLines(),
        "triangles": tri.GetOutput().GetNumberOfPolys(),
        "bounds": list(pd.GetBounds()),
        "coordinate_sum": float(pts.sum()),
        "scalars": {
            a.GetName(): {
                "range": list(a.GetRange()),
                "sum": float(numpy_support.vtk_to_numpy(a).astype(np.float64).sum()),
            }
            for a in (pd.GetPointData().GetArray(i) for i in range(pd.GetPointData().GetNumberOfArrays()))
            if a.GetNumberOfComponents() == 1
        },
        "point_arrays": [
            pd.GetPointData().GetArrayName(i) for i in range(pd.GetPointData().GetNumberOfArrays())
        ],
    }


def write_xml(writer, data, name, mode):
    path = os.path.join(OUT, name)
    writer.SetInputData(data)
    configure(writer, mode)
    writer.SetFileName(path)
    if not writer.Write():
        raise RuntimeError(f"VTK failed to write {path}")
    return path


def check_chisel(folder):
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name)
        if name.endswith(".vtp"):
            print(name, json.dumps(summary_poly(path)))
        elif name.endswith(".vti") or name.endswith(".vtk"):
            print(name, json.dumps({k: v for k, v in summary_image(path).items() if k != "values"}))


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "--check-chisel":
        check_chisel(sys.argv[2])
        return
    os.makedirs(OUT, exist_ok=True)
    expected = {"vtk_version": vtk.vtkVersion.GetVTKVersion(), "files": {}}
    files = expected["files"]

    for tag, mode in MODES:
        p = write_xml(vtk.vtkXMLImageDataWriter(), image(), f"image_{tag}.vti", mode)
        files[os.path.basename(p)] = summary_image(p)
        p = write_xml(vtk.vtkXMLPolyDataWriter(), poly(), f"poly_{tag}.vtp", mode)
        files[os.path.basename(p)] = summary_poly(p)
    for name, data, mode in [
        ("image_reflect.vti", image(direction=REFLECT), "appended-raw"),
        ("image_f64_extra.vti", image("double", extra=True), "binary+zlib"),
        ("image_pieces.vti", image(), "appended-raw+pieces2"),
    ]:
        p = write_xml(vtk.vtkXMLImageDataWriter(), data, name, mode)
        files[name] = summary_image(p)
    for name, mode in [("poly_id32.vtp", "appended-raw+id32"), ("poly_id32_ascii.vtp", "ascii+id32")]:
        p = write_xml(vtk.vtkXMLPolyDataWriter(), poly(storage32=True), name, mode)
        files[name] = summary_poly(p)
    # Two pieces of one image: a raw file read by vtkImageReader2, which
    # streams, so the writer asks for (and writes) two sub-extents.
    raw = os.path.join(OUT, "image_pieces.raw")
    with open(raw, "wb") as f:
        f.write(numpy_support.vtk_to_numpy(image().GetPointData().GetArray(0)).astype("<i2").tobytes())
    reader = vtk.vtkImageReader2()
    reader.SetFileName(raw)
    reader.SetDataScalarTypeToShort()
    reader.SetDataByteOrderToLittleEndian()
    reader.SetFileDimensionality(3)
    reader.SetDataExtent(0, DIMS[0] - 1, 0, DIMS[1] - 1, 0, DIMS[2] - 1)
    reader.SetDataSpacing(*SPACING)
    reader.SetDataOrigin(*ORIGIN)
    reader.SetDataDirection(ROT_Z90)
    reader.GetOutput()  # pipeline only
    w = vtk.vtkXMLImageDataWriter()
    w.SetInputConnection(reader.GetOutputPort())
    configure(w, "appended-raw+pieces2")
    w.SetFileName(os.path.join(OUT, "image_pieces_streamed.vti"))
    w.Write()
    os.remove(raw)
    files["image_pieces_streamed.vti"] = summary_image(os.path.join(OUT, "image_pieces_streamed.vti"))
    # Two pieces: a sphere source split by the streaming pipeline, with a
    # one-component point array from vtkElevationFilter.
    sphere = vtk.vtkSphereSource()
    sphere.SetThetaResolution(8)
    sphere.SetPhiResolution(6)
    elev = vtk.vtkElevationFilter()
    elev.SetInputConnection(sphere.GetOutputPort())
    w = vtk.vtkXMLPolyDataWriter()
    w.SetInputConnection(elev.GetOutputPort())
    configure(w, "appended-raw+pieces2")
    w.SetFileName(os.path.join(OUT, "poly_pieces.vtp"))
    w.Write()
    files["poly_pieces.vtp"] = summary_poly(os.path.join(OUT, "poly_pieces.vtp"))

    # Legacy STRUCTURED_POINTS (no Direction in the legacy format).
    for name, data, binary in [
        ("sp_ascii.vtk", image(direction=(1, 0, 0, 0, 1, 0, 0, 0, 1)), False),
        ("sp_binary.vtk", image(direction=(1, 0, 0, 0, 1, 0, 0, 0, 1)), True),
        ("sp_f64_extra_binary.vtk", image("double", (1, 0, 0, 0, 1, 0, 0, 0, 1), True), True),
        ("sp_f64_extra_ascii.vtk", image("double", (1, 0, 0, 0, 1, 0, 0, 0, 1), True), False),
    ]:
        w = vtk.vtkStructuredPointsWriter()
        w.SetInputData(data)
        w.SetFileName(os.path.join(OUT, name))
        if binary:
            w.SetFileTypeToBinary()
        else:
            w.SetFileTypeToASCII()
        w.Write()
        files[name] = summary_image(os.path.join(OUT, name))

    with open(os.path.join(OUT, "expected.json"), "w") as f:
        json.dump(expected, f, indent=1, sort_keys=True)
        f.write("\n")
    total = sum(os.path.getsize(os.path.join(OUT, n)) for n in os.listdir(OUT))
    print(f"wrote {len(files)} files + expected.json to {OUT} ({total} bytes)")


if __name__ == "__main__":
    main()
