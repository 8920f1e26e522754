"""Independent check of a 3MF print job (issue 32), with Python's zipfile, zlib, struct and XML
parser (no code shared with splintcore): the ZIP's CRCs, the OPC parts, a 3MF core model in
millimetres, and for every build item its object's vertices moved by the item's transform:
all inside the tray (x, y in [0, X] x [0, Y], bottom at z = 0, top at most Z) and, between two
objects' bounding boxes along the row, at least GAP mm.
With STL files (binary, one per object in build order, e.g. intermediate.stl final.stl), each
object is compared with its STL, read here with struct: the same triangle count, the same
corners triangle by triangle (the 3MF's decimal text read back to float32 equals the STL's
float32), and the same signed volume to 1e-6 relative, the 3MF's computed on the vertices
as placed by the build item's transform (a rigid move keeps the volume).
usage: check_3mf.py JOB.3mf OBJECTS TRAY_X TRAY_Y GAP [SHA256 ...] [--height Z]
                    [--stl A.stl B.stl ...]
"""
import struct
import sys
import xml.etree.ElementTree as ET
import zipfile

NS = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}


def f32(x):
    """x rounded to float32, as a Python float."""
    return struct.unpack("<f", struct.pack("<f", x))[0]


def signed_volume(triangles):
    """Sum of the tetrahedra (origin, a, b, c): the enclosed volume of a closed outward mesh."""
    total = 0.0
    for a, b, c in triangles:
        total += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                  a[2] * (b[0] * c[1] - b[1] * c[0]))
    return total / 6.0


def read_binary_stl(path):
    """The triangles of a binary STL as ((x, y, z), (x, y, z), (x, y, z)) of float32 values."""
    data = open(path, "rb").read()
    assert len(data) >= 84, (path, "shorter than a binary STL header")
    (count,) = struct.unpack_from("<I", data, 80)
    assert len(data) == 84 + 50 * count, (path, len(data), count)
    triangles = []
    for t in range(count):
        v = struct.unpack_from("<12f", data, 84 + 50 * t)
        triangles.append(((v[3], v[4], v[5]), (v[6], v[7], v[8]), (v[9], v[10], v[11])))
    return triangles


def parse_args(argv):
    hashes, stls, height, k = [], [], None, 0
    while k < len(argv):
        if argv[k] == "--height":
            height = float(argv[k + 1])
            k += 2
        elif argv[k] == "--stl":
            stls = argv[k + 1:]
            break
        else:
            hashes.append(argv[k])
            k += 1
    return hashes, stls, height


def compare_with_stl(k, vertices, triangles, placed, stl_path):
    """Object k (its own vertices and triangles, and the triangles as placed) against its STL."""
    stl = read_binary_stl(stl_path)
    assert len(stl) == len(triangles), (k, stl_path, len(stl), len(triangles))
    for t, (ids, corners) in enumerate(zip(triangles, stl)):
        ours = tuple(tuple(f32(c) for c in vertices[i]) for i in ids)
        assert ours == corners, (k, stl_path, "triangle", t, ours, corners)
    v3mf, vstl = signed_volume(placed), signed_volume(stl)
    assert vstl > 0, (stl_path, vstl)
    assert abs(v3mf - vstl) <= 1e-6 * abs(vstl), (k, stl_path, v3mf, vstl)
    return len(stl), v3mf, vstl


def main():
    path, count = sys.argv[1], int(sys.argv[2])
    tray_x, tray_y, gap = float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
    hashes, stls, height = parse_args(sys.argv[6:])
    assert not stls or len(stls) == count, ("one STL per object", stls)
    z = zipfile.ZipFile(path)
    assert z.testzip() is None, "a CRC does not match"
    names = z.namelist()
    assert names == ["[Content_Types].xml", "_rels/.rels", "3D/3dmodel.model"], names
    assert b"/3D/3dmodel.model" in z.read("_rels/.rels")
    model = ET.fromstring(z.read("3D/3dmodel.model"))
    assert model.get("unit") == "millimeter", model.get("unit")
    objects = {o.get("id"): o for o in model.findall("m:resources/m:object", NS)}
    items = model.findall("m:build/m:item", NS)
    assert len(objects) == count and len(items) == count, (len(objects), len(items))
    boxes = []
    for k, item in enumerate(items):
        o = objects[item.get("objectid")]
        t = [float(v) for v in item.get("transform", "1 0 0 0 1 0 0 0 1 0 0 0").split()]
        assert t[:9] == [1, 0, 0, 0, 1, 0, 0, 0, 1], t
        vertices = [(float(v.get("x")), float(v.get("y")), float(v.get("z")))
                    for v in o.findall("m:mesh/m:vertices/m:vertex", NS)]
        moved = [(x + t[9], y + t[10], w + t[11]) for x, y, w in vertices]
        tris = [(int(x.get("v1")), int(x.get("v2")), int(x.get("v3")))
                for x in o.findall("m:mesh/m:triangles/m:triangle", NS)]
        assert len(tris) > 0 and all(i < len(vertices) for tri in tris for i in tri)
        xs, ys, zs = zip(*moved)
        box = (min(xs), max(xs), min(ys), max(ys), min(zs), max(zs))
        assert box[0] >= 0 and box[1] <= tray_x and box[2] >= 0 and box[3] <= tray_y, box
        assert abs(box[4]) < 1e-6, box
        assert height is None or box[5] <= height, (box, height)
        if hashes:
            sha = [m.text for m in o.findall("m:metadatagroup/m:metadata", NS)]
            assert sha == [hashes[k]], (sha, hashes[k])
        if stls:
            placed = [tuple(moved[i] for i in tri) for tri in tris]
            n, v3mf, vstl = compare_with_stl(k, vertices, tris, placed, stls[k])
            print("object %d: %d triangles, volume %.6f mm^3 placed, %.6f mm^3 in %s" %
                  (k, n, v3mf, vstl, stls[k]))
        boxes.append(box)
    for i, a in enumerate(boxes):  # every pair: apart by at least GAP along x or along y
        for b in boxes[i + 1:]:
            apart = max(b[0] - a[1], a[0] - b[1], b[2] - a[3], a[2] - b[3])
            assert apart >= gap - 1e-9, (a, b, apart)
    print("3MF ok: %d objects, %d bytes" % (count, sum(i.file_size for i in z.infolist())))


main()
