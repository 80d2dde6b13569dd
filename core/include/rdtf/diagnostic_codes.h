// Every diagnostic code rdtf emits (core, URDF, dynamics, CLI, daemon), defined once: the constant
// a call site names (codes::MESH_OPEN: a misspelt code does not compile), the severities it is
// emitted with and its area. docs/diagnostics.md explains each (meaning and fix); a test keeps the
// two equal and checks that every code-like literal in the sources is one of these.
//
// To add a code: one X(...) line below (kept sorted by area, then name), the diagnostic emitted
// with codes::NAME, and a row in docs/diagnostics.md's table of its area.
#pragma once

#include <string_view>
#include <vector>

namespace rdtf {

// Which severities a code is emitted with (a check may make the same finding a warning or an error
// by option).
enum SeverityMask : unsigned { kSeverityInfo = 1, kSeverityWarning = 2, kSeverityError = 4 };

#define RDTF_DIAGNOSTIC_CODES(X) \
  X(ACCESSOR_ANIMATION_INPUT_NEGATIVE, kSeverityError, "glTF") \
  X(ACCESSOR_ANIMATION_INPUT_NON_INCREASING, kSeverityError, "glTF") \
  X(ACCESSOR_ANIMATION_SAMPLER_OUTPUT_NON_NORMALIZED_QUATERNION, kSeverityError, "glTF") \
  X(ACCESSOR_DATA_UNREADABLE, kSeverityError, "glTF") \
  X(ACCESSOR_ELEMENT_OUT_OF_MAX_BOUND, kSeverityError, "glTF") \
  X(ACCESSOR_ELEMENT_OUT_OF_MIN_BOUND, kSeverityError, "glTF") \
  X(ACCESSOR_INDEX_OOB, kSeverityError, "glTF") \
  X(ACCESSOR_INDEX_PRIMITIVE_RESTART, kSeverityError, "glTF") \
  X(ACCESSOR_INVALID_FLOAT, kSeverityError, "glTF") \
  X(ACCESSOR_INVALID_IBM, kSeverityError, "glTF") \
  X(ACCESSOR_JOINTS_INDEX_DUPLICATE, kSeverityError, "glTF") \
  X(ACCESSOR_JOINTS_INDEX_OOB, kSeverityError, "glTF") \
  X(ACCESSOR_MATRIX_ALIGNMENT, kSeverityError, "glTF") \
  X(ACCESSOR_MAX_MISMATCH, kSeverityWarning, "glTF") \
  X(ACCESSOR_MIN_MISMATCH, kSeverityWarning, "glTF") \
  X(ACCESSOR_NORMALIZED_INVALID, kSeverityError, "glTF") \
  X(ACCESSOR_OFFSET_ALIGNMENT, kSeverityError, "glTF") \
  X(ACCESSOR_SMALL_BYTESTRIDE, kSeverityError, "glTF") \
  X(ACCESSOR_SPARSE_COUNT_OUT_OF_RANGE, kSeverityError, "glTF") \
  X(ACCESSOR_SPARSE_INDEX_OOB, kSeverityError, "glTF") \
  X(ACCESSOR_SPARSE_INDICES_NON_INCREASING, kSeverityError, "glTF") \
  X(ACCESSOR_TOO_LONG, kSeverityError, "glTF") \
  X(ACCESSOR_TOTAL_OFFSET_ALIGNMENT, kSeverityError, "glTF") \
  X(ACCESSOR_USAGE_OVERRIDE, kSeverityError, "glTF") \
  X(ACCESSOR_WEIGHTS_NEGATIVE, kSeverityError, "glTF") \
  X(ACCESSOR_WEIGHTS_NON_NORMALIZED, kSeverityError, "glTF") \
  X(ANIMATION_CHANNEL_TARGET_NODE_MATRIX, kSeverityError, "glTF") \
  X(ANIMATION_CHANNEL_TARGET_NODE_WEIGHTS_NO_MORPHS, kSeverityError, "glTF") \
  X(ANIMATION_DUPLICATE_TARGETS, kSeverityError, "glTF") \
  X(ANIMATION_SAMPLER_ACCESSOR_WITH_BYTESTRIDE, kSeverityError, "glTF") \
  X(ANIMATION_SAMPLER_INPUT_ACCESSOR_INVALID_FORMAT, kSeverityError, "glTF") \
  X(ANIMATION_SAMPLER_INPUT_ACCESSOR_TOO_FEW_ELEMENTS, kSeverityError, "glTF") \
  X(ANIMATION_SAMPLER_INPUT_ACCESSOR_WITHOUT_BOUNDS, kSeverityError, "glTF") \
  X(ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_COUNT, kSeverityError, "glTF") \
  X(ANIMATION_SAMPLER_OUTPUT_ACCESSOR_INVALID_FORMAT, kSeverityError, "glTF") \
  X(ARRAY_LENGTH_NOT_IN_LIST, kSeverityError, "glTF") \
  X(ARRAY_TYPE_MISMATCH, kSeverityError, "glTF") \
  X(ASSET_MIN_VERSION_GREATER_THAN_VERSION, kSeverityError, "glTF") \
  X(BUFFER_BYTE_LENGTH_MISMATCH, kSeverityError, "glTF") \
  X(BUFFER_DATA_URI_MIME_TYPE_INVALID, kSeverityError, "glTF") \
  X(BUFFER_EXTERNAL_BYTELENGTH_MISMATCH, kSeverityError, "glTF") \
  X(BUFFER_LOAD_FAILED, kSeverityError, "glTF") \
  X(BUFFER_MISSING_GLB_DATA, kSeverityError, "glTF") \
  X(BUFFER_MISSING_URI, kSeverityError, "glTF") \
  X(BUFFER_VIEW_INVALID_BYTE_STRIDE, kSeverityError, "glTF") \
  X(BUFFER_VIEW_TARGET_OVERRIDE, kSeverityError, "glTF") \
  X(BUFFER_VIEW_TOO_BIG_BYTE_STRIDE, kSeverityError, "glTF") \
  X(BUFFER_VIEW_TOO_LONG, kSeverityError, "glTF") \
  X(COMPRESSION_DECODED, kSeverityInfo, "glTF") \
  X(DRACO_INVALID, kSeverityError, "glTF") \
  X(DUPLICATE_ELEMENTS, kSeverityError, "glTF") \
  X(EMPTY_ENTITY, kSeverityError, "glTF") \
  X(EMPTY_FILE, kSeverityError, "glTF") \
  X(GLB_CHUNK_LENGTH_UNALIGNED, kSeverityError, "glTF") \
  X(GLB_CHUNK_TOO_BIG, kSeverityError, "glTF") \
  X(GLB_DUPLICATE_CHUNK, kSeverityError, "glTF") \
  X(GLB_EMPTY_CHUNK, kSeverityError, "glTF") \
  X(GLB_INVALID_MAGIC, kSeverityError, "glTF") \
  X(GLB_INVALID_VERSION, kSeverityError, "glTF") \
  X(GLB_LENGTH_MISMATCH, kSeverityError, "glTF") \
  X(GLB_NO_JSON_CHUNK, kSeverityError, "glTF") \
  X(GLB_UNEXPECTED_BIN_CHUNK, kSeverityError, "glTF") \
  X(GLB_UNEXPECTED_END_OF_CHUNK_HEADER, kSeverityError, "glTF") \
  X(GLB_UNEXPECTED_END_OF_HEADER, kSeverityError, "glTF") \
  X(GLB_UNEXPECTED_FIRST_CHUNK, kSeverityError, "glTF") \
  X(INSTANCING_INVALID, kSeverityError, "glTF") \
  X(INVALID_GL_VALUE, kSeverityError, "glTF") \
  X(INVALID_IBM_ACCESSOR_COUNT, kSeverityError, "glTF") \
  X(INVALID_JSON, kSeverityError, "glTF") \
  X(INVALID_URI, kSeverityError, "glTF") \
  X(IO_ERROR, kSeverityError | kSeverityWarning, "glTF") \
  X(JSON_BOM, kSeverityError, "glTF") \
  X(JSON_TOO_DEEP, kSeverityError, "glTF") \
  X(KHR_LIGHTS_PUNCTUAL_LIGHT_SPOT_ANGLES, kSeverityError, "glTF") \
  X(KHR_MATERIALS_VARIANTS_NON_UNIQUE_VARIANT, kSeverityError, "glTF") \
  X(LIMIT_EXCEEDED, kSeverityError, "glTF") \
  X(MESHOPT_INVALID, kSeverityError, "glTF") \
  X(MESH_INVALID_WEIGHTS_COUNT, kSeverityError, "glTF") \
  X(MESH_PRIMITIVES_UNEQUAL_TARGETS_COUNT, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_ACCESSOR_UNALIGNED, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_ACCESSOR_WITHOUT_BYTESTRIDE, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_INVALID_FORMAT, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_ATTRIBUTES_ACCESSOR_UNSIGNED_INT, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_INDEXED_SEMANTIC_CONTINUITY, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_INDICES_ACCESSOR_INVALID_FORMAT, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_INDICES_ACCESSOR_WITH_BYTESTRIDE, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_INVALID_ATTRIBUTE, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_JOINTS_WEIGHTS_MISMATCH, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_MORPH_TARGET_INVALID_ATTRIBUTE_COUNT, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_MORPH_TARGET_NO_BASE_ACCESSOR, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_POSITION_ACCESSOR_WITHOUT_BOUNDS, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_TOO_FEW_TEXCOORDS, kSeverityError, "glTF") \
  X(MESH_PRIMITIVE_UNEQUAL_ACCESSOR_COUNT, kSeverityError, "glTF") \
  X(NODE_LOOP, kSeverityError, "glTF") \
  X(NODE_MATRIX_NON_TRS, kSeverityError, "glTF") \
  X(NODE_MATRIX_TRS, kSeverityError, "glTF") \
  X(NODE_PARENT_OVERRIDE, kSeverityError, "glTF") \
  X(NODE_SKIN_NO_SCENE, kSeverityError, "glTF") \
  X(NODE_SKIN_WITH_NON_SKINNED_MESH, kSeverityError, "glTF") \
  X(NODE_WEIGHTS_INVALID, kSeverityError, "glTF") \
  X(NON_REQUIRED_EXTENSION, kSeverityError, "glTF") \
  X(ONE_OF_MISMATCH, kSeverityError, "glTF") \
  X(PATTERN_MISMATCH, kSeverityError, "glTF") \
  X(ROTATION_NON_UNIT, kSeverityError, "glTF") \
  X(SCENE_NON_ROOT_NODE, kSeverityError, "glTF") \
  X(SKIN_IBM_ACCESSOR_WITH_BYTESTRIDE, kSeverityError, "glTF") \
  X(SKIN_IBM_INVALID_FORMAT, kSeverityError, "glTF") \
  X(SKIN_NO_COMMON_ROOT, kSeverityError, "glTF") \
  X(SKIN_SKELETON_INVALID, kSeverityError, "glTF") \
  X(TYPE_MISMATCH, kSeverityError, "glTF") \
  X(UNDECLARED_EXTENSION, kSeverityError, "glTF") \
  X(UNDEFINED_PROPERTY, kSeverityError, "glTF") \
  X(UNEXPECTED_EXTENSION_OBJECT, kSeverityError, "glTF") \
  X(UNKNOWN_ASSET_MAJOR_VERSION, kSeverityError, "glTF") \
  X(UNKNOWN_ASSET_MINOR_VERSION, kSeverityWarning, "glTF") \
  X(UNRESOLVED_REFERENCE, kSeverityError, "glTF") \
  X(UNSATISFIED_DEPENDENCY, kSeverityError, "glTF") \
  X(UNSUPPORTED_EXTENSION, kSeverityError, "glTF") \
  X(UNUSED_EXTENSION_REQUIRED, kSeverityError, "glTF") \
  X(URI_REFUSED, kSeverityError, "glTF") \
  X(VALUE_MULTIPLE_OF, kSeverityError, "glTF") \
  X(VALUE_NOT_IN_LIST, kSeverityError | kSeverityWarning, "glTF") \
  X(VALUE_NOT_IN_RANGE, kSeverityError, "glTF") \
  X(BUFFER_VIEW_STRIDE_ADDED, kSeverityInfo, "model") \
  X(DENSITY_IMPLAUSIBLE, kSeverityWarning, "model") \
  X(DUPLICATE_NAMES, kSeverityWarning, "model") \
  X(EXTRAS_NOT_OBJECT, kSeverityError, "model") \
  X(IMAGE_NOT_COPIED, kSeverityWarning, "model") \
  X(IMAGE_NOT_EMBEDDED, kSeverityWarning, "model") \
  X(JOINT_AXIS_ZERO, kSeverityError, "model") \
  X(JOINT_CHAIN, kSeverityInfo | kSeverityWarning, "model") \
  X(JOINT_LIMITS_IMPLAUSIBLE, kSeverityWarning, "model") \
  X(JOINT_LIMITS_INVERTED, kSeverityError, "model") \
  X(JOINT_MOVES_NOTHING, kSeverityWarning, "model") \
  X(JOINT_MOVES_SEVERAL_LINKS, kSeverityInfo, "model") \
  X(JOINT_ORIGIN_QUANTIZED, kSeverityWarning, "model") \
  X(JOINT_TYPE_MISSING, kSeverityWarning, "model") \
  X(KHR_JOINT_FRAMES_DISAGREE, kSeverityError, "model") \
  X(KHR_JOINT_NOT_WRITTEN, kSeverityWarning, "model") \
  X(KHR_PHYSICS_IGNORED, kSeverityWarning, "model") \
  X(KHR_PHYSICS_INVALID, kSeverityError, "model") \
  X(KHR_PHYSICS_UNSUPPORTED, kSeverityWarning, "model") \
  X(LINK_MESH_SPLIT, kSeverityInfo, "model") \
  X(LINK_NO_VOLUME, kSeverityWarning, "model") \
  X(LINK_PARTS_OVERLAP, kSeverityWarning, "model") \
  X(MESH_HOLDS_FRAMES, kSeverityInfo, "model") \
  X(MESH_INCONSISTENT_WINDING, kSeverityWarning | kSeverityInfo, "model") \
  X(MESH_ENCLOSES_NO_VOLUME, kSeverityWarning, "model") \
  X(MESH_INSIDE_OUT, kSeverityWarning | kSeverityInfo, "model") \
  X(MESH_OPEN, kSeverityWarning | kSeverityInfo, "model") \
  X(MESH_PRIMITIVE_INCOMPATIBLE_MODE, kSeverityWarning, "model") \
  X(MESH_SCALED_TO_NOTHING, kSeverityWarning, "model") \
  X(MESH_SHELL_INSIDE_OUT, kSeverityWarning, "model") \
  X(MESH_WITHOUT_LINK, kSeverityWarning, "model") \
  X(MULTIPLE_ROOT_LINKS, kSeverityWarning, "model") \
  X(NO_LINKS, kSeverityWarning, "model") \
  X(NO_RDTF_PROPERTIES, kSeverityWarning, "model") \
  X(NO_SCENE, kSeverityError, "model") \
  X(NODE_ANIMATED, kSeverityWarning, "model") \
  X(NODE_SHEARED, kSeverityWarning, "model") \
  X(PRIMITIVE_SKIPPED, kSeverityInfo, "model") \
  X(RDTF_AXES_ASSUMED, kSeverityWarning, "model") \
  X(RDTF_INVALID_JOINT_TYPE, kSeverityError, "model") \
  X(RDTF_INVALID_NODE_ENTRY, kSeverityError, "model") \
  X(RDTF_INVALID_TYPE, kSeverityError, "model") \
  X(RDTF_INVALID_VALUE, kSeverityError, "model") \
  X(RDTF_MASS_OVERRIDDEN, kSeverityWarning, "model") \
  X(RDTF_NODE_EXTRAS_IGNORED, kSeverityWarning, "model") \
  X(RDTF_UNKNOWN_KEY, kSeverityWarning, "model") \
  X(RDTF_VERSION_NEWER, kSeverityWarning, "model") \
  X(SCENE_NOT_CONVERTED, kSeverityWarning, "model") \
  X(SKIN_NO_WEIGHTS, kSeverityWarning, "model") \
  X(SKIN_PART_SHARED, kSeverityInfo, "model") \
  X(UNITS_IMPLAUSIBLE, kSeverityWarning, "model") \
  X(FILE_TOO_LARGE, kSeverityError, "URDF") \
  X(TOO_MANY_TRIANGLES, kSeverityError, "URDF") \
  X(URDF_BALL_JOINT, kSeverityError, "URDF") \
  X(URDF_COLLISION_AS_VISUAL, kSeverityInfo, "URDF") \
  X(URDF_DUPLICATE_NAME, kSeverityError, "URDF") \
  X(URDF_EXPORT_FAILED, kSeverityError, "URDF") \
  X(URDF_FLOATING_JOINT, kSeverityWarning, "URDF") \
  X(URDF_GEOMETRY_SKIPPED, kSeverityWarning, "URDF") \
  X(URDF_IGNORED, kSeverityInfo, "URDF") \
  X(URDF_INVALID, kSeverityError, "URDF") \
  X(URDF_INVALID_INERTIAL, kSeverityError, "URDF") \
  X(URDF_INVALID_NUMBER, kSeverityError, "URDF") \
  X(URDF_JOINT_LOOP, kSeverityError, "URDF") \
  X(URDF_LIMIT_DEFAULTED, kSeverityInfo, "URDF") \
  X(URDF_LINK_TWO_PARENTS, kSeverityError, "URDF") \
  X(URDF_MALFORMED_XML, kSeverityError, "URDF") \
  X(URDF_MASSLESS_MOVING_LINK, kSeverityWarning, "URDF") \
  X(URDF_MESH_FORMAT_UNSUPPORTED, kSeverityWarning, "URDF") \
  X(URDF_MESH_INVALID, kSeverityError | kSeverityWarning, "URDF") \
  X(URDF_MESH_NOT_FOUND, kSeverityError | kSeverityWarning, "URDF") \
  X(URDF_MIMIC_IGNORED, kSeverityWarning, "URDF") \
  X(URDF_MULTIPLE_ROOTS, kSeverityError, "URDF") \
  X(URDF_NAME_CHANGED, kSeverityWarning, "URDF") \
  X(URDF_NOT_A_ROBOT, kSeverityError, "URDF") \
  X(URDF_NOT_UTF8, kSeverityError, "URDF") \
  X(URDF_NO_INERTIAL, kSeverityInfo | kSeverityWarning, "URDF") \
  X(URDF_NO_LINKS, kSeverityError, "URDF") \
  X(URDF_PARSE_FAILED, kSeverityError, "URDF") \
  X(URDF_PRISMATIC_WITHOUT_LIMITS, kSeverityError, "URDF") \
  X(URDF_READ_FAILED, kSeverityError, "URDF") \
  X(URDF_REVOLUTE_WITHOUT_LIMITS, kSeverityWarning, "URDF") \
  X(URDF_ROOT_ADDED, kSeverityInfo, "URDF") \
  X(URDF_SELF_CHECK_FAILED, kSeverityError, "URDF") \
  X(URDF_SHAPE_DEGENERATE, kSeverityWarning, "URDF") \
  X(URDF_SPRING_DROPPED, kSeverityWarning, "URDF") \
  X(URDF_TEXTURE_SKIPPED, kSeverityWarning, "URDF") \
  X(URDF_UNKNOWN_JOINT_TYPE, kSeverityError, "URDF") \
  X(URDF_UNKNOWN_LINK, kSeverityError, "URDF") \
  X(URDF_VISUAL_ONLY, kSeverityInfo, "URDF") \
  X(JOINT_AXIS_NOT_FINITE, kSeverityError, "dynamics") \
  X(JOINT_AXIS_NOT_UNIT, kSeverityWarning, "dynamics") \
  X(JOINT_DYNAMICS_INVALID, kSeverityError, "dynamics") \
  X(JOINT_LIMITS_NOT_FINITE, kSeverityError, "dynamics") \
  X(JOINT_MASS_RATIO, kSeverityError, "dynamics") \
  X(JOINT_POSE_NOT_FINITE, kSeverityError, "dynamics") \
  X(JOINT_REST_OUTSIDE_LIMITS, kSeverityWarning, "dynamics") \
  X(LINK_COM_NOT_FINITE, kSeverityError, "dynamics") \
  X(LINK_COM_OUTSIDE_GEOMETRY, kSeverityError | kSeverityWarning, "dynamics") \
  X(LINK_INERTIA_ABOVE_GEOMETRY_BOUND, kSeverityWarning, "dynamics") \
  X(LINK_INERTIA_BELOW_SOLID_BOUND, kSeverityError, "dynamics") \
  X(LINK_INERTIA_NOT_FINITE, kSeverityError, "dynamics") \
  X(LINK_INERTIA_NOT_POSITIVE_DEFINITE, kSeverityError | kSeverityWarning, "dynamics") \
  X(LINK_INERTIA_NOT_SYMMETRIC, kSeverityError | kSeverityWarning, "dynamics") \
  X(LINK_INERTIA_TRIANGLE_INEQUALITY, kSeverityError | kSeverityWarning, "dynamics") \
  X(LINK_MASSLESS, kSeverityInfo, "dynamics") \
  X(LINK_MASSLESS_WITH_INERTIA, kSeverityError | kSeverityWarning, "dynamics") \
  X(LINK_MASS_NEGATIVE, kSeverityError, "dynamics") \
  X(LINK_MASS_NOT_FINITE, kSeverityError, "dynamics") \
  X(LINK_MASS_ZERO, kSeverityError | kSeverityWarning, "dynamics") \
  X(LINK_NOT_CONNECTED, kSeverityError, "dynamics") \
  X(LINK_POINT_MASS, kSeverityInfo, "dynamics") \
  X(LINK_POSE_NOT_FINITE, kSeverityError, "dynamics") \
  X(ODE_INVALID_JOINT, kSeverityError, "dynamics") \
  X(ODE_INVALID_LINK, kSeverityError, "dynamics") \
  X(ODE_INVALID_ROBOT, kSeverityError, "dynamics") \
  X(ODE_MASSLESS_LINK, kSeverityError, "dynamics") \
  X(ODE_MASS_CHECK_FAILED, kSeverityError, "dynamics") \
  X(ODE_MESSAGE, kSeverityWarning, "dynamics") \
  X(ODE_PROPERTY_IGNORED, kSeverityWarning, "dynamics") \
  X(ODE_UNSUPPORTED_JOINT, kSeverityError, "dynamics") \
  X(ROBOT_INVALID_REFERENCE, kSeverityError, "dynamics") \
  X(ROBOT_MULTIPLE_ROOTS, kSeverityError, "dynamics") \
  X(ROBOT_NO_LINKS, kSeverityError, "dynamics") \
  X(SIM_BODY_LEFT_REGION, kSeverityError, "dynamics") \
  X(SIM_BUDGET_EXCEEDED, kSeverityError, "dynamics") \
  X(SIM_CANCELLED, kSeverityError, "dynamics") \
  X(SIM_ENERGY_RISE, kSeverityError, "dynamics") \
  X(SIM_INITIAL_POSITION_CLAMPED, kSeverityInfo, "dynamics") \
  X(SIM_INITIAL_POSITION_IGNORED, kSeverityWarning, "dynamics") \
  X(SIM_INVALID_OPTIONS, kSeverityError, "dynamics") \
  X(SIM_JOINT_MISALIGNMENT, kSeverityError | kSeverityWarning, "dynamics") \
  X(SIM_JOINT_SEPARATION, kSeverityError, "dynamics") \
  X(SIM_LIMIT_VIOLATED, kSeverityError, "dynamics") \
  X(SIM_NOT_FINITE, kSeverityError, "dynamics") \
  X(SIM_QUICKSTEP_FAILED, kSeverityInfo, "dynamics") \
  X(SIM_UNKNOWN_JOINT, kSeverityInfo, "dynamics") \
  X(WRITE_FAILED, kSeverityError, "output") \
  X(COMMAND_REJECTED, kSeverityError, "daemon") \
  X(DIAGNOSTICS_TRUNCATED, kSeverityInfo, "daemon") \
  X(INTERNAL_ERROR, kSeverityError, "daemon") \
  X(LCM_SEND_FAILED, kSeverityError, "daemon") \
  X(MANIFEST_INCOMPLETE, kSeverityWarning, "daemon") \
  X(NAME_TOO_LONG, kSeverityError, "daemon") \
  X(SIMULATION_FAILED, kSeverityError, "daemon") \
  X(URDF_NOT_WRITTEN, kSeverityWarning, "daemon") \
  X(WATCH_FAILED, kSeverityError, "daemon") \
  X(OUTPUT_PATH_INVALID, kSeverityError, "CLI")

namespace codes {
#define RDTF_DIAGNOSTIC_CODE_CONSTANT(name, severities, area) inline constexpr char name[] = #name;
RDTF_DIAGNOSTIC_CODES(RDTF_DIAGNOSTIC_CODE_CONSTANT)
#undef RDTF_DIAGNOSTIC_CODE_CONSTANT
}  // namespace codes

struct DiagnosticCode {
  std::string_view code;
  unsigned severities;  // SeverityMask bits.
  std::string_view area;  // "glTF", "model", "URDF", "dynamics", "output", "daemon" or "CLI".
};

// Every code, in the order above.
const std::vector<DiagnosticCode>& diagnostic_codes();
const DiagnosticCode* find_diagnostic_code(std::string_view code);

}  // namespace rdtf
