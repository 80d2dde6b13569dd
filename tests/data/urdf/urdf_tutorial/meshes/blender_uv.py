"""Blender as the independent judge of import's texture coordinates (blender -b --python).

Usage: blender -b --factory-startup --python blender_uv.py -- OUT.json IMPORTED.gltf FILE.dae:MESH ...

For each COLLADA file, Blender's own COLLADA importer reads it into an empty scene, and its glTF
importer reads the mesh MESH of rdtf's IMPORTED.gltf. Every triangle corner of each is described
by (u, v, r): its texture coordinate in Blender's convention (v up, as COLLADA writes it; Blender's
glTF importer turns glTF's v back) and its distance from the centroid of the mesh's distinct
positions, which no rigid motion changes (Blender turns a Y_UP file, import ignores up_axis, and
the link carries the mesh). The corners are matched one to one within `tolerance` in u, v and r;
OUT.json gets, per file, the corner counts, how many of Blender's found no match, and the images
the materials sample.
"""
import json
import sys

# Debian 12's Blender 3.4 glTF importer still uses numpy.bool, which numpy 1.24 removed.
import numpy
numpy.bool = bool

import bpy
from mathutils import Vector

TOLERANCE = 1e-6  # float32 texture coordinates and positions of about 0.1 m: a few ulp.


def clear():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def corners(objects):
    out = []
    for ob in objects:
        me = ob.data
        me.calc_loop_triangles()
        uv = me.uv_layers.active.data if me.uv_layers.active else None
        world = [ob.matrix_world @ v.co for v in me.vertices]
        for tri in me.loop_triangles:
            for loop, vertex in zip(tri.loops, tri.vertices):
                u, v = (uv[loop].uv[0], uv[loop].uv[1]) if uv else (float('nan'), float('nan'))
                out.append((u, v, world[vertex]))
    distinct = {}
    for _, _, p in out:
        distinct[(round(p.x, 7), round(p.y, 7), round(p.z, 7))] = p
    centre = sum(distinct.values(), Vector()) / len(distinct)
    return [(u, v, (p - centre).length) for u, v, p in out]


def images(objects):
    names = set()
    for ob in objects:
        for slot in ob.material_slots:
            if slot.material and slot.material.use_nodes:
                for node in slot.material.node_tree.nodes:
                    if node.type == 'TEX_IMAGE' and node.image:
                        names.add(bpy.path.basename(node.image.filepath) or node.image.name)
    return sorted(names)


def unmatched(reference, candidate):
    cell = 1e-3
    grid = {}
    for i, (u, v, r) in enumerate(candidate):
        grid.setdefault((round(u / cell), round(v / cell)), []).append(i)
    used = [False] * len(candidate)
    missing = 0
    for u, v, r in reference:
        cu, cv = round(u / cell), round(v / cell)
        found = False
        for du in (-1, 0, 1):
            for dv in (-1, 0, 1):
                for i in grid.get((cu + du, cv + dv), []):
                    if used[i]:
                        continue
                    cu2, cv2, cr2 = candidate[i]
                    if abs(cu2 - u) <= TOLERANCE and abs(cv2 - v) <= TOLERANCE and abs(cr2 - r) <= TOLERANCE:
                        used[i] = found = True
                        break
                if found:
                    break
            if found:
                break
        missing += 0 if found else 1
    return missing


def main():
    argv = sys.argv[sys.argv.index('--') + 1:]
    out_path, gltf = argv[0], argv[1]
    report = {}
    for pair in argv[2:]:
        dae, mesh_name = pair.rsplit(':', 1)
        clear()
        if bpy.ops.wm.collada_import(filepath=dae) != {'FINISHED'}:
            sys.exit('Blender could not import ' + dae)
        theirs = [ob for ob in bpy.context.scene.objects if ob.type == 'MESH']
        reference, reference_images = corners(theirs), images(theirs)
        clear()
        if bpy.ops.import_scene.gltf(filepath=gltf) != {'FINISHED'}:
            sys.exit('Blender could not import ' + gltf)
        ours = [ob for ob in bpy.context.scene.objects if ob.type == 'MESH' and ob.data.name == mesh_name]
        if not ours:
            report[dae] = {'error': 'no mesh named ' + mesh_name}
            continue
        candidate = corners(ours[:1])
        report[dae] = {
            'blender_corners': len(reference),
            'rdtf_corners': len(candidate),
            'unmatched': unmatched(reference, candidate),
            'blender_images': reference_images,
            'rdtf_images': images(ours[:1]),
        }
    with open(out_path, 'w') as f:
        json.dump(report, f, indent=1)


main()
