// Generates minimal .gltf files (data: URI buffers) probing ACCESSOR_USAGE_OVERRIDE,
// BUFFER_VIEW_TARGET_OVERRIDE and ACCESSOR_MATRIX_ALIGNMENT.
import fs from 'node:fs';

// Run from anywhere: node tests/data/gltf-usage/make_models.mjs (writes beside this script).
const dir = new URL('.', import.meta.url).pathname;
const f32 = (a) => Buffer.from(new Float32Array(a).buffer);
const u16 = (a) => Buffer.from(new Uint16Array(a).buffer);
const u8 = (a) => Buffer.from(Uint8Array.from(a));
const pad4 = (b) => (b.length % 4 ? Buffer.concat([b, Buffer.alloc(4 - (b.length % 4))]) : b);
const uri = (b) => 'data:application/octet-stream;base64,' + b.toString('base64');

// Unit-length triangle (so the same accessor can also be a NORMAL).
const POS = f32([1, 0, 0, 0, 1, 0, 0, 0, 1]); // 36 bytes
const POS_MIN = [0, 0, 0], POS_MAX = [1, 1, 1];
const IDX = pad4(u16([0, 1, 2])); // 6 bytes + 2 pad
const ID4 = f32([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]); // 64 bytes, identity MAT4
const asset = { version: '2.0' };

function write(name, gltf) {
  fs.writeFileSync(`${dir}/${name}.gltf`, JSON.stringify(gltf, null, 1) + '\n');
}

// Helper: one buffer made of the given chunks, one bufferView per chunk.
function views(chunks, targets = []) {
  const bin = Buffer.concat(chunks.map(pad4));
  let off = 0;
  const bvs = chunks.map((c, i) => {
    const bv = { buffer: 0, byteOffset: off, byteLength: c.length };
    if (targets[i] != null) bv.target = targets[i];
    off += pad4(c).length;
    return bv;
  });
  if (bvs[0].byteOffset === 0) for (const bv of bvs) if (bv.byteOffset === 0) delete bv.byteOffset;
  return { buffers: [{ byteLength: bin.length, uri: uri(bin) }], bufferViews: bvs };
}
const posAcc = (bv, extra = {}) => ({ bufferView: bv, componentType: 5126, count: 3, type: 'VEC3', min: POS_MIN, max: POS_MAX, ...extra });
const idxAcc = (bv, extra = {}) => ({ bufferView: bv, componentType: 5123, count: 3, type: 'SCALAR', ...extra });
const scene = { scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }] };

// 00 baseline: valid indexed triangle, targets set
write('00_baseline', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])], [34962, 34963]) });

// 01 same accessor as indices and as a custom vertex attribute (_ID): attribute first (JSON order), indices second
write('01_usage_attr_then_indices', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0, _ID: 1 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])], [34962]) });

// 02 same as 01 but accessor 1 has no bufferView (so no bufferView usage at all)
write('02_usage_attr_then_indices_no_bv', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0, _ID: 1 }, indices: 1 }] }],
  accessors: [posAcc(0), { componentType: 5123, count: 3, type: 'SCALAR' }], ...views([POS], [34962]) });

// 03 indices in primitive 0, attribute in primitive 1 (order across primitives)
write('03_usage_indices_then_attr_other_prim', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }, { attributes: { POSITION: 0, _ID: 1 } }] }],
  accessors: [posAcc(0), { componentType: 5123, count: 3, type: 'SCALAR' }], ...views([POS], [34962]) });

// 04 POSITION and NORMAL share one accessor
write('04_position_normal_shared', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0, NORMAL: 0 } }] }],
  accessors: [posAcc(0)], ...views([POS], [34962]) });

// 05 base POSITION and morph-target POSITION share one accessor
write('05_position_and_target_position_shared', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, targets: [{ POSITION: 0 }] }] }],
  accessors: [posAcc(0)], ...views([POS], [34962]) });

// 06 accessor used as a vertex attribute (_T) and as an animation sampler input (output has its own bufferView)
{
  const T = f32([0, 1, 2]);
  write('06_usage_attr_then_anim_input', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0, _T: 1 } }] }],
    animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'translation' } }],
      samplers: [{ input: 1, output: 2 }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 3, type: 'SCALAR', min: [0], max: [2] },
      { bufferView: 2, componentType: 5126, count: 3, type: 'VEC3' }],
    ...views([POS, T, f32([0, 0, 0, 1, 1, 1, 2, 2, 2])], [34962]) });
  // 06b the POSITION accessor (bufferView target ARRAY_BUFFER) reused as a translation output
  write('06b_usage_position_reused_as_anim_output', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
    animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'translation' } }],
      samplers: [{ input: 1, output: 0 }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 3, type: 'SCALAR', min: [0], max: [2] }],
    ...views([POS, T], [34962]) });
}

// 07 same accessor as animation input and output (weights, 1 morph target)
{
  const T = f32([0, 1]);
  write('07_usage_anim_input_and_output', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 }, targets: [{ POSITION: 0 }] }] }],
    animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'weights' } }],
      samplers: [{ input: 1, output: 1 }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 2, type: 'SCALAR', min: [0], max: [1] }],
    ...views([POS, T], [34962]) });
}

// 08 IBM accessor also used as a custom MAT4 vertex attribute (_M) -- vertex count 1 (points)
write('08_usage_attr_then_ibm', { asset, scene: 0, scenes: [{ nodes: [0] }],
  nodes: [{ mesh: 0 }, {}],
  skins: [{ joints: [1], inverseBindMatrices: 1 }],
  meshes: [{ primitives: [{ attributes: { POSITION: 0, _M: 1 }, mode: 0 }] }],
  accessors: [{ bufferView: 0, componentType: 5126, count: 1, type: 'VEC3', min: [1, 0, 0], max: [1, 0, 0] },
    { bufferView: 1, componentType: 5126, count: 1, type: 'MAT4' }],
  ...views([f32([1, 0, 0]), ID4], [34962]) });

// 09 accessor used as attribute, then indices in prim 0, then IBM: Initial stays the first usage
write('09_usage_three_uses', { asset, scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }, {}],
  skins: [{ joints: [1], inverseBindMatrices: 1 }],
  meshes: [{ primitives: [{ attributes: { POSITION: 0, _ID: 1 }, indices: 1 }, { attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), { componentType: 5123, count: 3, type: 'SCALAR' }], ...views([POS], [34962]) });

// 10 bufferView target ARRAY_BUFFER used by an indices accessor
write('10_bv_target_array_used_by_indices', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])], [34962, 34962]) });

// 11 bufferView target ELEMENT_ARRAY_BUFFER used by POSITION
write('11_bv_target_element_used_by_position', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])], [34963, 34963]) });

// 12 one bufferView (no target) holds both POSITION and indices
{
  const bin = Buffer.concat([POS, u16([0, 1, 2])]);
  write('12_bv_no_target_position_and_indices', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
    accessors: [posAcc(0), idxAcc(0, { byteOffset: 36 })],
    buffers: [{ byteLength: bin.length, uri: uri(bin) }], bufferViews: [{ buffer: 0, byteLength: bin.length }] });
}

// 13 bufferView (target ARRAY_BUFFER) referenced by an image and by POSITION
write('13_bv_target_array_image_and_position', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
  images: [{ bufferView: 0, mimeType: 'image/png' }],
  accessors: [posAcc(0)], ...views([POS], [34962]) });

// 14 bufferView (no target) referenced by an image and by POSITION
write('14_bv_no_target_image_and_position', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
  images: [{ bufferView: 0, mimeType: 'image/png' }],
  accessors: [posAcc(0)], ...views([POS]) });

// 15 animation sampler input/output bufferViews with target ARRAY_BUFFER
write('15_bv_target_array_anim_input_output', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
  animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'translation' } }],
    samplers: [{ input: 1, output: 2 }] }],
  accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 1, type: 'SCALAR', min: [0], max: [0] },
    { bufferView: 2, componentType: 5126, count: 1, type: 'VEC3' }],
  ...views([POS, f32([0]), f32([1, 2, 3])], [34962, 34962, 34962]) });

// 16 skin IBM bufferView with target ARRAY_BUFFER
write('16_bv_target_array_ibm', { asset, scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }, {}],
  skins: [{ joints: [1], inverseBindMatrices: 1 }],
  meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
  accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 1, type: 'MAT4' }],
  ...views([POS, ID4], [34962, 34962]) });

// 17 one bufferView shared by an IBM accessor and an animation input accessor (no targets)
{
  const bin = Buffer.concat([ID4, f32([0])]);
  write('17_bv_ibm_and_anim_input', { asset, scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }, {}],
    skins: [{ joints: [1], inverseBindMatrices: 1 }],
    meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
    animations: [{ channels: [{ sampler: 0, target: { node: 1, path: 'translation' } }], samplers: [{ input: 2, output: 3 }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 1, type: 'MAT4' },
      { bufferView: 1, byteOffset: 64, componentType: 5126, count: 1, type: 'SCALAR', min: [0], max: [0] },
      { bufferView: 2, componentType: 5126, count: 1, type: 'VEC3' }],
    buffers: [{ byteLength: 36 + 68 + 12, uri: uri(Buffer.concat([POS, bin, f32([1, 2, 3])])) }],
    bufferViews: [{ buffer: 0, byteLength: 36, target: 34962 }, { buffer: 0, byteOffset: 36, byteLength: 68 },
      { buffer: 0, byteOffset: 104, byteLength: 12 }] });
}

// 18 sparse accessor whose indices/values bufferViews have targets
{
  const bin = Buffer.concat([POS, pad4(u16([1])), f32([0, 1, 0])]);
  write('18_bv_target_sparse', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
    accessors: [posAcc(0, { sparse: { count: 1, indices: { bufferView: 1, componentType: 5123 }, values: { bufferView: 2 } } })],
    buffers: [{ byteLength: bin.length, uri: uri(bin) }],
    bufferViews: [{ buffer: 0, byteLength: 36, target: 34962 }, { buffer: 0, byteOffset: 36, byteLength: 2, target: 34963 },
      { buffer: 0, byteOffset: 40, byteLength: 12, target: 34962 }] });
}

// 19 POSITION bufferView without target (only hint)
write('19_bv_no_target_hint_only', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])]) });

// Matrix alignment probes (unused accessors; one buffer of 64 bytes)
const mat = (name, accs, bvExtra = {}) => {
  const bin = Buffer.alloc(128);
  write(name, { asset, accessors: accs, buffers: [{ byteLength: 128, uri: uri(bin) }],
    bufferViews: [{ buffer: 0, byteLength: 128, ...bvExtra }] });
};
mat('20_mat4_float_offset2', [{ bufferView: 0, byteOffset: 2, componentType: 5126, count: 1, type: 'MAT4' }]);
mat('21_mat2_ubyte_offset2', [{ bufferView: 0, byteOffset: 2, componentType: 5121, count: 1, type: 'MAT2' }]);
mat('22_mat3_ushort_offset6', [{ bufferView: 0, byteOffset: 6, componentType: 5123, count: 1, type: 'MAT3' }]);
mat('23_mat2_ubyte_offset4_ok', [{ bufferView: 0, byteOffset: 4, componentType: 5121, count: 1, type: 'MAT2' }]);
mat('24_mat2_ubyte_bv_offset2', [{ bufferView: 0, componentType: 5121, count: 1, type: 'MAT2' }], { byteOffset: 2, byteLength: 120 });
mat('25_vec4_ubyte_offset2_no_matrix', [{ bufferView: 0, byteOffset: 2, componentType: 5121, count: 1, type: 'VEC4' }]);
mat('26_mat4_float_no_bufferview_offset2', [{ byteOffset: 2, componentType: 5126, count: 1, type: 'MAT4' }]);
mat('27_mat2_ubyte_offset_negative', [{ bufferView: 0, byteOffset: -2, componentType: 5121, count: 1, type: 'MAT2' }]);
mat('28_mat2_ubyte_offset1', [{ bufferView: 0, byteOffset: 1, componentType: 5121, count: 1, type: 'MAT2' }]);
mat('29_mat2_ubyte_stride_6', [{ bufferView: 0, componentType: 5121, count: 2, type: 'MAT2' }], { byteStride: 6 });
mat('30_mat2_ubyte_offset_fractional', [{ bufferView: 0, byteOffset: 2.5, componentType: 5121, count: 1, type: 'MAT2' }]);
mat('33_mat4_float_offset4_ok', [{ bufferView: 0, byteOffset: 4, componentType: 5126, count: 1, type: 'MAT4' }]);

// 31 order inside one primitive: attributes, then indices, then targets
write('31_usage_order_attributes_indices_targets', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0, _ID: 2 }, indices: 1, targets: [{ _ID: 1 }] }] }],
  accessors: [posAcc(0), { componentType: 5123, count: 3, type: 'SCALAR' }, { componentType: 5123, count: 3, type: 'SCALAR' }],
  ...views([POS], [34962]) });

// 32 animation input and output accessors share one bufferView (no target): both 'Other', no error
{
  const bin = Buffer.concat([POS, f32([0, 1, 2, 3])]);
  write('32_bv_anim_input_output_shared_ok', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
    animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'translation' } }], samplers: [{ input: 1, output: 2 }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 1, type: 'SCALAR', min: [0], max: [0] },
      { bufferView: 1, byteOffset: 4, componentType: 5126, count: 1, type: 'VEC3' }],
    buffers: [{ byteLength: bin.length, uri: uri(bin) }],
    bufferViews: [{ buffer: 0, byteLength: 36, target: 34962 }, { buffer: 0, byteOffset: 36, byteLength: 16 }] });
}

// 34 the same override met twice via two meshes: one error per conflicting reference, Initial unchanged
write('34_bv_override_per_reference', { asset, scene: 0, scenes: [{ nodes: [0, 1] }], nodes: [{ mesh: 0 }, { mesh: 1 }],
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }, { primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])], [34962, 34962]) });


// 01b like 02 but "indices" precedes "attributes" in the JSON text: visiting order is fixed, not JSON order
write('01b_usage_indices_key_first', { asset, ...scene,
  meshes: [{ primitives: [{ indices: 1, attributes: { POSITION: 0, _ID: 1 } }] }],
  accessors: [posAcc(0), { componentType: 5123, count: 3, type: 'SCALAR' }], ...views([POS], [34962]) });

// 06c like 06 but "animations" precedes "meshes" in the JSON text
{
  const T = f32([0, 1, 2]);
  write('06c_usage_anim_key_before_meshes', { asset,
    animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'translation' } }], samplers: [{ input: 1, output: 2 }] }],
    ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0, _T: 1 } }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 3, type: 'SCALAR', min: [0], max: [2] },
      { bufferView: 2, componentType: 5126, count: 3, type: 'VEC3' }],
    ...views([POS, T, f32([0, 0, 0, 1, 1, 1, 2, 2, 2])], [34962, 34962 - 34962 || undefined]) });
}

// 35 sparse-indices bufferView (no target) also holds the primitive's index accessor: accessors are linked before meshes
{
  const bin = Buffer.concat([POS, u16([0, 1, 2, 1]), f32([0, 1, 0])]);
  write('35_bv_sparse_then_mesh_indices', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
    accessors: [posAcc(0, { sparse: { count: 1, indices: { bufferView: 1, byteOffset: 6, componentType: 5123 }, values: { bufferView: 2 } } }),
      idxAcc(1)],
    buffers: [{ byteLength: bin.length, uri: uri(bin) }],
    bufferViews: [{ buffer: 0, byteLength: 36, target: 34962 }, { buffer: 0, byteOffset: 36, byteLength: 8 },
      { buffer: 0, byteOffset: 44, byteLength: 12 }] });
}

// 36 invalid bufferView.target value: ignored for usage (no override, hint instead)
write('36_bv_invalid_target_value', { asset, ...scene,
  meshes: [{ primitives: [{ attributes: { POSITION: 0 }, indices: 1 }] }],
  accessors: [posAcc(0), idxAcc(1)], ...views([POS, u16([0, 1, 2])], [34962, 1234]) });

// 37 animation output bufferView with target ARRAY_BUFFER and byteStride: where the stride error falls between the two overrides
{
  const bin = Buffer.concat([POS, f32([0]), f32([1, 2, 3, 0])]);
  write('37_bv_anim_output_target_and_stride', { asset, ...scene,
    meshes: [{ primitives: [{ attributes: { POSITION: 0 } }] }],
    animations: [{ channels: [{ sampler: 0, target: { node: 0, path: 'translation' } }], samplers: [{ input: 1, output: 2 }] }],
    accessors: [posAcc(0), { bufferView: 1, componentType: 5126, count: 1, type: 'SCALAR', min: [0], max: [0] },
      { bufferView: 2, componentType: 5126, count: 1, type: 'VEC3' }],
    buffers: [{ byteLength: bin.length, uri: uri(bin) }],
    bufferViews: [{ buffer: 0, byteLength: 36, target: 34962 }, { buffer: 0, byteOffset: 36, byteLength: 4 },
      { buffer: 0, byteOffset: 40, byteLength: 16, byteStride: 16, target: 34962 }] });
}
