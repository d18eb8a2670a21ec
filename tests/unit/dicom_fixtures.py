"""DICOM slices written with pydicom (Debian's python3-pydicom) for the DICOM series tests: an
independent writer, so that the reader's reading of PixelSpacing, positions, rescale and
photometric interpretation is checked against the standard, not against itself."""
import os
import random

import numpy as np
from pydicom.dataset import FileDataset, FileMetaDataset
from pydicom.uid import CTImageStorage, ExplicitVRLittleEndian, RLELossless, generate_uid

PATIENT_NAME = "DOE^JANE^Q"
PATIENT_ID = "PID-77310452"


def write_slice(path, pixels, *, series_uid, description="", modality="CT", position=(0, 0, 0),
                orientation=(1, 0, 0, 0, 1, 0), spacing=(1.0, 1.0), slope=1, intercept=0, bits_stored=None,
                photometric="MONOCHROME2", instance=1, rle=False, extra=None):
    """One slice: pixels[row, column], uint8/uint16/int16."""
    meta = FileMetaDataset()
    meta.MediaStorageSOPClassUID = CTImageStorage
    meta.MediaStorageSOPInstanceUID = generate_uid()
    meta.TransferSyntaxUID = ExplicitVRLittleEndian
    ds = FileDataset(path, {}, file_meta=meta, preamble=b"\0" * 128)
    ds.is_little_endian, ds.is_implicit_VR = True, False
    ds.SOPClassUID, ds.SOPInstanceUID = CTImageStorage, meta.MediaStorageSOPInstanceUID
    ds.PatientName, ds.PatientID = PATIENT_NAME, PATIENT_ID
    ds.StudyInstanceUID = "1.2.826.0.1.3680043.8.498.1"
    ds.SeriesInstanceUID = series_uid
    ds.SeriesDescription = description
    ds.Modality = modality
    ds.InstanceNumber = instance
    ds.ImagePositionPatient = [float(v) for v in position]
    ds.ImageOrientationPatient = [float(v) for v in orientation]
    ds.PixelSpacing = [float(v) for v in spacing]
    ds.SliceThickness = 1.0
    ds.Rows, ds.Columns = pixels.shape
    ds.SamplesPerPixel = 1
    ds.PhotometricInterpretation = photometric
    bits = pixels.dtype.itemsize * 8
    ds.BitsAllocated = bits
    ds.BitsStored = bits_stored or bits
    ds.HighBit = ds.BitsStored - 1
    ds.PixelRepresentation = 1 if pixels.dtype.kind == "i" else 0
    ds.RescaleSlope, ds.RescaleIntercept = slope, intercept
    for key, value in (extra or {}).items():  # a header that says otherwise than the pixels (refusals)
        setattr(ds, key, value)
    ds.PixelData = np.ascontiguousarray(pixels).astype(pixels.dtype.newbyteorder("<")).tobytes()
    if rle:
        ds.compress(RLELossless)
    ds.save_as(path, write_like_original=False)


def write_series(folder, stack, *, positions, seed=1, **kw):
    """stack[k] at positions[k], into files with shuffled random names and instance numbers that
    run against the positions: order must come from the positions alone."""
    os.makedirs(folder, exist_ok=True)
    rng = random.Random(seed)
    names = [f"IM{rng.randrange(16**8):08X}" for _ in stack]
    order = list(range(len(stack)))
    rng.shuffle(order)
    for k in order:
        write_slice(os.path.join(folder, names[k]), stack[k], position=positions[k], instance=len(stack) - k, **kw)
    return names
