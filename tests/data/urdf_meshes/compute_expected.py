# Computes expected.json from the fixture files' own text, with neither assimp nor Blender: a small
# COLLADA reader (xml.etree + numpy, double precision) and a small OBJ/MTL reader. Run with a
# Python that has numpy:  python3 compute_expected.py
#
# Convention (ROS: RViz / geometric_shapes): every COLLADA node transform applied; <up_axis>
# ignored; <unit meter> applied; OBJ coordinates are metres as written; polygons are fanned into
# triangles (v0 vi vi+1), which for these planar convex quads changes neither bounds nor volume.
import json
import os
import xml.etree.ElementTree as ET

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
NS = "{http://www.collada.org/2005/11/COLLADASchema}"


def floats(text):
    return np.array([float(x) for x in text.split()], dtype=np.float64)


def node_matrix(node):
    """The node's local transform: its transform elements multiplied in document order."""
    m = np.eye(4)
    for el in node:
        tag = el.tag[len(NS):]
        if tag == "matrix":
            m = m @ floats(el.text).reshape(4, 4)
        elif tag == "translate":
            t = np.eye(4)
            t[:3, 3] = floats(el.text)
            m = m @ t
        elif tag == "scale":
            m = m @ np.diag(list(floats(el.text)) + [1.0])
        elif tag == "rotate":
            x, y, z, deg = floats(el.text)
            a = np.array([x, y, z]) / np.linalg.norm([x, y, z])
            th = np.radians(deg)
            k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
            r = np.eye(4)
            r[:3, :3] = np.eye(3) + np.sin(th) * k + (1 - np.cos(th)) * (k @ k)
            m = m @ r
        elif tag in ("lookat", "skew"):
            raise NotImplementedError(tag)
    return m


def read_dae(path):
    root = ET.parse(path).getroot()
    asset = root.find(NS + "asset")
    unit_el = asset.find(NS + "unit")
    unit = float(unit_el.get("meter")) if unit_el is not None else 1.0
    up_el = asset.find(NS + "up_axis")
    up = up_el.text.strip() if up_el is not None else "Y_UP"
    ids = {el.get("id"): el for el in root.iter() if el.get("id")}

    def ref(url):
        return ids[url.lstrip("#")]

    def diffuse(material_el):
        effect = ref(material_el.find(NS + "instance_effect").get("url"))
        col = effect.find(".//" + NS + "diffuse/" + NS + "color")
        return [float(x) for x in col.text.split()] if col is not None else None

    def geometry_triangles(geom):
        """[(symbol, [(i, j, k) position indices]), ...] and the positions."""
        mesh = geom.find(NS + "mesh")
        verts = mesh.find(NS + "vertices")
        pos_src = ref(verts.find(NS + "input[@semantic='POSITION']").get("source"))
        pos = floats(pos_src.find(NS + "float_array").text).reshape(-1, 3)
        groups = []
        for prim in mesh:
            tag = prim.tag[len(NS):]
            if tag not in ("triangles", "polylist", "polygons"):
                continue
            inputs = prim.findall(NS + "input")
            stride = max(int(i.get("offset")) for i in inputs) + 1
            voff = int(next(i for i in inputs if i.get("semantic") == "VERTEX").get("offset"))
            if tag == "polygons":
                polys = [list(map(int, p.text.split()))[voff::stride]
                         for p in prim.findall(NS + "p")]
            else:
                idx = list(map(int, prim.find(NS + "p").text.split()))[voff::stride]
                counts = ([3] * int(prim.get("count")) if tag == "triangles"
                          else list(map(int, prim.find(NS + "vcount").text.split())))
                polys, at = [], 0
                for c in counts:
                    polys.append(idx[at:at + c])
                    at += c
                assert at == len(idx)
            tris = [(p[0], p[k], p[k + 1]) for p in polys for k in range(1, len(p) - 1)]
            groups.append((prim.get("material"), tris))
        return pos, groups

    instances = []  # (world matrix, geometry element, {symbol: material element})

    def walk(node, parent):
        world = parent @ node_matrix(node)
        for ig in node.findall(NS + "instance_geometry"):
            binds = {im.get("symbol"): ref(im.get("target"))
                     for im in ig.iter(NS + "instance_material")}
            instances.append((world, ref(ig.get("url")), binds))
        for inode in node.findall(NS + "instance_node"):
            walk(ref(inode.get("url")), world)
        for child in node.findall(NS + "node"):
            walk(child, world)

    scene = ref(root.find(NS + "scene/" + NS + "instance_visual_scene").get("url"))
    for node in scene.findall(NS + "node"):
        walk(node, np.eye(4))

    tris, mats, closed = [], {}, True
    for world, geom, binds in instances:
        pos, groups = geometry_triangles(geom)
        p = (np.c_[pos, np.ones(len(pos))] @ world.T)[:, :3] * unit  # up_axis not used
        edges = {}
        for symbol, t in groups:
            m = binds[symbol]
            key = m.get("name") or m.get("id")
            entry = mats.setdefault(key, {"name": m.get("name"), "id": m.get("id"),
                                          "diffuse_rgba": diffuse(m), "triangles": 0})
            entry["triangles"] += len(t)
            for a, b, c in t:
                tris.append(p[[a, b, c]])
                for e in ((a, b), (b, c), (c, a)):
                    edges[e] = edges.get(e, 0) + 1
        # closed: every directed edge used once, and its reverse once
        closed &= all(n == 1 and edges.get((b, a)) == 1 for (a, b), n in edges.items())
    return {"unit_meter": unit, "up_axis": up, "instances": len(instances)}, np.array(tris), \
        list(mats.values()), closed


def read_obj(path):
    verts, tris, mats, cur, mtllib = [], [], {}, None, None
    edges = {}
    for line in open(path):
        w = line.split()
        if not w:
            continue
        if w[0] == "v":
            verts.append([float(x) for x in w[1:4]])
        elif w[0] == "mtllib":
            mtllib = w[1]
        elif w[0] == "usemtl":
            cur = w[1]
            mats.setdefault(cur, {"name": cur, "triangles": 0})
        elif w[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in w[1:]]
            for k in range(1, len(idx) - 1):
                tris.append((idx[0], idx[k], idx[k + 1]))
                mats[cur]["triangles"] += 1
                a, b, c = tris[-1]
                for e in ((a, b), (b, c), (c, a)):
                    edges[e] = edges.get(e, 0) + 1
    kd, d, name = {}, {}, None
    for line in open(os.path.join(os.path.dirname(path), mtllib)):
        w = line.split()
        if w and w[0] == "newmtl":
            name = w[1]
        elif w and w[0] == "Kd":
            kd[name] = [float(x) for x in w[1:4]]
        elif w and w[0] == "d":
            d[name] = float(w[1])
    for m in mats.values():
        m["diffuse_rgba"] = kd[m["name"]] + [d.get(m["name"], 1.0)]
    closed = all(n == 1 and edges.get((b, a)) == 1 for (a, b), n in edges.items())
    v = np.array(verts)
    return {"mtllib": mtllib}, np.array([v[list(t)] for t in tris]), list(mats.values()), closed


def summary(tris, closed):
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    vols = np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0  # tetrahedra with the origin
    vol = float(vols.sum())
    out = {"triangles": len(tris), "closed": bool(closed),
           "min": tris.reshape(-1, 3).min(axis=0).tolist(),
           "max": tris.reshape(-1, 3).max(axis=0).tolist(),
           "volume": vol if closed else None,
           "centroid": ((vols[:, None] * (a + b + c) / 4.0).sum(axis=0) / vol).tolist()
           if closed else None}
    if not closed:
        out["area"] = float(np.linalg.norm(np.cross(b - a, c - a), axis=1).sum() / 2.0)
    return out


def with_scale(entry, s):
    """The same mesh under a URDF <mesh scale> (positive), in the visual's frame."""
    s = np.array(s, dtype=float)
    lo, hi = np.array(entry["min"]) * s, np.array(entry["max"]) * s
    out = {"triangles": entry["triangles"], "min": np.minimum(lo, hi).tolist(),
           "max": np.maximum(lo, hi).tolist()}
    if entry["volume"] is not None:
        out["volume"] = entry["volume"] * float(np.prod(s))
        out["centroid"] = (np.array(entry["centroid"]) * s).tolist()
    return out


files = {}
for name in ["box_mm.dae", "box_yup.dae", "nested.dae", "open_plane.dae", "box.obj"]:
    path = os.path.join(HERE, name)
    head, tris, mats, closed = (read_obj if name.endswith(".obj") else read_dae)(path)
    files[name] = {**head, **summary(tris, closed), "materials": mats}

visuals = {  # link: (file, <mesh scale>), as in robot.urdf; visual origins are the identity
    "base_link": ("box_mm.dae", (1, 1, 1)),
    "nested_link": ("nested.dae", (1, 1, 1)),
    "obj_link": ("box.obj", (2, 2, 2)),
    "yup_link": ("box_yup.dae", (1, 1, 1)),
}
expected = {
    "convention": "metres in the link frame: COLLADA node transforms applied, <unit meter> "
                  "applied, <up_axis> ignored; OBJ as written; triangle counts after fanning "
                  "polygons; volume/centroid by the divergence theorem (closed meshes only)",
    "computed_by": "compute_expected.py: own COLLADA/OBJ readers, numpy float64, from the files' "
                   "text; cross-checked against blender_reference.json (matrix_world @ v.co)",
    "files": files,
    "urdf_visuals": {link: {"file": f, "scale": list(s), **with_scale(files[f], s)}
                     for link, (f, s) in visuals.items()},
}
with open(os.path.join(HERE, "expected.json"), "w") as f:
    json.dump(expected, f, indent=1)
    f.write("\n")

# Analytic values (each box's volume is the product of its scaled sides; see README.md). The files
# differ from them by Blender's float32 matrices as printed (cos 90 deg = -4.37114e-8): < 1e-7 m.
ANALYTIC = {
    # 50 x 30 x 20 mm box, scale (2, 1, 0.5), 90 deg about z, at (100, 50, 30) mm
    "box_mm.dae": ([0.085, 0.0, 0.025], [0.115, 0.1, 0.035], 0.1 * 0.03 * 0.01, [0.1, 0.05, 0.03]),
    # box_a 0.4 x 0.2 x 0.25 times 0.5 -> 0.0025 m^3 centred at (0.5, 0.2, 0.25); box_b with
    # (1, 2, 1) -> 0.005 m^3 centred at (0.5, 0.2, 0.45)
    "nested.dae": ([0.4, 0.1, 0.2], [0.6, 0.3, 0.55], 0.0075,
                   [0.5, 0.2, (0.0025 * 0.25 + 0.005 * 0.45) / 0.0075]),
    "open_plane.dae": ([-0.2, -0.1, 0.05], [0.2, 0.1, 0.05], None, None),
    # 0.1 x 0.08 x 0.06 box at (0.2, -0.1, 0.05)
    "box.obj": ([0.15, -0.14, 0.02], [0.25, -0.06, 0.08], 0.1 * 0.08 * 0.06, [0.2, -0.1, 0.05]),
}
ANALYTIC["box_yup.dae"] = ANALYTIC["box_mm.dae"]
for name, (lo, hi, vol, cen) in ANALYTIC.items():
    e = files[name]
    assert np.allclose(e["min"], lo, rtol=0, atol=1e-7), (name, e["min"], lo)
    assert np.allclose(e["max"], hi, rtol=0, atol=1e-7), (name, e["max"], hi)
    if vol is not None:
        assert abs(e["volume"] / vol - 1) < 1e-6, (name, e["volume"], vol)
        assert np.allclose(e["centroid"], cen, rtol=0, atol=1e-7), (name, e["centroid"], cen)
print("analytic values agree (1e-7 m, volume 1e-6 relative)")

# Cross-check with Blender's own world-space numbers (float32 inputs: about 1e-7 relative)
ref = json.load(open(os.path.join(HERE, "blender_reference.json")))
for name, e in files.items():
    r = ref[name]
    assert r["triangles"] == e["triangles"], name
    dmin = np.abs(np.array(r["min"]) - e["min"]).max()
    dmax = np.abs(np.array(r["max"]) - e["max"]).max()
    line = f"{name}: tris {e['triangles']} |dmin| {dmin:.2e} |dmax| {dmax:.2e}"
    if e["volume"] is not None:
        line += f" vol rel {abs(r['volume'] / e['volume'] - 1):.2e}"
        line += f" |dcentroid| {np.abs(np.array(r['centroid']) - e['centroid']).max():.2e}"
    counts = {m["name"]: m["triangles"] for m in e["materials"]}
    assert counts == r["material_triangles"], (name, counts, r["material_triangles"])
    print(line)
