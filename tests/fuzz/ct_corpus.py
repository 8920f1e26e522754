#!/usr/bin/env python3
"""Writes the seed corpora of the CT reader fuzz targets (tests/fuzz/ct_*_fuzz.cpp):
fixtures/fuzz/ct_dicom, ct_nrrd, ct_metaimage. Small valid files of each supported variant.
DICOM series are several files joined by SEPARATOR (the fuzz target splits them again); the
detached NRRD / MetaImage seeds name a data file, which the target serves from the input itself.
Run from anywhere: python3 tests/fuzz/ct_corpus.py"""
import os
import struct
import zlib

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "fixtures", "fuzz")
SEPARATOR = b"SPLINTCORE-NEXT-FILE"  # must match tests/fuzz/ct_dicom_fuzz.cpp


def write(folder, name, data):
    path = os.path.join(ROOT, folder, name)
    with open(path, "wb") as f:
        f.write(data)


def le16(values, signed=True):
    return b"".join(struct.pack("<h" if signed else "<H", v) for v in values)


# ---- NRRD
nrrd = (b"NRRD0004\n# seed\ntype: short\ndimension: 3\nspace: left-posterior-superior\n"
        b"sizes: 2 3 4\nspace directions: (0,0.5,0) (0.75,0,0) (0,0,-2.5)\n"
        b"kinds: domain domain domain\nendian: little\nencoding: raw\n"
        b"space origin: (-10,20.5,3)\nkey:=value\n\n")
write("ct_nrrd", "attached_short.nrrd", nrrd + le16(range(-1000, -976)))
write("ct_nrrd", "big_ushort.nrrd",
      b"NRRD0005\ntype: uint16\ndimension: 3\nsizes: 2 2 2\nspacings: 0.5 0.5 1\n"
      b"endian: big\nencoding: raw\n\n" + b"".join(struct.pack(">H", v) for v in
                                                   [0, 1, 65535, 40000, 32767, 32768, 7, 1000]))
write("ct_nrrd", "float.nrrd",
      b"NRRD0004\ntype: float\ndimension: 3\nsizes: 3 1 2\nendian: little\nencoding: raw\n\n" +
      struct.pack("<6f", 2.5, -2.5, 1e6, -1e9, 0.4, 17.0))
write("ct_nrrd", "uchar.nrrd",
      b"NRRD0001\ntype: uchar\ndimension: 3\nsizes: 8 8 2\nencoding: raw\n\n" +
      bytes((i * 37) % 256 for i in range(128)))
write("ct_nrrd", "detached.nhdr",
      b"NRRD0004\ntype: int16\ndimension: 3\nsizes: 2 2 2\nendian: little\nencoding: raw\n"
      b"data file: data.raw\nline skip: 1\nbyte skip: -1\n\n" + le16([1, -2, 3, -4, 5, -6, 7, -8]))


def gzip_bytes(data):
    """gzip member with no name and no time (the same bytes everywhere)."""
    c = zlib.compressobj(6, zlib.DEFLATED, 31)
    return c.compress(data) + c.flush()


write("ct_nrrd", "gzip_short.nrrd", nrrd.replace(b"encoding: raw", b"encoding: gzip") +
      gzip_bytes(le16(range(-1000, -976))))

# ---- MetaImage
mha = (b"ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\n"
       b"CompressedData = False\nTransformMatrix = 0 1 0 1 0 0 0 0 -1\nOffset = 1.5 -2 100\n"
       b"AnatomicalOrientation = RAI\nElementSpacing = 0.3 0.4 1.25\nDimSize = 3 2 2\n"
       b"ElementType = MET_SHORT\nElementDataFile = LOCAL\n")
write("ct_metaimage", "inline_short.mha", mha + le16(range(-2048, -2036)))
write("ct_metaimage", "msb_float.mha",
      mha.replace(b"MSB = False", b"MSB = True").replace(b"MET_SHORT", b"MET_FLOAT") +
      struct.pack(">12f", *[0.5 * i - 3 for i in range(12)]))
write("ct_metaimage", "uchar.mha",
      mha.replace(b"MET_SHORT", b"MET_UCHAR") + bytes(range(12)))
write("ct_metaimage", "detached.mhd",
      mha.replace(b"LOCAL", b"data.raw").replace(b"NDims = 3\n", b"NDims = 3\nHeaderSize = -1\n")
      + le16(range(12)))


# ---- DICOM
class Dicom:
    def __init__(self, implicit):
        self.b = bytearray(128) + b"DICM"
        self.implicit = implicit

    def element(self, group, elem, vr, data, meta=False):
        if len(data) % 2:
            data += b"\0" if vr == "UI" else b" "
        self.b += struct.pack("<HH", group, elem)
        if self.implicit and not meta:
            self.b += struct.pack("<I", len(data))
        elif vr in ("OB", "OW", "SQ", "UN", "UT"):
            self.b += vr.encode() + b"\0\0" + struct.pack("<I", len(data))
        else:
            self.b += vr.encode() + struct.pack("<H", len(data))
        self.b += data

    def raw(self, group, elem, length):
        self.b += struct.pack("<HHI", group, elem, length)


def dicom(implicit=False, z=0.0, bits=16, signed=True, rows=4, cols=5, sequences=False, k=0):
    d = Dicom(implicit)
    syntax = b"1.2.840.10008.1.2" if implicit else b"1.2.840.10008.1.2.1"
    d.element(2, 0x0001, "OB", b"\0\1", meta=True)
    d.element(2, 0x0002, "UI", b"1.2.840.10008.5.1.4.1.1.2", meta=True)
    d.element(2, 0x0010, "UI", syntax, meta=True)
    d.element(8, 0x0060, "CS", b"CT")
    if sequences:
        if implicit:
            d.raw(8, 0x1140, 0xFFFFFFFF)
        else:
            d.b += struct.pack("<HH", 8, 0x1140) + b"SQ\0\0" + struct.pack("<I", 0xFFFFFFFF)
        d.raw(0xFFFE, 0xE000, 0xFFFFFFFF)
        d.element(0x28, 0x10, "US", struct.pack("<H", 999))
        d.raw(0xFFFE, 0xE00D, 0)
        d.raw(0xFFFE, 0xE000, 4)
        d.b += b"\xef\xbe\xad\xde"
        d.raw(0xFFFE, 0xE0DD, 0)
    d.element(0x18, 0x0050, "DS", b"1.5")
    d.element(0x20, 0x0013, "IS", str(k + 1).encode())
    d.element(0x20, 0x0032, "DS", ("10\\-20\\%g" % z).encode())
    d.element(0x20, 0x0037, "DS", b"1\\0\\0\\0\\1\\0")
    d.element(0x28, 0x0002, "US", struct.pack("<H", 1))
    d.element(0x28, 0x0004, "CS", b"MONOCHROME2")
    d.element(0x28, 0x0010, "US", struct.pack("<H", rows))
    d.element(0x28, 0x0011, "US", struct.pack("<H", cols))
    d.element(0x28, 0x0030, "DS", b"0.5\\0.25")
    d.element(0x28, 0x0100, "US", struct.pack("<H", bits))
    d.element(0x28, 0x0101, "US", struct.pack("<H", bits if bits == 8 else 12))
    d.element(0x28, 0x0102, "US", struct.pack("<H", (bits if bits == 8 else 12) - 1))
    d.element(0x28, 0x0103, "US", struct.pack("<H", 1 if signed else 0))
    d.element(0x28, 0x1052, "DS", b"-1024")
    d.element(0x28, 0x1053, "DS", b"1.5")
    n = rows * cols
    if bits == 8:
        pixels = bytes((i * 13 + k) % 256 for i in range(n))
    else:
        pixels = le16([(i * 97 + k * 11) % 2048 - 1024 for i in range(n)])
    d.element(0x7FE0, 0x0010, "OB" if bits == 8 else "OW", pixels)
    return bytes(d.b)


def deflated(file):
    """The same file as Deflated Explicit VR Little Endian: the data set after the file meta
    as one raw deflate stream (PS3.5 A.5)."""
    at = 132
    while struct.unpack_from("<H", file, at)[0] == 2:
        vr = file[at + 4:at + 6]
        if vr in (b"OB", b"OW", b"SQ", b"UN", b"UT"):
            at += 12 + struct.unpack_from("<I", file, at + 8)[0]
        else:
            at += 8 + struct.unpack_from("<H", file, at + 6)[0]
    c = zlib.compressobj(6, zlib.DEFLATED, -15)
    head = file[:at].replace(b"1.2.840.10008.1.2.1\0", b"1.2.840.10008.1.2.1.99")
    head = head.replace(b"UI\x14\x00" + b"1.2.840.10008.1.2.1.99",
                        b"UI\x16\x00" + b"1.2.840.10008.1.2.1.99")
    return head + c.compress(file[at:]) + c.flush()


write("ct_dicom", "explicit_one.dcm", dicom(sequences=True))
write("ct_dicom", "implicit_one.dcm", dicom(implicit=True, sequences=True))
write("ct_dicom", "uint8_one.dcm", dicom(bits=8, signed=False, rows=3, cols=3))
write("ct_dicom", "series3.bin", SEPARATOR.join(dicom(z=z, k=k) for k, z in
                                                  enumerate([2.0, -1.0, 0.5])))
write("ct_dicom", "deflated_one.dcm", deflated(dicom(sequences=True)))
write("ct_dicom", "series2_deflated.bin",
      SEPARATOR.join(deflated(dicom(z=z, k=k, rows=3, cols=2)) for k, z in
                     enumerate([0.0, 1.5])))
write("ct_dicom", "series2_implicit.bin",
      SEPARATOR.join(dicom(implicit=True, z=z, k=k, rows=2, cols=2) for k, z in
                     enumerate([0.0, 1.25])))
