#!/usr/bin/env python3
"""Writes the KHR_physics_rigid_bodies twin fixtures (pure Python, no dependencies):

  arm_extras.gltf  a three-link arm whose joints and masses are authored as rdtf_* node extras
  arm_khr.gltf     the same arm with the same joints and masses authored as
                   KHR_physics_rigid_bodies motion and joints (attachment nodes), no rdtf_* key

Both must convert to the same robot (tests/rdtf/khr_physics_test.cc). Run from anywhere:
  python3 tests/data/khr/make_twins.py
"""
import base64
import json
import math
import os
import struct

HERE = os.path.dirname(os.path.abspath(__file__))


def box(hx, hy, hz):
    v = [(sx * hx, sy * hy, sz * hz) for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)]
    # Outward (counter-clockwise seen from outside) triangles of the 6 faces.
    faces = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    for a, b, c, d in faces:
        tris += [a, b, c, a, c, d]
    return v, tris


def qmul(a, b):  # [x, y, z, w]
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return [aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
            aw * bw - ax * bx - ay * by - az * bz]


def qaxis(axis, angle):
    s = math.sin(angle / 2)
    return [axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)]


def qmat(q):
    x, y, z, w = q
    return [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]


def buffers(meshes):
    data = b""
    views, accessors, gltf_meshes = [], [], []
    for verts, tris in meshes:
        pos = b"".join(struct.pack("<3f", *p) for p in verts)
        idx = b"".join(struct.pack("<H", i) for i in tris)
        idx += b"\0" * (-len(idx) % 4)
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(pos), "target": 34962})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5126, "count": len(verts), "type": "VEC3",
                          "min": [min(p[i] for p in verts) for i in range(3)],
                          "max": [max(p[i] for p in verts) for i in range(3)]})
        data += pos
        views.append({"buffer": 0, "byteOffset": len(data), "byteLength": len(tris) * 2, "target": 34963})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5123, "count": len(tris), "type": "SCALAR"})
        data += idx
        gltf_meshes.append({"primitives": [{"attributes": {"POSITION": len(accessors) - 2}, "indices": len(accessors) - 1}]})
    uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    return [{"byteLength": len(data), "uri": uri}], views, accessors, gltf_meshes


# The arm: base (mesh 0) -> arm (mesh 1), revolute about the arm frame's z, turned 30 degrees
# about z and placed at (0.3, 0.1, 0); arm -> slider (mesh 0), prismatic along (0.6, 0.8, 0) of
# the slider frame, 0.4 m up the arm's z.
Q_ARM = qaxis((0, 0, 1), math.radians(30))
T_ARM = [0.3, 0.1, 0.0]
T_SLIDER = [0.0, 0.0, 0.4]
REVOLUTE = {"lower": -1.0, "upper": 1.5, "damping": 0.3, "stiffness": 2.0}
PRISMATIC = {"lower": 0.0, "upper": 0.2, "damping": 5.0}
PRISMATIC_AXIS = [0.6, 0.8, 0.0]
BASE_MASS = 5.0
# The arm's authored inertia: principal moments turned by a quaternion (a full tensor).
ARM_MASS = 1.25
ARM_COM = [0.01, -0.02, 0.2]
ARM_MOMENTS = [0.002, 0.011, 0.012]
ARM_ORIENTATION = qmul(qaxis((0, 0, 1), 0.4), qaxis((1, 0, 0), -0.7))


def document(nodes, extensions=None):
    bufs, views, accessors, meshes = buffers([box(0.2, 0.1, 0.1), box(0.05, 0.05, 0.25)])
    doc = {"asset": {"version": "2.0", "generator": "rdtf tests/data/khr/make_twins.py"},
           "scene": 0, "scenes": [{"nodes": [0]}], "nodes": nodes, "meshes": meshes,
           "accessors": accessors, "bufferViews": views, "buffers": bufs}
    if extensions:
        doc["extensionsUsed"] = ["KHR_physics_rigid_bodies"]
        doc["extensions"] = extensions
    return doc


def extras_twin():
    R = qmat(ARM_ORIENTATION)
    I = [[sum(R[i][k] * ARM_MOMENTS[k] * R[j][k] for k in range(3)) for j in range(3)] for i in range(3)]
    nodes = [
        {"name": "base", "mesh": 0, "children": [1], "extras": {"rdtf_mass": BASE_MASS}},
        {"name": "arm", "mesh": 1, "translation": T_ARM, "rotation": Q_ARM, "children": [2, 3],
         "extras": {"rdtf_joint": "revolute", "rdtf_axis": [0, 0, 1], "rdtf_lower": REVOLUTE["lower"],
                    "rdtf_upper": REVOLUTE["upper"], "rdtf_damping": REVOLUTE["damping"],
                    "rdtf_spring_stiffness": REVOLUTE["stiffness"]}},
        {"name": "slider", "mesh": 0, "translation": T_SLIDER,
         "extras": {"rdtf_joint": "prismatic", "rdtf_axis": PRISMATIC_AXIS, "rdtf_lower": PRISMATIC["lower"],
                    "rdtf_upper": PRISMATIC["upper"], "rdtf_damping": PRISMATIC["damping"]}},
        {"name": "arm_inertial", "extras": {"rdtf_type": "inertial", "rdtf_inertial": {
            "mass": ARM_MASS, "gravityCenter": ARM_COM, "inertia": [I[0][0], I[0][1], I[0][2], I[1][1], I[1][2], I[2][2]]}}},
    ]
    return document(nodes)


def khr_twin():
    q_x_to_z = qaxis((0, 1, 0), -math.pi / 2)  # turns X onto Z: the revolute axis
    q_x_to_slide = qaxis((0, 0, 1), math.atan2(PRISMATIC_AXIS[1], PRISMATIC_AXIS[0]))
    physics = lambda **kw: {"extensions": {"KHR_physics_rigid_bodies": kw}}
    nodes = [
        dict({"name": "base", "mesh": 0, "children": [1, 3]}, **physics(motion={"mass": BASE_MASS})),
        dict({"name": "arm", "mesh": 1, "translation": T_ARM, "rotation": Q_ARM, "children": [2, 4, 5]},
             **physics(motion={"mass": ARM_MASS, "centerOfMass": ARM_COM, "inertiaDiagonal": ARM_MOMENTS,
                               "inertiaOrientation": ARM_ORIENTATION})),
        {"name": "slider", "mesh": 0, "translation": T_SLIDER, "children": [6]},
        dict({"name": "base_arm_frame", "translation": T_ARM, "rotation": qmul(Q_ARM, q_x_to_z)},
             **physics(joint={"connectedNode": 4, "joint": 0})),
        {"name": "arm_base_frame", "rotation": q_x_to_z},
        dict({"name": "arm_slider_frame", "translation": T_SLIDER, "rotation": q_x_to_slide},
             **physics(joint={"connectedNode": 6, "joint": 1})),
        {"name": "slider_arm_frame", "rotation": q_x_to_slide},
    ]
    locked = lambda key, axes: {key: axes, "min": 0.0, "max": 0.0}
    joints = [
        {"limits": [locked("linearAxes", [0, 1, 2]), locked("angularAxes", [1, 2]),
                    {"angularAxes": [0], "min": REVOLUTE["lower"], "max": REVOLUTE["upper"]}],
         "drives": [{"type": "angular", "mode": "force", "axis": 0, "damping": REVOLUTE["damping"],
                     "stiffness": REVOLUTE["stiffness"]}]},
        {"limits": [locked("linearAxes", [1, 2]), locked("angularAxes", [0, 1, 2]),
                    {"linearAxes": [0], "min": PRISMATIC["lower"], "max": PRISMATIC["upper"]}],
         "drives": [{"type": "linear", "mode": "force", "axis": 0, "damping": PRISMATIC["damping"]}]},
    ]
    return document(nodes, {"KHR_physics_rigid_bodies": {"physicsJoints": joints}})


for name, doc in (("arm_extras.gltf", extras_twin()), ("arm_khr.gltf", khr_twin())):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(doc, f, indent=2)
        f.write("\n")
