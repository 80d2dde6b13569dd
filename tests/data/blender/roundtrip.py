# Blender's importer then its exporter on each file given, as a modeller re-opening rdtf's output
# does (custom properties exported):
#
#   blender -b --factory-startup --python tests/data/blender/roundtrip.py -- IN.glb OUT.glb [IN OUT ...]
import sys

# Debian 12's Blender 3.4 importer still uses numpy.bool, which numpy 1.24 removed.
import numpy
numpy.bool = bool

import bpy

args = sys.argv[sys.argv.index("--") + 1:]
if not args or len(args) % 2:
    sys.exit("usage: roundtrip.py -- IN OUT [IN OUT ...]")
for source, target in zip(args[0::2], args[1::2]):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=source)
    if result != {"FINISHED"}:
        sys.exit("import of " + source + " failed: " + str(result))
    result = bpy.ops.export_scene.gltf(filepath=target, export_format="GLB", export_extras=True,
                                       export_animations=False)
    if result != {"FINISHED"}:
        sys.exit("export to " + target + " failed: " + str(result))
    print("rdtf roundtrip:", source, "->", target)
