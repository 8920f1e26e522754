"""Independent check of a 3MF print job (issue 32), with Python's zipfile, zlib and XML parser
(no code shared with splintcore): the ZIP's CRCs, the OPC parts, a 3MF core model in
millimetres, and for every build item its object's vertices moved by the item's transform:
all inside the tray (x, y in [0, X] x [0, Y], bottom at z = 0) and, between two objects'
bounding boxes along the row, at least GAP mm.
usage: check_3mf.py JOB.3mf OBJECTS TRAY_X TRAY_Y GAP [SHA256 ...]
"""
import sys
import xml.etree.ElementTree as ET
import zipfile

NS = {"m": "http://schemas.microsoft.com/3dmanufacturing/core/2015/02"}


def main():
    path, count = sys.argv[1], int(sys.argv[2])
    tray_x, tray_y, gap = float(sys.argv[3]), float(sys.argv[4]), float(sys.argv[5])
    hashes = sys.argv[6:]
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
        xs, ys, zs = [], [], []
        for v in o.findall("m:mesh/m:vertices/m:vertex", NS):
            xs.append(float(v.get("x")) + t[9])
            ys.append(float(v.get("y")) + t[10])
            zs.append(float(v.get("z")) + t[11])
        tris = o.findall("m:mesh/m:triangles/m:triangle", NS)
        assert len(tris) > 0 and all(int(x.get(a)) < len(xs) for x in tris for a in ("v1", "v2", "v3"))
        box = (min(xs), max(xs), min(ys), max(ys), min(zs), max(zs))
        assert box[0] >= 0 and box[1] <= tray_x and box[2] >= 0 and box[3] <= tray_y, box
        assert abs(box[4]) < 1e-6, box
        if hashes:
            sha = [m.text for m in o.findall("m:metadatagroup/m:metadata", NS)]
            assert sha == [hashes[k]], (sha, hashes[k])
        boxes.append(box)
    boxes.sort()
    for a, b in zip(boxes, boxes[1:]):
        assert b[0] - a[1] >= gap - 1e-9, (a, b)
    print("3MF ok: %d objects, %d bytes" % (count, sum(i.file_size for i in z.infolist())))


main()
