# Overlapping parts as modellers make them, exported with Blender's own glTF exporter. Run from the
# repository root:
#
#   blender -b --factory-startup --python tests/data/blender/make_overlap.py
#
# It writes, beside this script:
#   overlap_joined.glb  base: a cube 0.2 m on a side with a post (32-sided cylinder, radius 0.05,
#                       0.3 tall) standing in it, joined into one object (Ctrl+J); a hinge (an
#                       empty) on top; arm: a bar 0.1 x 0.1 x 0.4 with a motor (32-sided cylinder,
#                       radius 0.04, 0.12 long, across the bar) as a separate child object sunk
#                       into its lower end
#   overlap_union.glb   the same parts united with Boolean modifiers (Union, the Exact solver),
#                       applied, the cutters removed: what docs/blender.md asks for
#   overlap_skinned.glb two bones (a revolute joint between them); the lower bone's part is a box
#                       0.2 x 0.2 x 0.3 and a box 0.3 x 0.1 x 0.1 through it, joined, both wholly
#                       bound to that bone: a skinned mesh whose part overlaps itself
#   overlap.json        what Blender itself says of each link: the volume of the parts as exported
#                       (bmesh.calc_volume over the world-placed meshes, which counts the shared
#                       region twice as any signed-volume sum does) and of the Boolean union
import json
import math
import os

import bmesh
import bpy
from mathutils import Matrix

HERE = os.path.dirname(os.path.abspath(__file__))
T = Matrix.Translation


def clear_scene():
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj, do_unlink=True)
    for mesh in list(bpy.data.meshes):
        bpy.data.meshes.remove(mesh)


def place(obj, parent, world):
    obj.parent = parent
    obj.matrix_parent_inverse = Matrix.Identity(4)
    bpy.context.view_layer.update()
    obj.matrix_world = world
    bpy.context.view_layer.update()


def add(kind, name, world, parent=None, **size):
    if kind == "cube":
        bpy.ops.mesh.primitive_cube_add(size=1.0)
        obj = bpy.context.active_object
        obj.scale = size["scale"]
        bpy.ops.object.transform_apply(location=False, rotation=False, scale=True)
    else:
        bpy.ops.mesh.primitive_cylinder_add(vertices=32, radius=size["radius"], depth=size["depth"])
        obj = bpy.context.active_object
    obj.name = name
    obj.data.name = name
    place(obj, parent, world)
    return obj


def volume(objects):
    total = 0.0
    for obj in objects:
        bm = bmesh.new()
        bm.from_mesh(obj.data)
        bm.transform(obj.matrix_world)
        total += bm.calc_volume(signed=True)
        bm.free()
    return total


def select_only(objects, active):
    bpy.ops.object.select_all(action="DESELECT")
    for obj in objects:
        obj.select_set(True)
    bpy.context.view_layer.objects.active = active


def unite(target, cutter):
    modifier = target.modifiers.new("union", "BOOLEAN")
    modifier.operation = "UNION"
    modifier.solver = "EXACT"
    modifier.object = cutter
    select_only([target], target)
    bpy.ops.object.modifier_apply(modifier=modifier.name)
    bpy.data.objects.remove(cutter, do_unlink=True)


def build(united):
    """The robot; returns {link: [its mesh objects]} once the parts are joined or united."""
    clear_scene()
    base = add("cube", "base", T((0, 0, 0)), scale=(0.2, 0.2, 0.2))
    post = add("cylinder", "post", T((0, 0, 0.1)), radius=0.05, depth=0.3)
    if united:
        unite(base, post)
    else:
        select_only([base, post], base)
        bpy.ops.object.join()  # Ctrl+J: one mesh of two shells that overlap
    hinge = bpy.data.objects.new("hinge", None)
    bpy.context.scene.collection.objects.link(hinge)
    place(hinge, base, T((0, 0, 0.3)))
    hinge["rdtf_joint"] = "revolute"
    hinge["rdtf_axis"] = [1.0, 0.0, 0.0]
    hinge["rdtf_lower"] = -1.0
    hinge["rdtf_upper"] = 1.0
    arm = add("cube", "arm", T((0, 0, 0.5)), hinge, scale=(0.1, 0.1, 0.4))
    motor_world = T((0, 0, 0.35)) @ Matrix.Rotation(math.radians(90), 4, "Y")
    motor = add("cylinder", "arm_motor", motor_world, arm, radius=0.04, depth=0.12)
    if united:
        unite(arm, motor)
        return {"base": [base], "arm": [arm]}
    return {"base": [base], "arm": [arm, motor]}


def build_skinned():
    """Two bones; the lower one's part, joined from two boxes that cross, skinned to it."""
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
    upper.tail = (0, 0, 0.6)
    upper.parent = lower
    upper.use_connect = True
    bpy.ops.object.mode_set(mode="OBJECT")
    bone = rig.data.bones["upper"]
    bone["rdtf_joint"] = "revolute"
    bone["rdtf_axis"] = "x"
    bone["rdtf_lower"] = -1.0
    bone["rdtf_upper"] = 1.0
    parts = [("lower", add("cube", "post", T((0, 0, 0.15)), scale=(0.2, 0.2, 0.3))),
             ("lower", add("cube", "bar", T((0, 0, 0.15)), scale=(0.3, 0.1, 0.1))),
             ("upper", add("cube", "top", T((0, 0, 0.45)), scale=(0.1, 0.1, 0.3)))]
    for bone_name, obj in parts:
        group = obj.vertex_groups.new(name=bone_name)
        group.add(list(range(len(obj.data.vertices))), 1.0, "REPLACE")
    objects = [obj for _, obj in parts]
    lower_parts = volume(objects[:2])
    select_only(objects, objects[0])
    bpy.ops.object.join()
    body = bpy.context.active_object
    body.name = "body"
    body.parent = rig
    modifier = body.modifiers.new("Armature", "ARMATURE")
    modifier.object = rig
    bpy.context.view_layer.update()
    # The union of the lower bone's two boxes, by the Exact Boolean solver as for the others.
    post = add("cube", "post_u", T((0, 0, 0.15)), scale=(0.2, 0.2, 0.3))
    bar = add("cube", "bar_u", T((0, 0, 0.15)), scale=(0.3, 0.1, 0.1))
    unite(post, bar)
    united = volume([post])
    bpy.data.objects.remove(post, do_unlink=True)
    return {"lower": lower_parts}, {"lower": united}


def export(name):
    bpy.ops.export_scene.gltf(filepath=os.path.join(HERE, name), export_format="GLB", export_extras=True,
                              export_apply=True, export_animations=False)


def main():
    record = {"generator": "Blender " + bpy.app.version_string}
    joined = build(united=False)
    record["joined"] = {link: volume(objects) for link, objects in joined.items()}
    export("overlap_joined.glb")
    united = build(united=True)
    record["union"] = {link: volume(objects) for link, objects in united.items()}
    export("overlap_union.glb")
    record["skinned_joined"], record["skinned_union"] = build_skinned()
    export("overlap_skinned.glb")
    with open(os.path.join(HERE, "overlap.json"), "w") as out:
        json.dump(record, out, indent=1, sort_keys=True)
        out.write("\n")


main()
