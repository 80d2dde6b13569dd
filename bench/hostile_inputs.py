#!/usr/bin/env python3
# glTFs that cost rdtf more than their size if a stage walks them quadratically, one dimension at a
# time (docs/benchmarks.md, "Parsing JSON: objects of many keys" and after):
#   python3 bench/hostile_inputs.py KIND N OUT.gltf
#   KIND longroot_star  a root link of a 1 MB name with N child links (generated joint names)
#        anim_channels  N links carrying their own mesh, an animation channel on each (retargeting)
#        morph          30,000 vertices and N morph targets all naming them, all weighed
# Then time whole processes: /usr/bin/time -f '%e s %M KB' build/clients/rdtf/rdtf convert OUT.gltf -o o/out.gltf
import base64, json, struct, sys
kind, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
# A unit box: 8 vertices, 12 triangles.
P = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
T = [0,1,3, 0,3,2, 4,6,7, 4,7,5, 0,4,5, 0,5,1, 2,3,7, 2,7,6, 0,2,6, 0,6,4, 1,5,7, 1,7,3]
def box_doc(extra_bytes=b""):
    pos = b"".join(struct.pack("<3f", *p) for p in P)
    idx = b"".join(struct.pack("<H", i) for i in T)
    data = pos + idx + extra_bytes
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3", "min": [0,0,0], "max": [1,1,1]},
                         {"bufferView": 1, "componentType": 5123, "count": 36, "type": "SCALAR"}],
           "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 96, "target": 34962},
                           {"buffer": 0, "byteOffset": 96, "byteLength": 72, "target": 34963}],
           "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}]}
    return doc
if kind == "longroot_star":  # a root link of a 1 MB name, n child links
    doc = box_doc()
    doc["nodes"] = [{"name": "r" * 1_000_000, "mesh": 0, "children": list(range(1, n + 1))}] + \
                   [{"name": f"c{i}", "mesh": 0, "translation": [2.0 * i, 0, 0]} for i in range(1, n + 1)]
elif kind == "anim_channels":  # n links carrying their own mesh, one channel on each
    times = struct.pack("<2f", 0, 1); values = struct.pack("<6f", 0, 0, 0, 0, 0, 0)
    doc = box_doc(times + values)
    doc["nodes"] = [{"name": "base", "mesh": 0, "children": list(range(1, n + 1))}] + \
                   [{"name": f"c{i}", "mesh": 0, "translation": [2.0 * i, 0, 0]} for i in range(1, n + 1)]
    doc["bufferViews"] += [{"buffer": 0, "byteOffset": 168, "byteLength": 8}, {"buffer": 0, "byteOffset": 176, "byteLength": 24}]
    doc["accessors"] += [{"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
                         {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}]
    doc["animations"] = [{"samplers": [{"input": 2, "output": 3}],
                          "channels": [{"sampler": 0, "target": {"node": i, "path": "translation"}} for i in range(n + 1)]}]
elif kind == "morph":  # 30,000 vertices (10,000 small boxes' worth of triangles), n targets sharing them, all weighed
    import random
    random.seed(1)
    V = 30000
    pos = []
    for t in range(V // 3):
        x, y, z = random.random(), random.random(), random.random()
        pos += [(x, y, z), (x + 0.01, y, z), (x, y + 0.01, z + 0.001 * (t % 7))]
    data = b"".join(struct.pack("<3f", *p) for p in pos)
    doc = {"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "base", "mesh": 0}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "targets": [{"POSITION": 0}] * n}], "weights": [1e-9] * n}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": V, "type": "VEC3",
                          "min": [min(p[i] for p in pos) for i in range(3)], "max": [max(p[i] for p in pos) for i in range(3)]}],
           "bufferViews": [{"buffer": 0, "byteLength": len(data), "target": 34962}],
           "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}]}
else:
    sys.exit("unknown kind")
json.dump(doc, open(out, "w"), separators=(",", ":"))
