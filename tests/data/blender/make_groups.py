# Builds a rover the way modellers group parts in Blender and exports it with Blender's own glTF
# exporter. Run from the repository root:
#
#   blender -b --factory-startup --python tests/data/blender/make_groups.py
#
# The parts of one body sit in a group: an empty holding several meshes, with the body's
# rdtf_density or rdtf_mass on the empty. What sits on a part is parented to that part, not to the
# group: the IMU's and the camera's frames (empties, rdtf_joint fixed) and the wheel's axle (an
# empty, rdtf_joint continuous). docs/blender.md, section 1.
#
# It writes, beside this script:
#   modelled_groups.glb   chassis (empty, rdtf_density 2700) -> body, bumper (meshes);
#                         body -> imu (fixed frame), wheel_axle (continuous) -> wheel (mesh);
#                         chassis -> mast (empty, rdtf_mass 0.3) -> pole, head (meshes);
#                         head -> camera (fixed frame)
#   groups.json           what Blender itself says: each link's volume (bmesh, world transform
#                         applied), mass and centre of mass (of its solids, by the same tetrahedra
#                         sums over bmesh's triangles), each joint's parent and child link, its
#                         pivot and its frame's axes in glTF's scene axes
import json
import math
import os
import sys

import bmesh
import bpy
from mathutils import Matrix, Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from make_robots import clear_scene, cube, cylinder, empty, to_gltf  # noqa: E402


def volume_and_moment(obj):
    """The solid's volume and first moment (volume times centroid), in Blender's world axes."""
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.transform(obj.matrix_world)
    bmesh.ops.triangulate(bm, faces=bm.faces[:])
    volume = 0.0
    moment = Vector((0.0, 0.0, 0.0))
    for face in bm.faces:
        a, b, c = (v.co for v in face.verts)
        v = a.dot(b.cross(c)) / 6.0  # the tetrahedron with the origin
        volume += v
        moment += v * (a + b + c) / 4.0
    bm.free()
    return volume, moment


def link_record(objects, density=None, mass=None):
    volume = 0.0
    moment = Vector((0.0, 0.0, 0.0))
    for obj in objects:
        v, m = volume_and_moment(obj)
        volume += v
        moment += m
    total = mass if mass is not None else volume * density
    return {"volume": volume, "mass": total, "com_scene": to_gltf(moment / volume)}


def frame_record(name, obj, parent_link, child_link, kind, axis_local=None):
    """The joint frame: the object's node as Blender's exporter writes it, whose axes are the
    object's X, Z and -Y (turned to glTF's Y up along with everything else)."""
    R = obj.matrix_world.to_3x3().normalized()
    record = {"name": name, "parent": parent_link, "child": child_link, "type": kind,
              "pivot_scene": to_gltf(obj.matrix_world.translation),
              "x_scene": to_gltf(R @ Vector((1, 0, 0))), "y_scene": to_gltf(R @ Vector((0, 0, 1))),
              "z_scene": to_gltf(R @ Vector((0, -1, 0)))}
    if axis_local is not None:
        record["axis_scene"] = to_gltf((R @ Vector(axis_local)).normalized())
    return record


def build_rover():
    clear_scene()
    T = Matrix.Translation
    R = Matrix.Rotation
    chassis = empty("chassis", T((0, 0, 0)), None)
    chassis["rdtf_density"] = 2700.0
    body = cube("body", (0.4, 0.3, 0.1), T((0, 0, 0.1)), chassis)
    bumper = cube("bumper", (0.05, 0.3, 0.06), T((0.225, 0, 0.1)), chassis)
    imu = empty("imu", T((0.05, 0.02, 0.15)) @ R(math.radians(90), 4, "Z"), body)
    imu["rdtf_joint"] = "fixed"
    axle_world = T((0, 0.18, 0.05)) @ R(math.radians(-90), 4, "X")
    axle = empty("wheel_axle", axle_world, body)
    axle["rdtf_joint"] = "continuous"
    axle["rdtf_axis"] = "z"
    wheel = cylinder("wheel", 0.05, 0.03, axle_world, axle)
    mast = empty("mast", T((-0.1, 0, 0.15)), chassis)
    mast["rdtf_mass"] = 0.3
    pole = cylinder("pole", 0.01, 0.2, T((-0.1, 0, 0.25)), mast)
    head = cube("head", (0.06, 0.08, 0.04), T((-0.1, 0, 0.37)), mast)
    camera = empty("camera", T((-0.07, 0, 0.37)) @ R(math.radians(-90), 4, "Y"), head)
    camera["rdtf_joint"] = "fixed"
    links = {
        "chassis": link_record([body, bumper], density=2700.0),
        "wheel": link_record([wheel], density=1000.0),
        "mast": link_record([pole, head], mass=0.3),
    }
    # A frame's joint is named as rdtf names the joint node it adds; the axle's is the empty's.
    joints = [frame_record("chassis_imu_joint", imu, "chassis", "imu", "fixed"),
              frame_record("wheel_axle", axle, "chassis", "wheel", "continuous", (0, 0, 1)),
              frame_record("chassis_mast_joint", mast, "chassis", "mast", "fixed"),
              frame_record("mast_camera_joint", camera, "mast", "camera", "fixed")]
    return {"links": links, "frame_links": ["imu", "camera"], "joints": joints}


def main():
    record = {"generator": "Blender " + bpy.app.version_string, "modelled_groups": build_rover()}
    bpy.ops.export_scene.gltf(filepath=os.path.join(HERE, "modelled_groups.glb"), export_format="GLB",
                              export_extras=True, export_animations=False)
    with open(os.path.join(HERE, "groups.json"), "w") as out:
        json.dump(record, out, indent=1, sort_keys=True)
        out.write("\n")


if __name__ == "__main__":
    main()
