// Writes the models of tests/gltf/attribute_formats_test.cc: for each attribute (on a primitive
// and on a morph target), with and without KHR_mesh_quantization, one primitive per accessor
// format (type x componentType x normalized), so that rdtf's MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_*
// errors can be compared with the Khronos validator's, place by place.
// Run from anywhere: node tests/data/gltf-attribute-formats/make_models.mjs (writes beside it).
import fs from 'node:fs';

const dir = new URL('.', import.meta.url).pathname;
const TYPES = ['SCALAR', 'VEC2', 'VEC3', 'VEC4', 'MAT4'];
const COMPONENTS = [5120, 5121, 5122, 5123, 5125, 5126];
const BASE = ['POSITION', 'NORMAL', 'TANGENT', 'TEXCOORD_0', 'COLOR_0', 'JOINTS_0', 'WEIGHTS_0', '_CUSTOM'];
const TARGET = ['POSITION', 'NORMAL', 'TANGENT', 'TEXCOORD_0', 'COLOR_0', '_CUSTOM'];
// A valid format of each, for the base attribute a morph target's one moves.
const VALID = {
  POSITION: ['VEC3', 5126], NORMAL: ['VEC3', 5126], TANGENT: ['VEC4', 5126], TEXCOORD_0: ['VEC2', 5126],
  COLOR_0: ['VEC4', 5126], JOINTS_0: ['VEC4', 5121], WEIGHTS_0: ['VEC4', 5126], _CUSTOM: ['SCALAR', 5126],
};

// One buffer of zeros that every accessor reads from its start (the largest, MAT4 of FLOAT x 3, is
// 192 bytes); the values are not what is compared.
const bytes = Buffer.alloc(192);
const buffer = { byteLength: bytes.length, uri: 'data:application/octet-stream;base64,' + bytes.toString('base64') };

function model(attribute, onTarget, quantized) {
  const accessors = [{ bufferView: 0, componentType: 5126, count: 3, type: 'VEC3', min: [0, 0, 0], max: [0, 0, 0] }];
  const add = (a) => accessors.push(a) - 1;
  const validOf = (name) => add({ bufferView: 0, componentType: VALID[name][1], count: 3, type: VALID[name][0],
    ...(VALID[name][1] === 5121 && name !== 'JOINTS_0' ? { normalized: true } : {}) });
  const primitives = [];
  for (const type of TYPES) {
    for (const componentType of COMPONENTS) {
      for (const normalized of [false, true]) {
        const test = add({ bufferView: 0, componentType, count: 3, type, ...(normalized ? { normalized } : {}) });
        const attributes = { POSITION: 0 };
        const primitive = { attributes };
        if (onTarget) {
          if (attribute !== 'POSITION') attributes[attribute] = validOf(attribute);
          primitive.targets = [{ [attribute]: test }];
        } else {
          attributes[attribute] = test;
          if (attribute === 'JOINTS_0') attributes.WEIGHTS_0 = validOf('WEIGHTS_0');
          if (attribute === 'WEIGHTS_0') attributes.JOINTS_0 = validOf('JOINTS_0');
        }
        primitives.push(primitive);
      }
    }
  }
  const gltf = {
    asset: { version: '2.0' },
    ...(quantized ? { extensionsUsed: ['KHR_mesh_quantization'], extensionsRequired: ['KHR_mesh_quantization'] } : {}),
    scene: 0, scenes: [{ nodes: [0] }], nodes: [{ mesh: 0 }],
    meshes: [{ primitives }], accessors, bufferViews: [{ buffer: 0, byteLength: bytes.length }], buffers: [buffer],
  };
  const name = `${onTarget ? 'target' : 'base'}_${attribute.replace(/^_/, '')}${quantized ? '_quantized' : ''}`;
  fs.writeFileSync(`${dir}/${name}.gltf`, JSON.stringify(gltf) + '\n');
}

for (const quantized of [false, true]) {
  for (const attribute of BASE) model(attribute, false, quantized);
  for (const attribute of TARGET) model(attribute, true, quantized);
}
