# rdtf_draco: libdraco's mesh decoder built from Debian's source of the installed libdraco with
# scripts/draco/*.patch applied (scripts/install-deps.sh puts it in RDTF_DRACO_SOURCE_DIR), as an
# object library whose objects go into librdtf itself; never the system's libdraco. libdraco
# 1.5.5 as shipped sizes a table and a loop from a count in the stream (docs/format.md, "Draco").
# Only the decoder is built (45 files): no encoder, no file formats, no transcoder. It gets the
# build's sanitizer and fuzzer instrumentation, so the draco fuzz target explores libdraco too.
set(RDTF_DRACO_SOURCE_DIR /opt/rdtf/draco-src CACHE PATH
    "Debian's draco source (src/ and LICENSE) with scripts/draco/*.patch applied (made by scripts/install-deps.sh)")
include(${PROJECT_SOURCE_DIR}/cmake/PatchedSource.cmake)
rdtf_check_patched_source(${RDTF_DRACO_SOURCE_DIR} draco libdraco-dev src/draco/compression/decode.cc
                          "libdraco 1.5.5 as shipped decodes a crafted texture-coordinate count for seconds")

# draco_features.h is made by libdraco's own CMake; these are its decoder features, as Debian's
# build defines them, without the transcoder (materials, textures, scenes), which rdtf does not use.
set(RDTF_DRACO_FEATURES_DIR ${CMAKE_BINARY_DIR}/draco-features)
file(CONFIGURE OUTPUT ${RDTF_DRACO_FEATURES_DIR}/draco/draco_features.h CONTENT "// Made by cmake/PatchedDraco.cmake.
#ifndef DRACO_FEATURES_H_
#define DRACO_FEATURES_H_
#define DRACO_POINT_CLOUD_COMPRESSION_SUPPORTED
#define DRACO_MESH_COMPRESSION_SUPPORTED
#define DRACO_NORMAL_ENCODING_SUPPORTED
#define DRACO_STANDARD_EDGEBREAKER_SUPPORTED
#define DRACO_PREDICTIVE_EDGEBREAKER_SUPPORTED
#define DRACO_BACKWARDS_COMPATIBILITY_SUPPORTED
#define DRACO_ATTRIBUTE_INDICES_DEDUPLICATION_SUPPORTED
#define DRACO_ATTRIBUTE_VALUES_DEDUPLICATION_SUPPORTED
#endif  // DRACO_FEATURES_H_
")

set(draco_src ${RDTF_DRACO_SOURCE_DIR}/src/draco)
add_library(rdtf_draco OBJECT
  ${draco_src}/attributes/attribute_octahedron_transform.cc
  ${draco_src}/attributes/attribute_quantization_transform.cc
  ${draco_src}/attributes/attribute_transform.cc
  ${draco_src}/attributes/geometry_attribute.cc
  ${draco_src}/attributes/point_attribute.cc
  ${draco_src}/compression/attributes/attributes_decoder.cc
  ${draco_src}/compression/attributes/kd_tree_attributes_decoder.cc
  ${draco_src}/compression/attributes/sequential_attribute_decoder.cc
  ${draco_src}/compression/attributes/sequential_attribute_decoders_controller.cc
  ${draco_src}/compression/attributes/sequential_integer_attribute_decoder.cc
  ${draco_src}/compression/attributes/sequential_normal_attribute_decoder.cc
  ${draco_src}/compression/attributes/sequential_quantization_attribute_decoder.cc
  ${draco_src}/compression/bit_coders/adaptive_rans_bit_decoder.cc
  ${draco_src}/compression/bit_coders/direct_bit_decoder.cc
  ${draco_src}/compression/bit_coders/rans_bit_decoder.cc
  ${draco_src}/compression/bit_coders/symbol_bit_decoder.cc
  ${draco_src}/compression/decode.cc
  ${draco_src}/compression/entropy/symbol_decoding.cc
  ${draco_src}/compression/mesh/mesh_decoder.cc
  ${draco_src}/compression/mesh/mesh_edgebreaker_decoder.cc
  ${draco_src}/compression/mesh/mesh_edgebreaker_decoder_impl.cc
  ${draco_src}/compression/mesh/mesh_sequential_decoder.cc
  ${draco_src}/compression/point_cloud/algorithms/dynamic_integer_points_kd_tree_decoder.cc
  ${draco_src}/compression/point_cloud/algorithms/float_points_tree_decoder.cc
  ${draco_src}/compression/point_cloud/algorithms/integer_points_kd_tree_decoder.cc
  ${draco_src}/compression/point_cloud/point_cloud_decoder.cc
  ${draco_src}/compression/point_cloud/point_cloud_kd_tree_decoder.cc
  ${draco_src}/compression/point_cloud/point_cloud_sequential_decoder.cc
  ${draco_src}/core/bit_utils.cc
  ${draco_src}/core/bounding_box.cc
  ${draco_src}/core/data_buffer.cc
  ${draco_src}/core/decoder_buffer.cc
  ${draco_src}/core/divide.cc
  ${draco_src}/core/draco_types.cc
  ${draco_src}/core/hash_utils.cc
  ${draco_src}/core/options.cc
  ${draco_src}/core/quantization_utils.cc
  ${draco_src}/core/status.cc
  ${draco_src}/mesh/corner_table.cc
  ${draco_src}/mesh/mesh.cc
  ${draco_src}/mesh/mesh_attribute_corner_table.cc
  ${draco_src}/metadata/geometry_metadata.cc
  ${draco_src}/metadata/metadata.cc
  ${draco_src}/metadata/metadata_decoder.cc
  ${draco_src}/point_cloud/point_cloud.cc
)
# The patched headers and the features above come before /usr/include, where libdraco-dev's
# headers (another features set) may be: every file that includes <draco/...> must use this pair.
set(RDTF_DRACO_INCLUDE_DIRS ${RDTF_DRACO_FEATURES_DIR} ${RDTF_DRACO_SOURCE_DIR}/src)
target_include_directories(rdtf_draco SYSTEM PUBLIC ${RDTF_DRACO_INCLUDE_DIRS})
# Hidden: a program that also loads the system's libdraco (libassimp, for URDF import, needs it
# for its glTF importer) keeps the two apart; exported, rdtf's copy would stand in for libdraco's
# own symbols inside that library.
set_target_properties(rdtf_draco PROPERTIES CXX_STANDARD 17 CXX_VISIBILITY_PRESET hidden VISIBILITY_INLINES_HIDDEN ON)
target_compile_options(rdtf_draco PRIVATE -w)  # Third-party code: its warnings are not ours to fix.
if(RDTF_SANITIZE)
  # AddressSanitizer checks libdraco's memory accesses; UBSan's aborts stay on rdtf's own code.
  target_compile_options(rdtf_draco PRIVATE -fno-sanitize=undefined)
endif()
