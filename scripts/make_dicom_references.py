#!/usr/bin/env python3
"""Writes the DICOM test series in tests/data/dicom with pydicom (a writer
independent of the dicom-rs crates chisel reads with), and expected.json
with what every series holds, computed here from the arrays written.

Run: python3 -m venv /tmp/venv && /tmp/venv/bin/pip install pydicom numpy
     /tmp/venv/bin/python scripts/make_dicom_references.py

Every series has known content: stored value s(i, j, k) = 3·i + 20·j + 200·k
+ 7 at column i, row j, slice k (k counting along the slice normal), and
modality value s·slope + intercept.
"""
import json
import os
import shutil

import numpy as np
import pydicom
from pydicom.dataset import Dataset, FileMetaDataset
import pydicom.encaps
from pydicom.uid import (ExplicitVRLittleEndian, ImplicitVRLittleEndian,
                         RLELossless, generate_uid, CTImageStorage,
                         EnhancedCTImageStorage, JPEG2000Lossless,
                         DeflatedExplicitVRLittleEndian)

OUT = os.path.join(os.path.dirname(__file__), "..", "tests", "data", "dicom")
COLS, ROWS, SLICES = 6, 5, 4
ROW_SPACING, COL_SPACING, STEP = 0.7, 0.6, 2.5
EXPECTED = {}

# A rotation: row direction, column direction (orthonormal).
c, s = np.cos(0.3), np.sin(0.3)
ROW = np.array([c, s, 0.0])
COL = np.array([0.0, 0.0, -1.0])
NORMAL = np.cross(ROW, COL)
ORIGIN = np.array([-12.5, 30.25, 101.0])


def stored(k):
    j, i = np.mgrid[0:ROWS, 0:COLS]
    return (3 * i + 20 * j + 200 * k + 7).astype(np.uint16)


def slice_dataset(series_uid, k, position, slope=1.0, intercept=-1024.0,
                  orientation=None, description="chisel test CT"):
    ds = Dataset()
    ds.SOPClassUID = CTImageStorage
    ds.SOPInstanceUID = generate_uid(entropy_srcs=[series_uid, str(k), str(position)])
    ds.Modality = "CT"
    ds.SeriesInstanceUID = series_uid
    ds.StudyInstanceUID = "1.2.826.0.1.3680043.8.498.1"
    ds.SeriesDescription = description
    # Instance numbers run against the slice order on purpose.
    ds.InstanceNumber = 100 - k
    ds.ImagePositionPatient = [float(x) for x in position]
    o = orientation if orientation is not None else list(ROW) + list(COL)
    ds.ImageOrientationPatient = [float(x) for x in o]
    ds.PixelSpacing = [ROW_SPACING, COL_SPACING]
    ds.SliceThickness = STEP
    ds.Rows, ds.Columns = ROWS, COLS
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit = 16, 16, 15
    ds.PixelRepresentation = 0
    ds.RescaleSlope = slope
    ds.RescaleIntercept = intercept
    ds.PixelData = stored(k).tobytes()
    return ds


def save(ds, path, syntax=ExplicitVRLittleEndian, meta=True):
    if meta:
        fm = FileMetaDataset()
        fm.MediaStorageSOPClassUID = ds.SOPClassUID
        fm.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
        fm.TransferSyntaxUID = syntax
        ds.file_meta = fm
        if syntax == RLELossless:
            ds.file_meta.TransferSyntaxUID = ExplicitVRLittleEndian
            ds.compress(RLELossless, encoding_plugin="pydicom")
        ds.save_as(path, enforce_file_format=True)
    else:
        # Preamble + DICM, no file-meta group, implicit VR little endian.
        pydicom.dcmwrite(path, ds, implicit_vr=True, little_endian=True,
                         enforce_file_format=False, write_like_original=True)
        with open(path, "rb") as f:
            body = f.read()
        with open(path, "wb") as f:
            f.write(b"\0" * 128 + b"DICM" + body)


def expect(name, positions_sorted, slope, intercept, dtype):
    values = np.stack([stored(k).astype(np.float64) * slope + intercept
                       for k in range(len(positions_sorted))])
    EXPECTED[name] = {
        "dims": [COLS, ROWS, len(positions_sorted)],
        "spacing": [COL_SPACING, ROW_SPACING, STEP if len(positions_sorted) > 1 else STEP],
        "origin": [float(x) for x in positions_sorted[0]],
        "axes": [list(map(float, ROW)), list(map(float, COL)), list(map(float, NORMAL))],
        "space": "LPS",
        "scalar_type": dtype,
        "min": float(values.min()),
        "max": float(values.max()),
        "sum": float(values.sum()),
        # Sample (i, j, k) = (5, 4, 3): the last of each axis.
        "last": float(values[-1, -1, -1]),
    }


def series(name, syntax=ExplicitVRLittleEndian, meta=True, slope=1.0,
           intercept=-1024.0, dtype="i16", shifts=None, steps=None):
    d = os.path.join(OUT, name)
    os.makedirs(d)
    uid = generate_uid(entropy_srcs=[name])
    positions = []
    depth = 0.0
    for k in range(SLICES):
        shift = np.zeros(3) if shifts is None else shifts[k]
        positions.append(ORIGIN + depth * NORMAL + shift)
        depth += STEP if steps is None else steps[k]
    # File names in an order that is neither slice nor instance order.
    for n, k in enumerate([2, 0, 3, 1]):
        ds = slice_dataset(uid, k, positions[k], slope, intercept)
        save(ds, os.path.join(d, f"IM{n:04d}"), syntax, meta)
    return positions


def main():
    shutil.rmtree(OUT, ignore_errors=True)
    os.makedirs(OUT)
    p = series("ct_explicit")
    expect("ct_explicit", p, 1.0, -1024.0, "i16")
    p = series("ct_implicit", ImplicitVRLittleEndian)
    expect("ct_implicit", p, 1.0, -1024.0, "i16")
    p = series("ct_rle", RLELossless)
    expect("ct_rle", p, 1.0, -1024.0, "i16")
    p = series("ct_no_meta", meta=False)
    expect("ct_no_meta", p, 1.0, -1024.0, "i16")
    p = series("ct_fractional_rescale", slope=0.5, intercept=-10.25)
    expect("ct_fractional_rescale", p, 0.5, -10.25, "f32")
    # Refused: gantry tilt (each slice shifted across the normal) and a
    # missing slice (non-uniform spacing).
    series("ct_tilt", shifts=[ROW * 0.8 * k for k in range(SLICES)])
    series("ct_gap", steps=[STEP, 2 * STEP, STEP, STEP])
    # Two series in one directory.
    d = os.path.join(OUT, "two_series")
    os.makedirs(d)
    for s_name in ("a", "b"):
        uid = "1.2.826.0.1.3680043.8.498.77." + ("1" if s_name == "a" else "2")
        for k in range(2):
            ds = slice_dataset(uid, k, ORIGIN + k * STEP * NORMAL,
                               description=f"series {s_name}")
            save(ds, os.path.join(d, f"{s_name}{k}.dcm"))
    EXPECTED["two_series"] = {"uids": ["1.2.826.0.1.3680043.8.498.77.1",
                                        "1.2.826.0.1.3680043.8.498.77.2"]}
    # One enhanced multi-frame file: per-frame positions, shared
    # orientation, pixel measures and rescale, frames stored in reverse.
    ds = Dataset()
    ds.SOPClassUID = EnhancedCTImageStorage
    ds.SOPInstanceUID = generate_uid(entropy_srcs=["multiframe"])
    ds.Modality = "CT"
    ds.SeriesInstanceUID = generate_uid(entropy_srcs=["multiframe series"])
    ds.Rows, ds.Columns = ROWS, COLS
    ds.NumberOfFrames = SLICES
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = "MONOCHROME2"
    ds.BitsAllocated, ds.BitsStored, ds.HighBit = 16, 16, 15
    ds.PixelRepresentation = 0
    shared = Dataset()
    po = Dataset()
    po.ImageOrientationPatient = [float(x) for x in list(ROW) + list(COL)]
    shared.PlaneOrientationSequence = [po]
    pm = Dataset()
    pm.PixelSpacing = [ROW_SPACING, COL_SPACING]
    pm.SliceThickness = STEP
    shared.PixelMeasuresSequence = [pm]
    pv = Dataset()
    pv.RescaleSlope = 1.0
    pv.RescaleIntercept = -1024.0
    pv.RescaleType = "HU"
    shared.PixelValueTransformationSequence = [pv]
    ds.SharedFunctionalGroupsSequence = [shared]
    order = list(reversed(range(SLICES)))
    frames = []
    positions = [ORIGIN + k * STEP * NORMAL for k in range(SLICES)]
    for k in order:
        f = Dataset()
        pp = Dataset()
        pp.ImagePositionPatient = [float(x) for x in positions[k]]
        f.PlanePositionSequence = [pp]
        frames.append(f)
    ds.PerFrameFunctionalGroupsSequence = frames
    ds.PixelData = b"".join(stored(k).tobytes() for k in order)
    save(ds, os.path.join(OUT, "multiframe.dcm"))
    expect("multiframe.dcm", positions, 1.0, -1024.0, "i16")
    # Transfer syntaxes this build refuses by name: JPEG 2000 (a native
    # codec left out; the fragment is not decoded) and deflated data sets.
    ds = slice_dataset(generate_uid(entropy_srcs=["j2k"]), 0, ORIGIN)
    ds.PixelData = pydicom.encaps.encapsulate([b"\xff\x4f\xff\x51" + b"\0" * 60])
    ds["PixelData"].VR = "OB"
    fm = FileMetaDataset()
    fm.MediaStorageSOPClassUID = ds.SOPClassUID
    fm.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
    fm.TransferSyntaxUID = JPEG2000Lossless
    ds.file_meta = fm
    ds.save_as(os.path.join(OUT, "jpeg2000.dcm"), enforce_file_format=True)
    ds = slice_dataset(generate_uid(entropy_srcs=["deflate"]), 0, ORIGIN)
    save(ds, os.path.join(OUT, "deflated.dcm"), DeflatedExplicitVRLittleEndian)
    with open(os.path.join(OUT, "expected.json"), "w") as f:
        json.dump(EXPECTED, f, indent=1, sort_keys=True)
        f.write("\n")


if __name__ == "__main__":
    main()
