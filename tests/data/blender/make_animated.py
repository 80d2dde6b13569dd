# Builds make_robots.py's three-bone rig with an action, as a modeller who keyframes a pose does,
# and exports it with Blender's glTF exporter, animations on (its default). Run from the
# repository root:
#
#   blender -b --factory-startup --python tests/data/blender/make_animated.py
#
# It writes, beside this script:
#   idle_bones.glb    every bone keyframed at frames 1 and 30 in its rest pose: the action moves
#                     nothing (Blender writes a channel for each bone all the same)
#   waving_bones.glb  the same with the upper bone turned 60 degrees about its X at frame 30: only
#                     the upper bone moves, though Blender writes channels for all three
import math
import os
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import make_robots  # noqa: E402  (Blender's Python finds it beside this script)


def keyframe_rig(turn_upper):
    rig = bpy.data.objects["rig"]
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode="POSE")
    for bone in rig.pose.bones:
        bone.rotation_mode = "QUATERNION"
        bone.keyframe_insert("rotation_quaternion", frame=1)
        bone.keyframe_insert("location", frame=1)
    if turn_upper:
        rig.pose.bones["upper"].rotation_quaternion = (math.cos(math.radians(30)), math.sin(math.radians(30)), 0, 0)
    for bone in rig.pose.bones:
        bone.keyframe_insert("rotation_quaternion", frame=30)
        bone.keyframe_insert("location", frame=30)
    bpy.ops.object.mode_set(mode="OBJECT")
    bpy.context.scene.frame_set(1)


def export(name):
    bpy.ops.export_scene.gltf(filepath=os.path.join(HERE, name), export_format="GLB", export_extras=True,
                              export_animations=True)


def main():
    for name, turn in (("idle_bones.glb", False), ("waving_bones.glb", True)):
        make_robots.build_bones()
        keyframe_rig(turn)
        export(name)


if __name__ == "__main__":
    main()
