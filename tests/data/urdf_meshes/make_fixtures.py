# Makes the URDF-mesh fixtures with Blender 3.4's own COLLADA and OBJ exporters. Run:
#
#   blender -b --factory-startup --python make_fixtures.py
#
# It writes, beside this script (robot.urdf and expected.json are not written by it):
#   box_mm.dae      scene unit millimetres (<unit meter="0.001">, Z_UP); one box object
#                   (location, 90 deg about Z, scale 2 1 0.5), top face "Red", the rest "Grey";
#                   quads kept (polylist, triangulate=False)
#   box_yup.dae     box_mm.dae with only <up_axis>Z_UP</up_axis> replaced by Y_UP
#   nested.dae      metres; empty "arm_root" (location, 90 deg about Z, scale 0.5) -> "box_a"
#                   (mesh "shared_box") -> "box_b" (linked duplicate: the same mesh data);
#                   faces "Blue", bottom "Green"; triangles (triangulate=True)
#   box.obj/.mtl    a box at (0.2, -0.1, 0.05) m, top "Orange", the rest "Steel", exported by the
#                   legacy exporter with axis_forward='Y', axis_up='Z' (coordinates as in Blender)
#   open_plane.dae  one open quad (0.4 x 0.2 m at z = 0.05 m), "Yellow"
#   blender_reference.json  Blender's own world-space numbers (matrix_world @ v.co times the
#                   unit scale): a cross-check of expected.json
import json
import math
import os

import bpy
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))

# Blender's COLLADA writer (OpenCOLLADA) prints mesh coordinates below 0.1 inexactly (0.05 is
# written 0.04999995, 0.025 as 0.02499997) unless they are dyadic (0.0625): the sizes below are
# chosen so that the files hold exactly the intended numbers. Node matrices are printed with six
# significant digits (cos 90 deg as -4.37114e-8).

# Outward (counter-clockwise seen from outside) quads of a box with corners 0..7:
# 0 (-,-,-) 1 (+,-,-) 2 (+,+,-) 3 (-,+,-) 4 (-,-,+) 5 (+,-,+) 6 (+,+,+) 7 (-,+,+)
BOX_FACES = [(0, 3, 2, 1),  # bottom, -z
             (4, 5, 6, 7),  # top, +z
             (0, 1, 5, 4),  # -y
             (2, 3, 7, 6),  # +y
             (0, 4, 7, 3),  # -x
             (1, 2, 6, 5)]  # +x
BOTTOM, TOP = 0, 1


def reset(scale_length=1.0):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    units = bpy.context.scene.unit_settings
    units.system = 'METRIC'
    units.scale_length = scale_length
    if scale_length == 0.001:
        units.length_unit = 'MILLIMETERS'


def material(name, rgba):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    mat.node_tree.nodes["Principled BSDF"].inputs["Base Color"].default_value = rgba
    mat.diffuse_color = rgba  # the viewport colour, the same
    return mat


def box_mesh(name, half, mats, face_material):
    hx, hy, hz = half
    verts = [(-hx, -hy, -hz), (hx, -hy, -hz), (hx, hy, -hz), (-hx, hy, -hz),
             (-hx, -hy, hz), (hx, -hy, hz), (hx, hy, hz), (-hx, hy, hz)]
    mesh = bpy.data.meshes.new(name)
    mesh.from_pydata(verts, [], BOX_FACES)
    for m in mats:
        mesh.materials.append(m)
    for i, poly in enumerate(mesh.polygons):
        poly.material_index = face_material(i)
    mesh.update()
    assert not mesh.validate()
    return mesh


def new_object(name, data, location=(0, 0, 0), rotation=(0, 0, 0), scale=(1, 1, 1), parent=None):
    obj = bpy.data.objects.new(name, data)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    obj.rotation_euler = rotation
    obj.scale = scale
    if parent is not None:
        obj.parent = parent  # matrix_parent_inverse stays the identity
    return obj


def reference(scale_length):
    """Blender's own numbers: world-space triangles (matrix_world @ v.co, times the unit scale)."""
    bpy.context.view_layer.update()
    tris, mats = [], {}
    for obj in bpy.context.scene.objects:
        if obj.type != 'MESH':
            continue
        mw = obj.matrix_world
        mesh = obj.data
        for poly in mesh.polygons:
            pts = [(mw @ mesh.vertices[i].co) * scale_length for i in poly.vertices]
            name = mesh.materials[poly.material_index].name
            for k in range(1, len(pts) - 1):
                tris.append((pts[0], pts[k], pts[k + 1]))
                mats[name] = mats.get(name, 0) + 1
    lo = [min(p[i] for t in tris for p in t) for i in range(3)]
    hi = [max(p[i] for t in tris for p in t) for i in range(3)]
    vol, mom = 0.0, [0.0, 0.0, 0.0]
    for a, b, c in tris:
        v = a.dot(b.cross(c)) / 6.0
        vol += v
        for i in range(3):
            mom[i] += v * (a[i] + b[i] + c[i]) / 4.0
    return {"triangles": len(tris), "min": lo, "max": hi, "volume": vol,
            "centroid": [m / vol for m in mom] if abs(vol) > 1e-12 else None,
            "material_triangles": mats}


refs = {}

# 1. box_mm.dae: millimetres, quads
reset(0.001)
red = material("Red", (0.8, 0.05, 0.05, 1.0))
grey = material("Grey", (0.5, 0.5, 0.5, 1.0))
mesh = box_mesh("box_mm", (25.0, 15.0, 10.0), [grey, red], lambda i: 1 if i == TOP else 0)
new_object("box_mm", mesh, location=(100.0, 50.0, 30.0), rotation=(0, 0, math.radians(90)),
           scale=(2.0, 1.0, 0.5))
refs["box_mm.dae"] = reference(0.001)
refs["box_yup.dae"] = refs["box_mm.dae"]
path = os.path.join(HERE, "box_mm.dae")
bpy.ops.wm.collada_export(filepath=path, triangulate=False)

# 2. box_yup.dae: the same text with only the up axis changed
with open(path) as f:
    text = f.read()
assert text.count("<up_axis>Z_UP</up_axis>") == 1
with open(os.path.join(HERE, "box_yup.dae"), "w") as f:
    f.write(text.replace("<up_axis>Z_UP</up_axis>", "<up_axis>Y_UP</up_axis>"))

# 3. nested.dae: metres, a chain of three nodes, one mesh used twice, triangles
reset(1.0)
blue = material("Blue", (0.1, 0.2, 0.9, 1.0))
green = material("Green", (0.1, 0.7, 0.2, 1.0))
shared = box_mesh("shared_box", (0.2, 0.1, 0.125), [blue, green],
                  lambda i: 1 if i == BOTTOM else 0)
root = new_object("arm_root", None, location=(0.5, 0.0, 0.25), rotation=(0, 0, math.radians(90)),
                  scale=(0.5, 0.5, 0.5))
box_a = new_object("box_a", shared, location=(0.4, 0.0, 0.0), rotation=(math.radians(90), 0, 0),
                   parent=root)
box_b = new_object("box_b", shared, location=(0.0, 0.4, 0.0), rotation=(0, math.radians(90), 0),
                   scale=(1.0, 2.0, 1.0), parent=box_a)  # Alt+D: box_b.data is box_a.data
assert box_b.data is box_a.data
refs["nested.dae"] = reference(1.0)
bpy.ops.wm.collada_export(filepath=os.path.join(HERE, "nested.dae"), triangulate=True)

# 4. box.obj + box.mtl: metres as written, quads
reset(1.0)
orange = material("Orange", (1.0, 0.5, 0.0, 1.0))
steel = material("Steel", (0.6, 0.6, 0.65, 1.0))
mesh = box_mesh("box", (0.05, 0.04, 0.03), [steel, orange], lambda i: 1 if i == TOP else 0)
new_object("box", mesh, location=(0.2, -0.1, 0.05))
refs["box.obj"] = reference(1.0)
bpy.ops.export_scene.obj(filepath=os.path.join(HERE, "box.obj"), use_materials=True,
                         axis_forward='Y', axis_up='Z')

# 5. open_plane.dae: one open quad
reset(1.0)
yellow = material("Yellow", (0.9, 0.8, 0.1, 1.0))
mesh = bpy.data.meshes.new("plane")
mesh.from_pydata([(-0.2, -0.1, 0.0), (0.2, -0.1, 0.0), (0.2, 0.1, 0.0), (-0.2, 0.1, 0.0)],
                 [], [(0, 1, 2, 3)])
mesh.materials.append(yellow)
mesh.update()
new_object("open_plane", mesh, location=(0.0, 0.0, 0.05))
refs["open_plane.dae"] = reference(1.0)
bpy.ops.wm.collada_export(filepath=os.path.join(HERE, "open_plane.dae"), triangulate=False)

with open(os.path.join(HERE, "blender_reference.json"), "w") as f:
    json.dump(refs, f, indent=1, default=list)
