#!/usr/bin/env bash
# Rebuilds the encoded fixtures of this folder with the real encoders, pinned in
# tools/encoders/package.json (npm gltfpack 1.3.0, gltf-pipeline 4.3.1; `bash
# scripts/install-deps.sh` installs them) and Debian's `draco` 1.5.5 (draco_transcoder).
# Run from anywhere; writes only into this folder. The outputs are committed: the tests read them
# and never run the encoders.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
root=$(cd "$here/../../.." && pwd)
bin=${RDTF_ENCODERS_BIN:-$root/tools/encoders/node_modules/.bin}
cd "$here"

# A copy of a Blender fixture (tests/data/blender/NAME.gltf) as NAME_source.gltf with
# "rdtf_axes": "blender" beside each rdtf_axis. Encoders replace asset.generator, which is how rdtf
# tells Blender's axes otherwise (docs/format.md, Node extras); the robot is the fixture's.
source_of() {
  python3 - "$root/tests/data/blender/$1.gltf" "$2" <<'PY'
import json, shutil, sys
source, name = sys.argv[1], sys.argv[2]
document = json.load(open(source))
for node in document["nodes"]:
    extras = node.get("extras", {})
    if "rdtf_axis" in extras:
        extras["rdtf_axes"] = "blender"
document["buffers"][0]["uri"] = name + ".bin"
json.dump(document, open(name + ".gltf", "w"), indent=1)
shutil.copy(source.replace(".gltf", ".bin"), name + ".bin")
PY
}

source_of modelled_arm arm_source

# gltfpack, keeping named nodes and extras: KHR_mesh_quantization, each mesh moved into a new
# child node that carries the dequantization transform.
"$bin/gltfpack" -i arm_source.gltf -o arm_gltfpack.gltf -kn -ke
# The same with EXT_meshopt_compression (-cc), as a GLB.
"$bin/gltfpack" -i arm_source.gltf -o arm_meshopt.glb -kn -ke -cc
# gltf-pipeline's Draco (default quantization: 11 bits for positions), buffers embedded.
"$bin/gltf-pipeline" -i arm_source.gltf -o arm_draco.gltf -d
# The same with the uncompressed data kept beside it for readers without Draco (the extension is
# then used, not required, and each accessor keeps a bufferView). gltf-pipeline 4.3.1 writes this
# wrong where meshes share an accessor (arm_source's forearm and upper_arm share their index
# list): arm_draco_fallback_shared.gltf, which rdtf refuses. arm_unshared_source.gltf is
# arm_source.gltf with that accessor copied for the second mesh (python3 -c 'import json;
# d=json.load(open("arm_source.gltf")); ... append a copy of accessor 3 and point
# meshes[1].primitives[0].indices at it'), the same robot.
"$bin/gltf-pipeline" -i arm_unshared_source.gltf -o arm_draco_fallback.gltf -d --draco.uncompressedFallback
"$bin/gltf-pipeline" -i arm_source.gltf -o arm_draco_fallback_shared.gltf -d --draco.uncompressedFallback
# draco_transcoder (Debian draco), default quantization (11 bits for positions); it drops extras.
draco_transcoder -i arm_source.gltf -o arm_draco_transcoder.gltf
# arm3: parts as named leaf mesh nodes under empties (Blender's "empty holding meshes" link).
# gltfpack moves each mesh into a carrier under its named node, which must stay a mesh node.
source_of arm3 arm3_source
"$bin/gltfpack" -i arm3_source.gltf -o arm3_gltfpack.glb -kn -ke

# rdtf's own output of Blender's modelled_arm (as exported: no rdtf_axes), through gltfpack,
# which drops extras.RDTF and replaces asset.generator: the node extras alone must keep the
# robot, axes included. Needs a built rdtf (RDTF, else build/clients/rdtf/rdtf).
rdtf=${RDTF:-$root/build/clients/rdtf/rdtf}
"$rdtf" convert "$root/tests/data/blender/modelled_arm.gltf" -o "$here/arm_rdtf_output.glb"
"$bin/gltfpack" -i arm_rdtf_output.glb -o arm_rdtf_gltfpack.glb -kn -ke
rm arm_rdtf_output.glb

# A unit cube with texture coordinates as a bare Draco stream (Debian draco's draco_encoder,
# defaults: edgebreaker, the portable texture-coordinate prediction); fuzz/make_decoder_seeds.py
# makes the draco fuzz seed and the regression inputs of the orientation bound from it.
draco_encoder -i cube_texcoords.obj -o cube_texcoords.drc >/dev/null

# A skinned mesh (Blender's skinned_arm, three bones): gltfpack moves the mesh and its skin into an
# unnamed carrier under the named node, which must stay the mesh node (no link of its own).
"$bin/gltfpack" -i "$root/tests/data/blender/skinned_arm.gltf" -o skinned_gltfpack.glb -kn -ke -cc

# glTF-Transform's quantize (npm @gltf-transform/cli 4.5.1; not pinned in tools/encoders: its
# package pulls sharp, whose native binary does not come from npm) folds a leaf part's
# dequantization into the part's node, moving its origin and a joint the part carries itself
# (JOINT_ORIGIN_QUANTIZED); rdtf's own output keeps its joints. Made by hand, when it is at hand:
if command -v gltf-transform >/dev/null; then
  gltf-transform quantize leaf_joint_source.gltf leaf_joint_gltf_transform_quantize.glb
  "$root/build/clients/rdtf/rdtf" convert leaf_joint_source.gltf -o /tmp/leaf_joint_rdtf.gltf
  gltf-transform quantize /tmp/leaf_joint_rdtf.gltf leaf_joint_rdtf_gltf_transform_quantize.glb
fi
# leaf_joint_on_empty_gltf_transform_quantize.glb: leaf_joint_gltf_transform_quantize.glb edited by
# hand (a review's repro): the forearm's joint keys moved to a new empty 'elbow' at (0.15, 0.5, 0)
# holding the forearm, so the joint turns about the empty.
