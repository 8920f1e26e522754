#!/usr/bin/env python3
"""Writes the seed corpora of the CT reader fuzz targets (tests/fuzz/ct_*_fuzz.cpp):
fixtures/fuzz/ct_dicom, ct_nrrd, ct_metaimage. Small valid files of each supported variant.
DICOM series are several files joined by SEPARATOR (the fuzz target splits them again); the
detached NRRD / MetaImage seeds name a data file, which the target serves from the input itself.
Run from anywhere: python3 tests/fuzz/ct_corpus.py"""
import os
import struct
import sys
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


# ---- DICOM encapsulated pixel data (PS3.5 A.4), RLE (Annex G), JPEG lossless (T.81 H),
# explicit VR big endian. Small encoders of our own: the fixtures/ct files are made by gdcm and
# dcmtk; these seeds only need to be valid and small.
def packbits_rows(plane, cols):
    """PackBits (PS3.5 G.3.1), each row on its own: repeats of 3 or more, literals otherwise."""
    out = bytearray()
    for r in range(0, len(plane), cols):
        row, i = plane[r:r + cols], 0
        while i < len(row):
            j = i
            while j < len(row) and row[j] == row[i] and j - i < 128:
                j += 1
            if j - i >= 3:
                out += bytes([257 - (j - i), row[i]])
                i = j
                continue
            j = i
            while j < len(row) and j - i < 128 and not (
                    j + 2 < len(row) and row[j] == row[j + 1] == row[j + 2]):
                j += 1
            out += bytes([j - i - 1]) + bytes(row[i:j])
            i = j
    if len(out) % 2:
        out += b"\x80"
    return bytes(out)


def rle_frame(pixels, bits, cols):
    n = len(pixels) // (bits // 8)
    if bits == 8:
        planes = [pixels]
    else:
        planes = [pixels[1::2], pixels[0::2]]  # most significant byte first
    segments = [packbits_rows(p, cols) for p in planes]
    offsets, at = [], 64
    for s in segments:
        offsets.append(at)
        at += len(s)
    header = struct.pack("<16I", len(segments), *(offsets + [0] * (15 - len(offsets))))
    assert n > 0
    return header + b"".join(segments)


def jpeg_lossless(samples, rows, cols, precision, predictor, restart_lines=0):
    """T.81 H: every difference category 0..16 a 5-bit code (a flat table), predictor p."""
    def at(x, y):
        return samples[y * cols + x]
    bits, n = 0, 0
    out = bytearray()

    def put(v, k):
        nonlocal bits, n
        bits, n = (bits << k) | v, n + k
        while n >= 8:
            n -= 8
            byte = (bits >> n) & 0xFF
            out.append(byte)
            if byte == 0xFF:
                out.append(0)

    def flush():
        nonlocal n
        if n:
            put((1 << (8 - n)) - 1, 8 - n)

    for y in range(rows):
        if restart_lines and y and y % restart_lines == 0:
            flush()
            out.extend(bytes([0xFF, 0xD0 + (y // restart_lines - 1) % 8]))
        first = y - y % restart_lines if restart_lines else 0
        for x in range(cols):
            a = at(x - 1, y) if x else 0
            b = at(x, y - 1) if y else 0
            c = at(x - 1, y - 1) if x and y else 0
            if y == first:
                p = 1 << (precision - 1) if x == 0 else a
            elif x == 0:
                p = b
            else:
                p = [a, b, c, a + b - c, a + ((b - c) >> 1), b + ((a - c) >> 1),
                     (a + b) >> 1][predictor - 1]
            d = (at(x, y) - p) & 0xFFFF
            d = d - 65536 if d >= 32768 else d
            s = 16 if d == -32768 else abs(d).bit_length()
            put(s, 5)
            if 0 < s < 16:
                put(d if d > 0 else d + (1 << s) - 1, s)
    flush()
    head = b"\xff\xd8\xff\xc3" + struct.pack(">HBHHB", 11, precision, rows, cols, 1) + b"\x01\x11\x00"
    head += b"\xff\xc4" + struct.pack(">H", 2 + 17 + 17) + b"\x00" + bytes([0, 0, 0, 0, 17] + [0] * 11)
    head += bytes(range(17))
    if restart_lines:
        head += b"\xff\xdd" + struct.pack(">HH", 4, restart_lines * cols)
    head += b"\xff\xda" + struct.pack(">HB", 8, 1) + bytes([1, 0, predictor, 0, 0])
    return head + bytes(out) + b"\xff\xd9"


def encapsulated(file, syntax, frame, split=0):
    """file's Pixel Data as encapsulated fragments of `frame` (split: bytes per fragment)."""
    at = file.index(b"\xe0\x7f\x10\x00")
    if len(syntax) % 2:
        syntax += b"\0"
    head = file[:at].replace(b"UI\x14\x001.2.840.10008.1.2.1\0",
                             b"UI" + struct.pack("<H", len(syntax)) + syntax)
    if len(frame) % 2:
        frame += b"\0"
    body = b"\xe0\x7f\x10\x00OB\0\0" + struct.pack("<I", 0xFFFFFFFF)
    body += struct.pack("<HHI", 0xFFFE, 0xE000, 4) + struct.pack("<I", 0)
    step = split or len(frame)
    for i in range(0, len(frame), step):
        body += struct.pack("<HHI", 0xFFFE, 0xE000, len(frame[i:i + step])) + frame[i:i + step]
    return head + body + struct.pack("<HHI", 0xFFFE, 0xE0DD, 0)


def big_endian(file):
    """Explicit VR big endian (1.2.840.10008.1.2.2): group 0002 stays little endian."""
    at = 132
    out = bytearray(file[:at])
    while at < len(file):
        group, elem = struct.unpack_from("<HH", file, at)
        vr = file[at + 4:at + 6]
        long_vr = vr in (b"OB", b"OW", b"SQ", b"UN", b"UT")
        length = struct.unpack_from("<I" if long_vr else "<H", file, at + (8 if long_vr else 6))[0]
        head = 12 if long_vr else 8
        value = file[at + head:at + head + length]
        if group == 2 and elem == 0x10:
            value = b"1.2.840.10008.1.2.2\0"
            out += file[at:at + 6] + struct.pack("<H", len(value)) + value
        elif group == 2:
            out += file[at:at + head + length]
        else:
            if vr == b"US" or vr == b"OW":
                value = b"".join(value[i:i + 2][::-1] for i in range(0, len(value), 2))
            out += struct.pack(">HH", group, elem) + vr
            out += (b"\0\0" + struct.pack(">I", len(value))) if long_vr else struct.pack(">H", len(value))
            out += value
        at += head + length
    return bytes(out)


def pixels_of(file):
    at = file.index(b"\xe0\x7f\x10\x00")
    length = struct.unpack_from("<I", file, at + 8)[0]
    return file[at + 12:at + 12 + length]


plain16 = dicom(rows=4, cols=5)
px16 = pixels_of(plain16)
plain8 = dicom(bits=8, signed=False, rows=3, cols=3)
write("ct_dicom", "explicit_4x5.dcm", plain16)  # the twin of the seeds below
write("ct_dicom", "rle16_one.dcm",
      encapsulated(plain16, b"1.2.840.10008.1.2.5", rle_frame(px16, 16, 5)))
write("ct_dicom", "rle8_one.dcm",
      encapsulated(plain8, b"1.2.840.10008.1.2.5", rle_frame(pixels_of(plain8), 8, 3)))
samples16 = [v & 0xFFF for v in struct.unpack("<20H", px16)]  # 12 bits stored
for p in (1, 4, 7):
    write("ct_dicom", "jpeg57_p%d.dcm" % p,
          encapsulated(plain16, b"1.2.840.10008.1.2.4.57",
                       jpeg_lossless(samples16, 4, 5, 12, p)))
write("ct_dicom", "jpeg70_restart.dcm",
      encapsulated(plain16, b"1.2.840.10008.1.2.4.70",
                   jpeg_lossless(samples16, 4, 5, 12, 1, restart_lines=1), split=10))
write("ct_dicom", "big_one.dcm", big_endian(plain16))
write("ct_dicom", "series2_rle.bin",
      SEPARATOR.join(encapsulated(dicom(z=z, k=k, rows=3, cols=2), b"1.2.840.10008.1.2.5",
                                  rle_frame(pixels_of(dicom(z=z, k=k, rows=3, cols=2)), 16, 2))
                     for k, z in enumerate([0.0, 1.5])))


# ---- The decoders directly (tests/fuzz/ct_codecs_fuzz.cpp): mode, rows, columns, frame.
def codec_seed(name, mode, rows, cols, frame):
    write("ct_codecs", name, bytes([mode, rows - 1, cols - 1]) + frame)


os.makedirs(os.path.join(ROOT, "ct_codecs"), exist_ok=True)
codec_seed("rle16.bin", 0, 4, 5, rle_frame(px16, 16, 5))
codec_seed("rle8.bin", 2, 3, 3, rle_frame(pixels_of(plain8), 8, 3))
for p in (1, 5, 7):
    codec_seed("jpeg_p%d.bin" % p, 1 | (14 << 2), 4, 5, jpeg_lossless(samples16, 4, 5, 12, p))
codec_seed("jpeg_restart.bin", 1 | (14 << 2), 4, 5,
           jpeg_lossless(samples16, 4, 5, 12, 2, restart_lines=2))


def j2k_codestream(name):
    """The one-fragment codestream of a JPEG 2000 fixture (fixtures/ct, make_ct_fixtures.py)."""
    data = open(os.path.join(ROOT, "..", "ct", name), "rb").read()
    at = data.rfind(b"\xe0\x7f\x10\x00") + 12
    table = struct.unpack("<I", data[at + 4:at + 8])[0]
    at += 8 + table
    length = struct.unpack("<I", data[at + 4:at + 8])[0]
    return data[at + 8:at + 8 + length]


for name, precision in (("j2k16_0", 16), ("j2k97", 16), ("j2k_tiles", 16), ("j2k8", 8)):
    codec_seed(name + ".bin", 4 | ((precision - 2) << 3), 56, 64, j2k_codestream(name + ".dcm"))
# make_j2k_styles.py's codestreams (12 bits): every code-block style the decoder reads
# together; layers, precincts, SOP and EPH; the 9/7 wavelet on signed samples.
for name in ("j2k_style58", "j2k_precincts_rpcl", "j2k_s97"):
    codec_seed(name + ".bin", 4 | ((12 - 2) << 3), 56, 64,
               open(os.path.join(ROOT, "..", "ct", name + ".j2k"), "rb").read())

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "fixtures", "ct"))
import jpegls_encode  # noqa: E402 (T.87, one component)
for name, near, lines in (("jls.bin", 0, 0), ("jls_near.bin", 2, 0), ("jls_restart.bin", 0, 2)):
    codec_seed(name, 3 | (14 << 2), 4, 5, jpegls_encode.encode(samples16, 4, 5, 12, near, lines))
for p in (2, 5, 7):  # the low bits: small MAXVAL, k 0, the default thresholds clamped
    codec_seed("jls_p%d.bin" % p, 3 | ((p - 2) << 2), 4, 5,
               jpegls_encode.encode([v & ((1 << p) - 1) for v in samples16], 4, 5, p))
for name, f in (("jls_c_high.bin", lambda x, y: 170 * x * y),  # the bias C up to 127
                ("jls_c_low.bin", lambda x, y: 170 * x * (19 - y))):  # down to -128
    codec_seed(name, 3 | (14 << 2), 20, 20,
               jpegls_encode.encode([f(x, y) for y in range(20) for x in range(20)], 20, 20, 16))
# 40 x 40, gradients of every size around the default thresholds, at precisions 2, 4, 7, 8;
# then with MAXVAL 64 and 128 in LSE, where the two default threshold formulas meet
# (C.2.4.1.1: FACTOR from 256 / (MAXVAL + 1) below 128, from (MAXVAL + 128) / 256 from 128 on).
for name, p, top in (("jls_grad_p2", 2, None), ("jls_grad_p4", 4, None),
                     ("jls_grad_p7", 7, None), ("jls_grad_p8", 8, None),
                     ("jls_grad_maxval64", 7, 64), ("jls_grad_maxval128", 8, 128)):
    levels = (1 << p) if top is None else top + 1
    codec_seed(name + ".bin", 3 | ((p - 2) << 2), 40, 40,
               jpegls_encode.encode([((x * y) // 3 + (x * x) // 7) % levels
                                     for y in range(40) for x in range(40)], 40, 40, p,
                                    maxval=top))
two_bits = [0, 0, 0, 1, 2, 3, 0, 1, 2, 0, 1, 1, 0, 3, 2, 0, 2, 1, 0, 3]  # a run, interrupted
for kind in ("regular", "run"):  # refused: a mapped error over 2 RANGE + 2
    codec_seed("jls_bad_%s.bin" % kind, 3, 4, 5,
               jpegls_encode.encode(two_bits, 4, 5, 2, corrupt=kind))
write("ct_dicom", "jls_one.dcm", encapsulated(plain16, b"1.2.840.10008.1.2.4.80",
                                              jpegls_encode.encode(samples16, 4, 5, 12)))

# Enhanced multi-frame CT (issue 31): fixtures/ct/mf16.dcm (functional groups of defined
# length) and mf16_rev.dcm (undefined lengths, frames out of order), made by
# fixtures/ct/make_ct_fixtures.py.
FIXTURES_CT = os.path.join(ROOT, "..", "ct")
for name in ("mf16.dcm", "mf16_rev.dcm"):
    with open(os.path.join(FIXTURES_CT, name), "rb") as f:
        write("ct_dicom", name, f.read())


# Compressed enhanced multi-frame (issue 31): mf16.dcm's header with the fragments of the
# single-frame compressed twins of its three frames (fixtures/ct: rle16_k, jpeg70_k, jls16_k,
# j2k16_k), one or several fragments a frame, no table, a Basic or an Extended Offset Table.
def fragment_of(data):
    at = data.rfind(b"\xe0\x7f\x10\x00") + 12
    table = struct.unpack("<I", data[at + 4:at + 8])[0]
    at += 8 + table
    length = struct.unpack("<I", data[at + 4:at + 8])[0]
    return data[at + 8:at + 8 + length]


def multi_frame(prefix, uid, pieces, table):
    with open(os.path.join(FIXTURES_CT, "mf16.dcm"), "rb") as f:
        header = f.read()
    at = header.find(b"\x02\x00\x10\x00UI")
    old = struct.unpack("<H", header[at + 6:at + 8])[0]
    value = uid + (b"\0" if len(uid) % 2 else b"")
    header = header[:at + 6] + struct.pack("<H", len(value)) + value + header[at + 8 + old:]
    group = header.find(b"\x02\x00\x00\x00UL")
    length = struct.unpack("<I", header[group + 8:group + 12])[0] + len(value) - old
    header = header[:group + 8] + struct.pack("<I", length) + header[group + 12:]
    header = header[:header.rfind(b"\xe0\x7f\x10\x00OW")]
    frames = []
    for k in range(3):
        with open(os.path.join(FIXTURES_CT, "%s_%d.dcm" % (prefix, k)), "rb") as f:
            whole = fragment_of(f.read())
        cuts = [0] + [(len(whole) * (i + 1) // pieces) & ~1 for i in range(pieces - 1)] + [len(whole)]
        frames.append([whole[cuts[i]:cuts[i + 1]] for i in range(pieces)])
    offsets, relative = [], 0
    for frame in frames:
        offsets.append(relative)
        relative += sum(8 + len(f) for f in frame)
    out = header
    if table == "extended":
        out += b"\x01\x00\xe0\x7fOV\0\0" + struct.pack("<I", 24) + b"".join(
            struct.pack("<Q", o) for o in offsets)
    bot = b"".join(struct.pack("<I", o) for o in offsets) if table == "basic" else b""
    out += b"\xe0\x7f\x10\x00OB\0\0\xff\xff\xff\xff\xfe\xff\x00\xe0" + struct.pack("<I", len(bot)) + bot
    for frame in frames:
        for f in frame:
            out += b"\xfe\xff\x00\xe0" + struct.pack("<I", len(f)) + f
    return out + b"\xfe\xff\xdd\xe0\0\0\0\0"


for name, prefix, uid, pieces, table in (
        ("mf_rle.dcm", "rle16", b"1.2.840.10008.1.2.5", 1, None),
        ("mf_jpeg70_bot.dcm", "jpeg70", b"1.2.840.10008.1.2.4.70", 2, "basic"),
        ("mf_jls_split.dcm", "jls16", b"1.2.840.10008.1.2.4.80", 3, None),
        ("mf_j2k_eot.dcm", "j2k16", b"1.2.840.10008.1.2.4.90", 2, "extended")):
    write("ct_dicom", name, multi_frame(prefix, uid, pieces, table))
