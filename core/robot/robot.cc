#include "rdtf/robot.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <tuple>

#include "rdtf/completion.h"
#include "rdtf/geometry.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

// Where a joint's properties were found, and the frame its axis is expressed in.
struct JointSource {
  const Json* values = nullptr;  // Object holding the keys.
  std::string pointer;           // JSON pointer of that object.
  std::string label;             // The node it is about, as diagnostics name it.
  bool rdtf_entry = false;       // extras.RDTF joint object (keys without the "rdtf_" prefix).
  int frame_node = -1;           // Node whose frame a node-extras axis is in.
  bool blender_axes = false;     // A node-extras vector is in Blender's axes (Z up).
};

std::string key_for(const JointSource& source, const std::string& rdtf_key,
                    const std::string& extras_key) {
  return source.rdtf_entry ? rdtf_key : extras_key;
}

std::optional<double> read_number(const JointSource& source, const std::string& key,
                                  Diagnostics& diag) {
  if (!source.values->contains(key)) return std::nullopt;
  const Json& value = (*source.values)[key];
  if (!value.is_number() || !std::isfinite(value.get<double>())) {
    diag.error(codes::RDTF_INVALID_VALUE, json_pointer(source.pointer, key),
               source.label + ": " + key + " is " + value_text(value) + ", not a finite number" +
                   text_value_advice(value, key));
    return std::nullopt;
  }
  return value.get<double>();
}

// A number that is 0 or more: an effort or speed limit, damping, friction, a spring's stiffness.
std::optional<double> read_amount(const JointSource& source, const std::string& key, Diagnostics& diag) {
  const auto value = read_number(source, key, diag);
  if (value && *value < 0) {
    diag.error(codes::RDTF_INVALID_VALUE, json_pointer(source.pointer, key),
               source.label + ": " + key + " is " + value_text(Json(*value)) + ", which is negative: it must be 0 or more");
    return std::nullopt;
  }
  return value;
}

const Json* node_extras(const Json& document, std::size_t node) {
  const Json& n = document["nodes"][node];
  if (!n.contains("extras") || !n["extras"].is_object()) return nullptr;
  return &n["extras"];
}

bool has_joint_keys(const Json* extras) {
  if (extras == nullptr) return false;
  for (const char* key : kJointExtrasKeys) {
    if (extras->contains(key)) return true;
  }
  return false;
}

// A local transform other than the identity: the node is placed somewhere of its own.
bool has_own_transform(const Json& node) {
  auto differs = [&](const char* key, const std::vector<double>& identity) {
    if (!node.contains(key) || !node[key].is_array() || node[key].size() != identity.size()) return false;
    for (std::size_t i = 0; i < identity.size(); ++i) {
      if (!node[key][i].is_number() || node[key][i].get<double>() != identity[i]) return true;
    }
    return false;
  };
  return differs("translation", {0, 0, 0}) || differs("rotation", {0, 0, 0, 1}) ||
         differs("scale", {1, 1, 1}) ||
         differs("matrix", {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1});
}

// Whether the node is a joint of a skin: a bone, in Blender's terms.
bool is_skin_joint(const Json& document, std::size_t node) {
  if (!document.contains("skins") || !document["skins"].is_array()) return false;
  for (const Json& skin : document["skins"]) {
    if (!skin.is_object() || !skin.contains("joints") || !skin["joints"].is_array()) continue;
    for (const Json& joint : skin["joints"]) {
      if (joint.is_number_unsigned() && joint.get<std::size_t>() == node) return true;
    }
  }
  return false;
}

// The tool that re-saved a file and replaced its generator, when asset.generator names one (below).
std::optional<std::string> resaved_by(const Json& document);

// Does a node-extras vector of this node need turning from Blender's axes to the node's? "rdtf_axes"
// on the node says whether it is in Blender's axes ("blender" or "gltf"); without it, it is exactly
// when Blender's exporter wrote the file. A bone is never turned: Blender's exporter writes a bone's
// node in the bone's own axes as Blender draws them (Y from head to tail); only objects' frames are
// turned from Blender's Z up to glTF's Y up.
bool reads_blender_axes(const Json& document, std::size_t node, Diagnostics& diag) {
  const Json* extras = node_extras(document, node);
  bool blender = written_by_blender(document);
  const bool typed_axis = extras != nullptr && extras->contains("rdtf_axis");
  if (typed_axis && !extras->contains("rdtf_axes") && !is_skin_joint(document, node)) {
    // A packer that replaces asset.generator hides which tool wrote the axis: gltfpack's output of
    // a Blender export turned every typed axis by 90 degrees, without a word.
    if (const auto tool = resaved_by(document)) {
      diag.warning(codes::RDTF_AXES_ASSUMED, json_pointer("/nodes", node) + "/extras/rdtf_axis",
                   node_label(document, node) + ": rdtf_axis " + value_text((*extras)["rdtf_axis"]) +
                       " is read in glTF's axes, since asset.generator is '" + *tool +
                       "', which replaces the generator of a file it re-saves: rdtf cannot tell whether "
                       "Blender wrote it, where a typed axis is in Blender's axes (Z up). If it came from "
                       "Blender, add \"rdtf_axes\": \"blender\" beside rdtf_axis, or re-save rdtf's own output "
                       "instead (rdtf convert first, then e.g. gltfpack -kn -ke), which says its axes");
    }
  }
  if (extras != nullptr && extras->contains("rdtf_axes")) {
    const Json& value = (*extras)["rdtf_axes"];
    if (value == "blender" || value == "gltf") {
      blender = value == "blender";
    } else {
      diag.error(codes::RDTF_INVALID_VALUE, json_pointer("/nodes", node) + "/extras/rdtf_axes",
                 node_label(document, node) + ": rdtf_axes is " + value_text(value) +
                     ", not \"blender\" or \"gltf\"");
    }
  }
  return blender && !is_skin_joint(document, node);
}

}  // namespace

bool node_extras_in_blender_axes(const Json& document, std::size_t node) {
  Diagnostics scratch;
  return reads_blender_axes(document, node, scratch);
}

std::vector<const Json*> rdtf_entries(const Json& document, std::vector<std::string>& pointers) {
  const std::size_t count = document["nodes"].size();
  std::vector<const Json*> entries(count, nullptr);
  pointers.assign(count, "");
  if (!document.contains("extras") || !document["extras"].is_object()) return entries;
  const Json& extras = document["extras"];
  if (!extras.contains("RDTF") || !extras["RDTF"].is_object()) return entries;
  const Json& rdtf = extras["RDTF"];
  if (!rdtf.contains("nodes") || !rdtf["nodes"].is_array()) return entries;
  for (std::size_t i = 0; i < rdtf["nodes"].size(); ++i) {
    const Json& entry = rdtf["nodes"][i];
    if (!entry.is_object() || !entry.contains("node") || !entry["node"].is_number_unsigned()) continue;
    const auto node = entry["node"].get<std::size_t>();
    if (node < count && entries[node] == nullptr) {  // A node listed again: typing refused it.
      entries[node] = &entry;
      pointers[node] = json_pointer("/extras/RDTF/nodes", i);
    }
  }
  return entries;
}

namespace {

// "x", "-z", "+y": a unit vector along a named axis.
std::optional<Eigen::Vector3d> named_axis(const std::string& text) {
  if (text.empty() || text.size() > 2) return std::nullopt;
  const double sign = text[0] == '-' ? -1.0 : 1.0;
  const std::string name = (text[0] == '-' || text[0] == '+') ? text.substr(1) : text;
  if (name == "x" || name == "X") return sign * Eigen::Vector3d::UnitX();
  if (name == "y" || name == "Y") return sign * Eigen::Vector3d::UnitY();
  if (name == "z" || name == "Z") return sign * Eigen::Vector3d::UnitZ();
  return std::nullopt;
}

// Only an axis's direction counts. One whose squared norm overflows a double ([1e300, 1e300, 0]
// became the zero vector) or underflows it is scaled to a largest component of 1 first; any other
// is left as it is, so that a unit axis read back from rdtf's output keeps its bits.
void in_range(Eigen::Vector3d& v) {
  const double squared = v.squaredNorm();
  if (std::isfinite(squared) && squared > 1e-200) return;
  const double largest = v.cwiseAbs().maxCoeff();
  if (largest > 0.0) v /= largest;
}

void read_axis(const JointSource& source, const Eigen::Affine3d& X_SF, const Eigen::Isometry3d& X_SC,
               Joint& joint, Diagnostics& diag) {
  const std::string axis_key = key_for(source, "axis", "rdtf_axis");
  if (!source.values->contains(axis_key)) return;
  const Json& value = (*source.values)[axis_key];
  const std::string pointer = json_pointer(source.pointer, axis_key);
  std::optional<Eigen::Vector3d> axis;
  if (value.is_string()) {
    axis = named_axis(value.get<std::string>());
  } else if (value.is_array() && value.size() == 3 && value[0].is_number() && value[1].is_number() &&
             value[2].is_number()) {
    axis = Eigen::Vector3d(value[0].get<double>(), value[1].get<double>(), value[2].get<double>());
    if (!axis->allFinite()) axis.reset();
  }
  if (!axis) {
    diag.error(codes::RDTF_INVALID_VALUE, pointer,
               source.label + ": " + axis_key + " is " + value_text(value) +
                   ", not three finite numbers or one of \"x\", \"y\", \"z\", \"-x\", \"-y\", \"-z\"" +
                   text_value_advice(value, axis_key));
    return;
  }
  if (axis->cwiseAbs().maxCoeff() == 0.0) {
    diag.error(codes::JOINT_AXIS_ZERO, pointer,
               source.label + ": the joint axis " + value_text(value) + " is the zero vector");
    return;
  }
  in_range(*axis);
  if (!source.rdtf_entry) {
    // A node-extras axis is a direction in that node's frame (in Blender's axes when Blender wrote
    // the file: glTF (x, y, z) = Blender (x, z, -y)); map it into the child link frame.
    if (source.blender_axes) *axis = blender_to_gltf_axes() * *axis;
    *axis = X_SC.linear().transpose() * (X_SF.linear() * *axis);
    if (axis->allFinite()) in_range(*axis);
    if (!axis->allFinite() || !(axis->norm() > 0.0)) {  // A scale of 0 flattens it, one of 1e200 overflows.
      diag.error(codes::JOINT_AXIS_ZERO, pointer,
                 source.label + ": the joint axis " + value_text(value) +
                     (axis->allFinite() ? " has no length in the scene: the node's scale flattens it"
                                        : " has no direction in the scene: the nodes' scales overflow it"));
      return;
    }
  }
  joint.axis = axis->normalized();
}

// "; did you mean 'revolute'?" for a joint type written in other case or with spaces ("Revolute").
std::string lower_case_advice(const Json& value) {
  if (!value.is_string()) return {};
  std::string lower;
  for (const char c : value.get<std::string>()) {
    if (!std::isspace(static_cast<unsigned char>(c))) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  if (!joint_kind_from_string(lower)) return {};
  return "; did you mean '" + lower + "'? (types are lower case, without spaces)";
}

void read_joint_properties(const JointSource& source, const Eigen::Affine3d& X_SF,
                           const Eigen::Isometry3d& X_SC, Joint& joint, Diagnostics& diag) {
  const std::string kind_key = key_for(source, "type", "rdtf_joint");
  if (source.values->contains(kind_key)) {
    const Json& value = (*source.values)[kind_key];
    const auto kind = value.is_string() ? joint_kind_from_string(value.get<std::string>()) : std::nullopt;
    if (!kind) {
      diag.error(codes::RDTF_INVALID_JOINT_TYPE, json_pointer(source.pointer, kind_key),
                 source.label + ": joint type " + value_text(value) +
                     " is not one of fixed, revolute, continuous, prismatic, floating, planar, ball" +
                     lower_case_advice(value));
    } else {
      joint.kind = *kind;
    }
  }
  read_axis(source, X_SF, X_SC, joint, diag);
  const auto lower = read_number(source, key_for(source, "lower", "rdtf_lower"), diag);
  const auto upper = read_number(source, key_for(source, "upper", "rdtf_upper"), diag);
  const auto effort = read_amount(source, key_for(source, "effort", "rdtf_effort"), diag);
  const auto velocity = read_amount(source, key_for(source, "velocity", "rdtf_velocity"), diag);
  // An effort or speed of 0 is "not given" (JointLimits): alone, it makes no limits at all.
  if (lower || upper || effort.value_or(0) != 0 || velocity.value_or(0) != 0) {
    JointLimits limits;
    limits.lower = lower.value_or(0.0);
    limits.upper = upper.value_or(0.0);
    limits.effort = effort.value_or(0.0);
    limits.velocity = velocity.value_or(0.0);
    limits.position = lower || upper;
    if (limits.position && limits.lower > limits.upper) {
      diag.error(codes::JOINT_LIMITS_INVERTED, source.pointer,
                 source.label + ": lower limit " + value_text(limits.lower) +
                     " is above upper limit " + value_text(limits.upper));
    }
    joint.limits = limits;
  }
  joint.damping = read_amount(source, key_for(source, "damping", "rdtf_damping"), diag).value_or(0);
  joint.friction = read_amount(source, key_for(source, "friction", "rdtf_friction"), diag).value_or(0);
  joint.spring_stiffness =
      read_amount(source, key_for(source, "springStiffness", "rdtf_spring_stiffness"), diag)
          .value_or(0);
  // Properties of a moving joint without its type: the type is fixed by default, and they would do
  // nothing without a word (an empty given an axis and limits but no rdtf_joint, s101fmt D8).
  if (!source.values->contains(kind_key)) {
    std::string given;
    for (const auto& [entry_key, extras_key] :
         {std::pair{"axis", "rdtf_axis"}, {"lower", "rdtf_lower"}, {"upper", "rdtf_upper"}, {"effort", "rdtf_effort"},
          {"velocity", "rdtf_velocity"}, {"damping", "rdtf_damping"}, {"friction", "rdtf_friction"},
          {"springStiffness", "rdtf_spring_stiffness"}}) {
      const std::string key = key_for(source, entry_key, extras_key);
      if (source.values->contains(key)) given += (given.empty() ? "" : ", ") + key;
    }
    if (!given.empty()) {
      diag.warning(codes::JOINT_TYPE_MISSING, source.pointer,
                   source.label + ": " + given + " given without " + kind_key +
                       ", so the joint is fixed and they do nothing; set " + kind_key +
                       " to revolute, continuous or prismatic, or remove them");
    }
  }
}

std::string vector_text(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}).dump(); }

bool agree(double a, double b) { return std::abs(a - b) <= 1e-9 * std::max({1.0, std::abs(a), std::abs(b)}); }

// What differs between a joint as its node extras give it and as its extras.RDTF entry does:
// "<property>: <node extras' value> in node extras, <entry's value> in extras.RDTF"; nothing
// when they agree to 1e-9 relative (rdtf writes the axis of its node-extras copy in another
// frame, which rounds).
std::optional<std::string> joint_properties_differ(const Joint& extras, const Joint& entry) {
  const auto both = [](const std::string& what, const std::string& in_extras, const std::string& in_entry) {
    return what + ": " + in_extras + " in node extras, " + in_entry + " in extras.RDTF";
  };
  const auto text = [](double value) { return value_text(Json(value)); };
  if (extras.kind != entry.kind) return both("type", to_string(extras.kind), to_string(entry.kind));
  const bool has_axis = entry.kind != JointKind::kFixed && entry.kind != JointKind::kFloating && entry.kind != JointKind::kBall;
  if (has_axis && (extras.axis - entry.axis).norm() > 1e-9) {
    return both("axis (in the child link frame)", vector_text(extras.axis), vector_text(entry.axis));
  }
  const JointLimits none{0, 0, 0, 0, false};
  const JointLimits& a = extras.limits ? *extras.limits : none;
  const JointLimits& b = entry.limits ? *entry.limits : none;
  const auto range = [&](const JointLimits& l) {
    return l.position ? "[" + text(l.lower) + ", " + text(l.upper) + "]" : std::string("none");
  };
  if (a.position != b.position || (a.position && (!agree(a.lower, b.lower) || !agree(a.upper, b.upper)))) {
    return both("position limits", range(a), range(b));
  }
  for (const auto& [what, x, y] : {std::tuple{"effort limit", a.effort, b.effort}, {"velocity limit", a.velocity, b.velocity},
                                   {"damping", extras.damping, entry.damping}, {"friction", extras.friction, entry.friction},
                                   {"spring stiffness", extras.spring_stiffness, entry.spring_stiffness}}) {
    if (!agree(x, y)) return both(what, text(x), text(y));
  }
  return std::nullopt;
}

// A joint node with joint properties is one degree of freedom: whatever hangs from it moves as
// one part. The link among its children (the first with geometry and no joint of its own, else
// one that fixes itself, else one with its own moving joint; else the first) is that part, and what else hangs from the joint node
// hangs from that link: a part parented to a bone beside the next bone, an elbow empty parented
// to the shoulder empty beside the upper arm, two jaws under one grip empty. A joint node without properties (the paper's, which groups a link's child links
// in one node, or rdtf's inserted ones) moves nothing: each link below it keeps its own joint to
// the link above. The link node each joint node carries, -1 for none.
std::vector<int> carried_links(const Json& document, const std::vector<NodeType>& types,
                               const std::vector<const Json*>& entries) {
  std::vector<int> carried(types.size(), -1);
  if (!document.contains("nodes")) return carried;
  // Whether a mesh has a surface: a primitive of triangles (a strip or fan too). A three.js
  // AxesHelper or a wire gizmo under the joint empty is a mesh of lines, which weighs nothing.
  const auto has_surface = [&](const Json& mesh_index) {
    if (!mesh_index.is_number_unsigned() || !document.contains("meshes") ||
        mesh_index.get<std::size_t>() >= document["meshes"].size()) {
      return true;  // Not this function's to judge: validation names a bad index.
    }
    const Json& primitives = document["meshes"][mesh_index.get<std::size_t>()].value("primitives", Json::array());
    if (!primitives.is_array()) return true;
    return std::any_of(primitives.begin(), primitives.end(), [](const Json& primitive) {
      const Json mode = primitive.is_object() ? primitive.value("mode", Json(4)) : Json(4);
      return !mode.is_number_integer() || mode.get<int>() >= 4;
    });
  };
  // Whether a link node has geometry: a mesh with a surface of its own or below it before the
  // next link or joint (a marker empty beside the part under a joint empty is a link too, and
  // carries nothing).
  const auto has_geometry = [&](std::size_t link) {
    std::vector<std::size_t> stack{link};
    while (!stack.empty()) {
      const std::size_t at = stack.back();
      stack.pop_back();
      if (document["nodes"][at].contains("mesh") && has_surface(document["nodes"][at]["mesh"])) return true;
      for (const Json& child : document["nodes"][at].value("children", Json::array())) {
        const auto c = child.get<std::size_t>();
        if (types[c] != NodeType::kLink && types[c] != NodeType::kJoint) stack.push_back(c);
      }
    }
    return false;
  };
  for (std::size_t node = 0; node < types.size(); ++node) {
    if (types[node] != NodeType::kJoint) continue;
    const Json* entry = entries[node];
    const bool has_entry_joint = entry != nullptr && entry->contains("joint") && (*entry)["joint"].is_object();
    if (!has_entry_joint && !has_joint_keys(node_extras(document, node))) continue;
    // Among the links with geometry, one without a joint type of its own is the part; then one
    // that fixes itself (rdtf_joint 'fixed': rdtf's output writes that on the second jaw); last
    // one with a moving joint of its own, which then keeps it. So the choice does not hang on the
    // children's order, which Blender's importer sorts by name (a tyre and its hubcap under a
    // wheel's empty came back with the hubcap carrying the tyre).
    // (A joint told only by an extras.RDTF entry has its keys written on its frame node, which is
    // the part when the joint node has no transform of its own.)
    const Json entry_type =
        !has_joint_keys(node_extras(document, node)) && has_entry_joint ? (*entry)["joint"].value("type", Json()) : Json();
    const auto rank = [&](std::size_t link) {
      const Json* extras = node_extras(document, link);
      if (extras == nullptr || !extras->contains("rdtf_joint") || (*extras)["rdtf_joint"] == entry_type) return 0;
      return (*extras)["rdtf_joint"] == "fixed" ? 1 : 2;
    };
    int first = -1, chosen = -1, chosen_rank = 3;
    for (const Json& child : document["nodes"][node].value("children", Json::array())) {
      const auto c = child.get<std::size_t>();
      if (types[c] != NodeType::kLink) continue;
      if (first < 0) first = static_cast<int>(c);
      if (!has_geometry(c)) continue;
      if (const int r = rank(c); r < chosen_rank) {
        chosen = static_cast<int>(c);
        chosen_rank = r;
      }
    }
    carried[node] = chosen >= 0 ? chosen : first;
  }
  return carried;
}

}  // namespace

namespace {

// asset.generator, or "" when there is none.
std::string generator_of(const Json& document) {
  if (!document.contains("asset") || !document["asset"].is_object()) return {};
  const Json& asset = document["asset"];
  if (!asset.contains("generator") || !asset["generator"].is_string()) return {};
  return asset["generator"].get<std::string>();
}

std::optional<std::string> resaved_by(const Json& document) {
  if (auto packer = repacked_by(document)) return packer;
  // Editors and converters that load a file and write it again, keeping node extras (three.js's
  // userData, the three.js editor; Assimp; Babylon.js): a Blender export they re-save reads its
  // typed axes turned by 90 degrees (s90tools D2).
  const std::string generator = generator_of(document);
  // (Assimp signs "Open Asset Import Library (assimp v5.2.0)": s90rev R5.)
  for (const char* editor : {"THREE.GLTFExporter", "Open Asset Import Library", "Assimp", "Babylon.js", "babylon.js"}) {
    if (generator.rfind(editor, 0) == 0) return generator.substr(0, 80);
  }
  return std::nullopt;
}

}  // namespace

std::optional<std::string> repacked_by(const Json& document) {
  const std::string generator = generator_of(document);
  // Tools that rewrite a model (Draco's transcoder and decoder, Assimp's converter), not modellers:
  // what they drop is theirs to keep, not a Blender export setting.
  for (const char* packer : {"gltfpack", "glTF-Transform", "draco_transcoder", "draco_decoder",
                             "Open Asset Import Library"}) {
    if (generator.rfind(packer, 0) == 0) return generator.substr(0, 80);
  }
  return std::nullopt;
}


bool written_by_blender(const Json& document) {
  return generator_of(document).rfind("Khronos glTF Blender I/O", 0) == 0;
}

Eigen::Matrix3d blender_to_gltf_axes() {
  Eigen::Matrix3d C;
  C << 1, 0, 0, 0, 0, 1, 0, -1, 0;
  return C;
}

const char* to_string(JointKind kind) {
  switch (kind) {
    case JointKind::kFixed:
      return "fixed";
    case JointKind::kRevolute:
      return "revolute";
    case JointKind::kContinuous:
      return "continuous";
    case JointKind::kPrismatic:
      return "prismatic";
    case JointKind::kFloating:
      return "floating";
    case JointKind::kPlanar:
      return "planar";
    case JointKind::kBall:
      return "ball";
  }
  return "fixed";
}

std::optional<JointKind> joint_kind_from_string(const std::string& text) {
  for (JointKind kind : {JointKind::kFixed, JointKind::kRevolute, JointKind::kContinuous,
                         JointKind::kPrismatic, JointKind::kFloating, JointKind::kPlanar,
                         JointKind::kBall}) {
    if (text == to_string(kind)) return kind;
  }
  return std::nullopt;
}

Robot build_robot(const Json& document, const std::vector<NodeType>& types, std::size_t scene,
                  Diagnostics& diag) {
  Robot robot;
  const Json& scene_json = document["scenes"][scene];
  if (!document.contains("nodes")) return robot;
  const auto parents = node_parents(document);
  const auto world = node_world_transforms(document);
  std::vector<std::string> entry_pointers;
  const auto entries = rdtf_entries(document, entry_pointers);

  // A node's extras.RDTF joint object, if it has one.
  const auto entry_joint = [&](std::size_t node) -> const Json* {
    const Json* entry = entries[node];
    return entry != nullptr && entry->contains("joint") && (*entry)["joint"].is_object() ? &(*entry)["joint"] : nullptr;
  };
  // What each joint node with joint properties moves (carried_links, above).
  const std::vector<int> carried_link = carried_links(document, types, entries);

  // Links in pre-order of the scene, so parents come before children: a joint node's carried
  // link before its other children.
  std::vector<int> link_of_node(types.size(), -1);
  std::vector<std::size_t> stack;
  const Json roots = scene_json.value("nodes", Json::array());
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back(it->get<std::size_t>());
  std::vector<char> seen(types.size(), 0);
  while (!stack.empty()) {
    const std::size_t node = stack.back();
    stack.pop_back();
    if (seen[node]) continue;
    seen[node] = 1;
    if (types[node] == NodeType::kLink) {
      Link link;
      link.name = node_name(document, node);
      link.node = static_cast<int>(node);
      link.X_SL = rigid_part(world[node]);
      link_of_node[node] = static_cast<int>(robot.links.size());
      robot.links.push_back(std::move(link));
    }
    const Json children = document["nodes"][node].value("children", Json::array());
    for (auto it = children.rbegin(); it != children.rend(); ++it) {
      if (it->get<int>() != carried_link[node]) stack.push_back(it->get<std::size_t>());
    }
    if (carried_link[node] >= 0) stack.push_back(static_cast<std::size_t>(carried_link[node]));
  }

  std::vector<char> joint_node_used(types.size(), 0);  // passed on the way up from a link
  const auto is_frame_link = [&](int node) {
    const Json& json = document["nodes"][node];
    if (json.contains("mesh")) return false;
    for (const Json& c : json.value("children", Json::array())) {
      const NodeType type = types[c.get<std::size_t>()];
      if (type != NodeType::kInertial && type != NodeType::kVisual && type != NodeType::kNone) return false;
    }
    return true;
  };
  for (std::size_t c = 0; c < robot.links.size(); ++c) {
    Link& child = robot.links[c];
    // Walk up to the parent link, remembering the joint-typed nodes passed on the way; a joint
    // node that carries another link ends the walk at that link.
    std::vector<int> joint_nodes;
    int below = child.node;
    int up = parents[child.node];
    while (up >= 0 && types[up] != NodeType::kLink) {
      if (carried_link[up] >= 0 && carried_link[up] != below) break;
      if (types[up] == NodeType::kJoint) joint_nodes.push_back(up);
      below = up;
      up = parents[up];
    }
    if (up >= 0 && types[up] != NodeType::kLink) {
      const int joint_node = up;
      up = carried_link[joint_node];
      if (joint_nodes.empty()) {
        diag.info(codes::JOINT_MOVES_SEVERAL_LINKS, json_pointer("/nodes", joint_node),
                  "joint " + node_label(document, joint_node) + " moves '" + node_name(document, up) + "' and '" +
                      child.name + "' as one part: '" + child.name + "' hangs from '" + node_name(document, up) +
                      "' (by a fixed joint, unless it has joint properties of its own)");
      }
    }
    if (up < 0) {
      robot.root_links.push_back(static_cast<int>(c));
      continue;
    }
    Joint joint;
    joint.parent_link = link_of_node[up];
    joint.child_link = static_cast<int>(c);
    const Link& parent = robot.links[joint.parent_link];
    joint.node = joint_nodes.empty() ? -1 : joint_nodes.front();
    joint.name = joint.node >= 0 ? node_name(document, joint.node)
                                 : parent.name + "_" + child.name + "_joint";
    if (joint_nodes.size() > 1) {
      // Two joint nodes with properties and no link between them are two degrees of freedom the
      // model cannot have: only the nearest the child's are read (an empty stacked on an empty).
      // Counted by source: rdtf's output holds a joint's properties in its joint node's entry and,
      // for Blender, on another node's extras; that is one joint told twice, not two.
      std::vector<int> with_properties, with_entries;
      for (int node : joint_nodes) {
        if (has_joint_keys(node_extras(document, static_cast<std::size_t>(node)))) with_properties.push_back(node);
        if (entry_joint(static_cast<std::size_t>(node)) != nullptr) with_entries.push_back(node);
      }
      if (with_properties.size() < 2) with_properties = with_entries;
      if (with_properties.size() > 1) {
        std::string ignored;
        for (std::size_t i = 1; i < with_properties.size(); ++i) {
          ignored += (i > 1 ? ", " : "") + node_label(document, with_properties[i]);
        }
        diag.warning(codes::JOINT_CHAIN, json_pointer("/nodes", with_properties[1]),
                     std::to_string(joint_nodes.size()) + " joint nodes between links '" + parent.name + "' and '" +
                         child.name + "' make one joint, '" + node_name(document, with_properties.front()) +
                         "'; the joint properties of " + ignored +
                         " are not used: a joint moves a link, so parent the next joint node to a link (a part "
                         "with a mesh), not to a joint node");
      } else {
        diag.info(codes::JOINT_CHAIN, json_pointer("/nodes", joint_nodes.front()),
                  std::to_string(joint_nodes.size()) + " joint nodes between links '" + parent.name +
                      "' and '" + child.name + "': they make one joint");
      }
    }
    // The joint frame, and so the child link frame (URDF keeps them one), is the pivot the
    // modeller placed: the joint node nearest the child that has a transform of its own or joint
    // properties. Without one (rdtf's inserted joint nodes, URDF import's) it is the child link
    // node's frame. The geometry stays where it is: visuals and inertial are expressed in it.
    // A child that carries the joint properties itself, below joint nodes that carry none (a
    // camera's empty, fixed, under a plain mount empty), is its own pivot: the nodes between only
    // place it. Only node extras count here: rdtf's output holds every joint's properties in the
    // entry of its joint node (where the paper's readers look) and its keys on the frame node, so
    // an entry between is no pivot of its own where the child carries the keys (converting the
    // output again put the pivot at the mount, 0.1 m off; so did every armature Blender re-exported,
    // its importer turning the inserted joint node).
    joint.frame_node = child.node;
    // Unless an entry between names another joint type than the child's keys: those keys are stale
    // (RDTF_NODE_EXTRAS_IGNORED says so below), and what they say does not move the pivot.
    bool properties_between = false;
    for (int node : joint_nodes) properties_between = properties_between || has_joint_keys(node_extras(document, node));
    const Json* child_keys = node_extras(document, child.node);
    bool entry_disagrees = false;
    for (int node : joint_nodes) {
      const Json* entry = entry_joint(static_cast<std::size_t>(node));
      if (entry != nullptr && entry->is_object() && child_keys != nullptr && child_keys->contains("rdtf_joint") &&
          entry->value("type", Json()) != (*child_keys)["rdtf_joint"]) {
        entry_disagrees = true;
      }
    }
    const bool own_pivot = !properties_between && !entry_disagrees && has_joint_keys(child_keys);
    for (std::size_t k = 0; !own_pivot && k < joint_nodes.size(); ++k) {
      const int node = joint_nodes[k];
      if (has_own_transform(document["nodes"][node]) || has_joint_keys(node_extras(document, node))) {
        joint.frame_node = node;
        break;
      }
    }
    child.X_SL = rigid_part(world[joint.frame_node]);
    joint.X_PJ = parent.X_SL.inverse() * child.X_SL;

    // Sources of properties, first found wins: the RDTF entry of a joint node, then node extras
    // of the joint nodes (nearest the child first), then of the child link node.
    std::optional<JointSource> source;
    for (int node : joint_nodes) {
      if (const Json* joint_json = entry_joint(static_cast<std::size_t>(node))) {
        source = JointSource{joint_json, entry_pointers[node] + "/joint",
                             "entry for " + node_label(document, node), true, node, false};
        break;
      }
    }
    std::vector<int> extras_nodes = joint_nodes;
    extras_nodes.push_back(child.node);
    for (std::size_t i = 0; !source && i < extras_nodes.size(); ++i) {
      const Json* extras = node_extras(document, extras_nodes[i]);
      if (has_joint_keys(extras)) {
        source = JointSource{extras, json_pointer("/nodes", extras_nodes[i]) + "/extras",
                             node_label(document, extras_nodes[i]), false, extras_nodes[i],
                             reads_blender_axes(document, extras_nodes[i], diag)};
      }
    }
    joint.source_node = source ? source->frame_node : -1;
    joint.source_is_entry = source && source->rdtf_entry;
    // Read apart first: an entry with an invalid value holds a default in its place, which the
    // comparison with node extras below must not state as what the file says (s100err D3).
    Diagnostics read(diag.file());
    if (source) read_joint_properties(*source, world[source->frame_node], child.X_SL, joint, read);
    const bool entry_invalid = read.has_errors();
    diag.append(read);
    // A frame link (no mesh, nothing below it but its inertial or visual nodes: a camera's empty)
    // on a fixed joint is its own frame, wherever the joint's properties sit (a fixed mount empty
    // above holding two cameras): a fixed joint turns about nothing, and the frame is the link.
    if (joint.kind == JointKind::kFixed && joint.frame_node != child.node && is_frame_link(child.node)) {
      joint.frame_node = child.node;
      child.X_SL = rigid_part(world[child.node]);
      joint.X_PJ = parent.X_SL.inverse() * child.X_SL;
    }
    // The entry wins over node extras. A tool that keeps node extras only (Blender's importer)
    // would read the node extras instead, so say where they disagree.
    for (std::size_t i = 0; joint.source_is_entry && !entry_invalid && i < extras_nodes.size(); ++i) {
      const int node = extras_nodes[i];
      const Json* extras = node_extras(document, node);
      if (!has_joint_keys(extras)) continue;
      Diagnostics scratch;
      const JointSource shadow_source{extras, json_pointer("/nodes", node) + "/extras", node_label(document, node),
                                      false, node, reads_blender_axes(document, node, scratch)};
      Joint shadow = joint;
      shadow.kind = JointKind::kFixed;
      shadow.axis = Eigen::Vector3d::UnitX();
      shadow.limits.reset();
      shadow.damping = shadow.friction = shadow.spring_stiffness = 0;
      read_joint_properties(shadow_source, world[node], child.X_SL, shadow, scratch);
      std::optional<std::string> difference;
      if (const Diagnostic* error = scratch.first_error()) {
        difference = "an invalid value in node extras (" + error->message + ")";
      } else {
        difference = joint_properties_differ(shadow, joint);
      }
      if (difference) {
        joint.ignored_extras_node = node;
        diag.warning(codes::RDTF_NODE_EXTRAS_IGNORED, shadow_source.pointer,
                     shadow_source.label + ": joint '" + joint.name + "': " + *difference +
                         "; extras.RDTF takes precedence, and the output's node extras are rewritten to agree");
      }
      break;
    }
    // Joint keys on the child link node, below a joint node whose keys are read: they are not read
    // at all. Said where they say otherwise ("rdtf_lower": "abc" on the part, or limits typed on
    // the part and the empty alike but apart), or the modeller's edit on the part does nothing.
    if (source && !source->rdtf_entry && source->frame_node != child.node) {
      if (const Json* part_keys = node_extras(document, child.node); has_joint_keys(part_keys)) {
        std::string differing;
        int keys = 0;
        for (const char* key : kJointExtrasKeys) {
          if (!part_keys->contains(key)) continue;
          const Json& here = (*part_keys)[key];
          const bool there = source->values->contains(key);
          if (there && (*source->values)[key] == here) continue;
          ++keys;
          differing += (differing.empty() ? "" : ", ") + std::string(key) + " " + value_text(here) +
                       (there ? " (" + value_text((*source->values)[key]) + " there)" : " (not there)");
        }
        if (!differing.empty()) {
          diag.warning(codes::RDTF_NODE_EXTRAS_IGNORED, json_pointer("/nodes", child.node) + "/extras",
                       node_label(document, child.node) + ": joint '" + joint.name + "': " + differing +
                           (keys == 1 ? " is" : " are") + " not read: the joint's properties are those of " + source->label +
                           ", the joint node nearest the part that has any. Set them there, or only on the part");
        }
      }
    }
    for (int node : joint_nodes) joint_node_used[static_cast<std::size_t>(node)] = 1;
    child.parent_joint = static_cast<int>(robot.joints.size());
    robot.links[joint.parent_link].child_joints.push_back(child.parent_joint);
    robot.joints.push_back(std::move(joint));
  }
  // A joint node with joint properties that no link hangs below (a joint empty whose part was
  // parented elsewhere, or left out of the export) makes no joint: say so, or the joint the
  // modeller set up is simply missing from the robot.
  // A joint node at the top of the tree has a part below it but none above to turn on (a root
  // empty typed "floating", the source objects of a Blender collection instance).
  for (std::size_t node = 0; node < types.size(); ++node) {
    if (types[node] != NodeType::kJoint || !seen[node] || joint_node_used[node]) continue;
    if (entry_joint(node) == nullptr && !has_joint_keys(node_extras(document, node))) continue;
    bool link_above = false;
    for (int up = parents[node]; up >= 0 && !link_above; up = parents[up]) link_above = types[up] == NodeType::kLink;
    diag.warning(codes::JOINT_MOVES_NOTHING, json_pointer("/nodes", node),
                 "joint " + node_label(document, node) +
                     (link_above ? " has joint properties but no part hangs below it, so it makes no joint: parent the "
                                   "part it turns to it (in Blender, select the part, then the empty, Ctrl+P > Object)"
                                 : " has joint properties but no part above it, so it makes no joint: a joint turns the "
                                   "part below it on the part above it, and the top part of the tree is the robot's "
                                   "base, held by the world (free for a mobile robot: docs/format.md). Parent the "
                                   "empty to the part it turns on, or remove its joint properties"));
  }
  // A joint node's mass keys are not read: mass belongs to parts (rdtf_density on a mesh node or
  // between it and its link, rdtf_mass on a mesh or link node). A modeller who selected the joint
  // empty to type its properties puts the part's mass there too, and the part silently kept the
  // default density.
  for (std::size_t node = 0; node < types.size(); ++node) {
    if (types[node] != NodeType::kJoint || !seen[node] || document["nodes"][node].contains("mesh")) continue;
    const Json* extras = node_extras(document, node);
    if (extras == nullptr || (!extras->contains("rdtf_density") && !extras->contains("rdtf_mass"))) continue;
    std::string below;
    for (const Joint& joint : robot.joints) {
      if (joint.source_node == static_cast<int>(node)) below = robot.links[joint.child_link].name;
    }
    for (const char* key : {"rdtf_density", "rdtf_mass"}) {
      if (!extras->contains(key)) continue;
      diag.warning(codes::RDTF_NODE_EXTRAS_IGNORED, json_pointer("/nodes", node) + "/extras/" + key,
                   "joint " + node_label(document, node) + ": " + key + " is not read on a joint node, which has no "
                   "mass of its own; set it on the part" +
                       (below.empty() ? std::string(" (its mesh node, or its link)") : " '" + below + "' (the link below it)"));
    }
  }
  // Nor on a node without a mesh that is no link (an empty standing for a payload, a battery): it
  // has no shape to give the mass a volume and an inertia, and the mass was dropped without a word.
  for (std::size_t node = 0; node < types.size(); ++node) {
    if ((types[node] != NodeType::kVisual && types[node] != NodeType::kNone) || !seen[node] ||
        document["nodes"][node].contains("mesh")) {
      continue;
    }
    const Json* extras = node_extras(document, node);
    if (extras == nullptr || (!extras->contains("rdtf_density") && !extras->contains("rdtf_mass"))) continue;
    std::string rides_on;
    for (int up = parents[node]; up >= 0 && rides_on.empty(); up = parents[up]) {
      if (link_of_node[static_cast<std::size_t>(up)] >= 0) rides_on = robot.links[link_of_node[up]].name;
    }
    for (const char* key : {"rdtf_density", "rdtf_mass"}) {
      if (!extras->contains(key)) continue;
      diag.warning(codes::RDTF_NODE_EXTRAS_IGNORED, json_pointer("/nodes", node) + "/extras/" + key,
                   node_label(document, node) + ": " + key + " " + value_text((*extras)[key]) +
                       " is not read on a node without a mesh (it has no shape to give the mass a volume and an "
                       "inertia): count it in the rdtf_mass of the part it rides on" +
                       (rides_on.empty() ? std::string() : " ('" + rides_on + "')") +
                       ", or give the node a mesh of the payload's shape");
    }
  }
  if (robot.links.empty()) {
    diag.warning(codes::NO_LINKS, json_pointer("/scenes", scene),
                 "the scene has no link: nothing in it carries a mesh or children");
  }
  return robot;
}

std::vector<int> owning_link_nodes(const Json& document, const std::vector<NodeType>& types) {
  const std::size_t count = document.contains("nodes") ? std::min(document["nodes"].size(), types.size()) : 0;
  std::vector<int> owner(count, -1);
  if (count == 0) return owner;
  std::vector<std::string> pointers;
  const std::vector<int> carried = carried_links(document, types, rdtf_entries(document, pointers));
  const auto parents = node_parents(document);
  // Walked up once to the first node already answered, then filled in on the way back, so a
  // chain of n nodes costs n steps, not n^2.
  constexpr int kUnknown = -2;
  std::vector<int> answer(count, kUnknown);
  std::vector<std::size_t> path;
  for (std::size_t n = 0; n < count; ++n) {
    int found = -1;
    std::size_t below = n;
    for (int at = static_cast<int>(n); at >= 0; at = parents[static_cast<std::size_t>(at)]) {
      const auto a = static_cast<std::size_t>(at);
      // A joint node that carries a link: what hangs from it beside that link is that link's
      // (the joint node's own answer, remembered below, is the link above it).
      if (a != n && carried[a] >= 0 && static_cast<std::size_t>(carried[a]) != below) {
        found = carried[a];
        break;
      }
      if (answer[a] != kUnknown) {
        found = answer[a];
        break;
      }
      if (types[a] == NodeType::kLink) {
        found = at;
        answer[a] = found;
        break;
      }
      path.push_back(a);
      below = a;
    }
    for (std::size_t a : path) answer[a] = found;
    path.clear();
  }
  for (std::size_t n = 0; n < count; ++n) owner[n] = answer[n] == kUnknown ? -1 : answer[n];
  return owner;
}

}  // namespace rdtf
