# Builds the Blender-made test robots the way a modeller does and exports them with Blender's own
# glTF exporter. Run from the repository root:
#
#   blender -b --factory-startup --python tests/data/blender/make_robots.py
#
# It writes, beside this script:
#   modelled_arm.gltf/.bin   base -> shoulder (empty) -> upper arm (mesh) -> elbow (empty, a child
#                            of the upper-arm mesh) -> forearm; pivots at the empties, primitives
#                            with their origins at their centres, custom properties exported
#   modelled_arm.glb         the same, as GLB
#   modelled_arm_no_extras.glb   the same with "Include > Custom Properties" off (the default)
#   modelled_bones.gltf/.bin an armature of three bones whose Bone properties make the joints (the
#                            last one bent and rolled, its axis the bone's Z), with a mesh rigidly
#                            skinned to it
#   modelled_arm_mm.glb      the arm modelled in millimetres (everything 1000 times too large)
#   modelled.json            what Blender itself says: each joint's pivot and axis in glTF's scene
#                            axes (glTF (x, y, z) = Blender (x, z, -y)), each link's volume from
#                            bmesh.calc_volume (world transform applied) and its mass
import json
import math
import os

import bmesh
import bpy
from mathutils import Matrix, Vector

HERE = os.path.dirname(os.path.abspath(__file__))


def to_gltf(v):
    return [v.x, v.z, -v.y]


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)
    for armature in list(bpy.data.armatures):
        bpy.data.armatures.remove(armature)


def place(obj, parent, world):
    """Parents obj without a parent-inverse (as glTF has none) and puts it at `world`."""
    obj.parent = parent
    obj.matrix_parent_inverse = Matrix.Identity(4)
    bpy.context.view_layer.update()
    obj.matrix_world = world
    bpy.context.view_layer.update()


def cube(name, size, world, parent=None):
    bpy.ops.mesh.primitive_cube_add(size=1.0)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.name = name
    obj.scale = size
    bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    place(obj, parent, world)
    return obj


def cylinder(name, radius, depth, world, parent=None):
    # Origin at the centre, as the menu leaves it.
    bpy.ops.mesh.primitive_cylinder_add(vertices=32, radius=radius, depth=depth)
    obj = bpy.context.active_object
    obj.name = name
    obj.data.name = name
    place(obj, parent, world)
    return obj


def empty(name, world, parent):
    obj = bpy.data.objects.new(name, None)
    bpy.context.scene.collection.objects.link(obj)
    place(obj, parent, world)
    return obj


def world_volume(obj):
    bm = bmesh.new()
    bm.from_mesh(obj.data)
    bm.transform(obj.matrix_world)
    volume = bm.calc_volume(signed=False)
    bm.free()
    return volume


def joint_record(obj, parent_link, child_link, axis_local):
    R = obj.matrix_world.to_3x3().normalized()
    axis_world = (R @ Vector(axis_local)).normalized()
    return {"name": obj.name, "parent": parent_link, "child": child_link,
            "pivot_scene": to_gltf(obj.matrix_world.translation),
            "axis_scene": to_gltf(axis_world)}


def build_arm(unit=1.0):
    """The arm of docs/blender.md. `unit` 1000 gives the millimetre mistake."""
    clear_scene()
    T = Matrix.Translation
    base = cube("base", (0.3 * unit, 0.3 * unit, 0.1 * unit), T((0, 0, 0.05 * unit)))
    base["rdtf_density"] = 2700.0
    # The shoulder turns about Blender's up (its own Z), 30 degrees turned about Z.
    shoulder_world = T((0, 0, 0.1 * unit)) @ Matrix.Rotation(math.radians(30), 4, "Z")
    shoulder = empty("shoulder", shoulder_world, base)
    shoulder["rdtf_joint"] = "revolute"
    shoulder["rdtf_axis"] = [0.0, 0.0, 1.0]
    shoulder["rdtf_lower"] = -1.5
    shoulder["rdtf_upper"] = 1.5
    shoulder["rdtf_effort"] = 20.0
    shoulder["rdtf_velocity"] = 2.0
    # The upper arm: a cylinder whose origin stays at its centre, 0.25 above the shoulder.
    upper = cylinder("upper_arm", 0.04 * unit, 0.5 * unit, shoulder_world @ T((0, 0, 0.25 * unit)), shoulder)
    # The elbow: an empty parented to the upper-arm mesh, at its top, tilted 20 degrees about its
    # own X; it turns about its own Y ("y" named, as Blender shows it).
    elbow_world = shoulder_world @ T((0, 0, 0.5 * unit)) @ Matrix.Rotation(math.radians(20), 4, "X")
    elbow = empty("elbow", elbow_world, upper)
    elbow["rdtf_joint"] = "revolute"
    elbow["rdtf_axis"] = "y"
    elbow["rdtf_lower"] = -2.0
    elbow["rdtf_upper"] = 2.0
    elbow["rdtf_damping"] = 0.1
    forearm = cylinder("forearm", 0.03 * unit, 0.4 * unit, elbow_world @ T((0, 0, 0.2 * unit)), elbow)
    forearm["rdtf_density"] = 1200.0
    links = {}
    for obj, density in ((base, 2700.0), (upper, 1000.0), (forearm, 1200.0)):
        volume = world_volume(obj)
        links[obj.name] = {"volume": volume, "density": density, "mass": volume * density}
    joints = [joint_record(shoulder, "base", "upper_arm", (0, 0, 1)),
              joint_record(elbow, "upper_arm", "forearm", (0, 1, 0))]
    return {"links": links, "joints": joints}


def build_bones():
    clear_scene()
    bpy.ops.object.armature_add(enter_editmode=True, location=(0, 0, 0))
    rig = bpy.context.active_object
    rig.name = "rig"
    bones = rig.data.edit_bones
    lower = bones[0]
    lower.name = "lower"
    lower.head = (0, 0, 0)
    lower.tail = (0, 0, 0.3)
    upper = bones.new("upper")
    upper.head = (0, 0, 0.3)
    upper.tail = (0, 0.3, 0.3)  # The upper bone points along Blender's Y.
    upper.parent = lower
    upper.use_connect = True
    # The hand bends away from both and is rolled: its axes are none of the armature's.
    hand = bones.new("hand")
    hand.head = (0, 0.3, 0.3)
    hand.tail = (0.15, 0.45, 0.4)
    hand.roll = math.radians(30)
    hand.parent = upper
    hand.use_connect = True
    bpy.ops.object.mode_set(mode="OBJECT")
    # Bone properties (not pose-bone ones: the exporter writes only these).
    bone = rig.data.bones["upper"]
    bone["rdtf_joint"] = "revolute"
    bone["rdtf_axis"] = "x"
    bone["rdtf_lower"] = -1.0
    bone["rdtf_upper"] = 1.0
    # A bone's Z, as Blender draws the bone's axes: Blender's exporter writes a bone's node in the
    # bone's own axes, not turned to glTF's as an object's are.
    rig.data.bones["hand"]["rdtf_joint"] = "revolute"
    rig.data.bones["hand"]["rdtf_axis"] = "z"
    hand_rest = rig.matrix_world @ rig.data.bones["hand"].matrix_local
    hand_length = (Vector((0.15, 0.45, 0.4)) - Vector((0, 0.3, 0.3))).length
    # Boxes in one mesh, each wholly bound to one bone.
    parts = [("lower", (0.1, 0.1, 0.3), Matrix.Translation((0, 0, 0.15))),
             ("upper", (0.08, 0.3, 0.08), Matrix.Translation((0, 0.15, 0.3))),
             ("hand", (0.06, hand_length, 0.04), hand_rest @ Matrix.Translation((0, hand_length / 2, 0)))]
    volumes = {}
    objects = []
    for bone_name, size, world in parts:
        obj = cube("part_" + bone_name, size, world)
        volumes[bone_name] = world_volume(obj)
        group = obj.vertex_groups.new(name=bone_name)
        group.add(list(range(len(obj.data.vertices))), 1.0, "REPLACE")
        objects.append(obj)
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = objects[0]
    bpy.ops.object.join()
    body = bpy.context.active_object
    body.name = "body"
    body.parent = rig
    modifier = body.modifiers.new("Armature", "ARMATURE")
    modifier.object = rig
    bpy.context.view_layer.update()
    links = {name: {"volume": v, "density": 1000.0, "mass": 1000.0 * v} for name, v in volumes.items()}
    # The joint between bones is named after both: "<parent bone>_<bone>_joint".
    joints = []
    for parent, child, axis in (("lower", "upper", (1, 0, 0)), ("upper", "hand", (0, 0, 1))):
        M = rig.matrix_world @ rig.data.bones[child].matrix_local
        axis_world = (M.to_3x3().normalized() @ Vector(axis)).normalized()
        joints.append({"name": parent + "_" + child + "_joint", "parent": parent, "child": child,
                       "pivot_scene": to_gltf(M.translation), "axis_scene": to_gltf(axis_world)})
    return {"links": links, "joints": joints}


def export(name, fmt, extras=True):
    path = os.path.join(HERE, name)
    bpy.ops.export_scene.gltf(filepath=path, export_format=fmt, export_extras=extras,
                              export_animations=False)


def main():
    record = {"generator": "Blender " + bpy.app.version_string}
    record["modelled_arm"] = build_arm()
    export("modelled_arm.gltf", "GLTF_SEPARATE")
    export("modelled_arm.glb", "GLB")
    export("modelled_arm_no_extras.glb", "GLB", extras=False)
    record["modelled_arm_mm"] = build_arm(unit=1000.0)
    export("modelled_arm_mm.glb", "GLB")
    record["modelled_bones"] = build_bones()
    export("modelled_bones.gltf", "GLTF_SEPARATE")
    with open(os.path.join(HERE, "modelled.json"), "w") as out:
        json.dump(record, out, indent=1, sort_keys=True)
        out.write("\n")


if __name__ == "__main__":
    main()
