#!/usr/bin/env python3
"""Seeds of the draco and meshopt fuzz targets (fuzz/decoder_models.h says the input layout):
the compressed meshes of the encoders' outputs in tests/data/encoded/, each with its header.
Run from the repository root: python3 fuzz/make_decoder_seeds.py"""
import base64, json, os, struct

ENCODED = "tests/data/encoded"


def gltf_buffers(path):
    document = json.load(open(path))
    buffers = []
    for buffer in document["buffers"]:
        uri = buffer["uri"]
        if uri.startswith("data:"):
            buffers.append(base64.b64decode(uri.split(",", 1)[1]))
        else:
            buffers.append(open(os.path.join(os.path.dirname(path), uri), "rb").read())
    return document, buffers


def glb(path):
    data = open(path, "rb").read()
    json_length = struct.unpack_from("<I", data, 12)[0]
    document = json.loads(data[20:20 + json_length])
    bin_at = 20 + json_length
    bin_length = struct.unpack_from("<I", data, bin_at)[0]
    return document, [data[bin_at + 8:bin_at + 8 + bin_length]]


def view_bytes(document, buffers, index):
    view = document["bufferViews"][index]
    start = view.get("byteOffset", 0)
    return buffers[view["buffer"]][start:start + view["byteLength"]]


def write(target, name, data):
    folder = os.path.join("fuzz/corpus", target)
    os.makedirs(folder, exist_ok=True)
    open(os.path.join(folder, name), "wb").write(data)


for source in ("arm_draco.gltf", "arm_draco_transcoder.gltf"):
    document, buffers = gltf_buffers(os.path.join(ENCODED, source))
    for m, mesh in enumerate(document["meshes"]):
        primitive = mesh["primitives"][0]
        draco = primitive["extensions"]["KHR_draco_mesh_compression"]
        vertices = document["accessors"][primitive["attributes"]["POSITION"]]["count"]
        indices = document["accessors"][primitive["indices"]]
        wide = 1 if indices["componentType"] == 5125 else 0
        header = struct.pack("<HHBB", vertices, indices["count"], draco["attributes"]["POSITION"], wide)
        write("draco", "%s_mesh%d" % (source.split(".")[0], m), header + view_bytes(document, buffers, draco["bufferView"]))

document, buffers = glb(os.path.join(ENCODED, "arm_meshopt.glb"))
views = [v["extensions"]["EXT_meshopt_compression"] for v in document["bufferViews"]]
positions = next(v for v in views if v["mode"] == "ATTRIBUTES" and v["byteStride"] == 8)
triangles = next(v for v in views if v["mode"] == "TRIANGLES")


def stream(extension):
    start = extension.get("byteOffset", 0)
    return buffers[extension["buffer"]][start:start + extension["byteLength"]]


flags = 1 | (4 if triangles["byteStride"] == 4 else 0)
vertex_stream = stream(positions)
# The index stream refers to vertices of all three meshes: the whole vertex stream with it.
header = struct.pack("<HHBH", positions["count"], triangles["count"], flags, len(vertex_stream))
write("meshopt", "arm_meshopt", header + vertex_stream + stream(triangles))

# The unit cube with texture coordinates (22 points: the coordinates' seams split vertices; 36
# indices; POSITION is Draco attribute 0): a seed, and as regression inputs of scripts/draco's patch
# the cube as it is and with its count of texture-coordinate orientations (an int32 at byte 117 of
# the stream, found by printing the decoder's position there; 12 as encoded) set to 2^30, over the
# mesh's 36 corners. Unpatched libdraco 1.5.5 takes seconds and 130 MB over it, then decodes it.
cube = open(os.path.join(ENCODED, "cube_texcoords.drc"), "rb").read()
header = struct.pack("<HHBB", 22, 36, 0, 0)
write("draco", "cube_texcoords", header + cube)
ORIENTATIONS_AT = 117
assert struct.unpack_from("<i", cube, ORIENTATIONS_AT)[0] == 12
crafted = bytearray(cube)
struct.pack_into("<i", crafted, ORIENTATIONS_AT, 1 << 30)
regressions = "tests/data/fuzz-regressions/draco"
open(os.path.join(regressions, "cube_texcoords"), "wb").write(header + cube)
open(os.path.join(regressions, "texcoord_orientations_over_corners"), "wb").write(header + bytes(crafted))
