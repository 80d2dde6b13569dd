// The result cache's entry as text, and back (result_cache.h). Doubles go through JSON's shortest
// round-trip form, so a robot read back is bit for bit the one written; a value JSON cannot carry
// (not finite) makes the entry unreadable, which only costs a conversion.
#include <cmath>

#include <nlohmann/json.hpp>

#include "json_bytes.h"
#include "rdtf/diagnostics_json.h"
#include "result_cache.h"
#include "revision_store.h"

namespace rdtf::daemon {
namespace {

using Json = nlohmann::json;

constexpr std::string_view kFormat = "rdtfd-results 4";  // As kCacheFormat (result_cache.cc)

struct Refused {
  std::string why;
};

const Json& at(const Json& object, const char* key) {
  if (!object.is_object() || !object.contains(key)) throw Refused{std::string("no '") + key + "'"};
  return object[key];
}

double number(const Json& value) {
  if (!value.is_number()) throw Refused{"a number is missing or not finite"};
  return value.get<double>();
}

int integer(const Json& value) {
  if (!value.is_number_integer()) throw Refused{"an index is not an integer"};
  return value.get<int>();
}

std::string text(const Json& value) {
  if (!value.is_string()) throw Refused{"a text is not a string"};
  return value.get<std::string>();
}

std::string file_name(const Json& value) {
  auto bytes = bytes_from_json(value);
  if (!bytes) throw Refused{"a file name is neither text nor {\"hex\": ...}"};
  return std::move(*bytes);
}

bool flag(const Json& value) {
  if (!value.is_boolean()) throw Refused{"a flag is not a boolean"};
  return value.get<bool>();
}

// A pose as 12 numbers: the rotation row by row, then the translation.
Json pose_json(const Eigen::Isometry3d& X) {
  Json out = Json::array();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.push_back(X.linear()(r, c));
  }
  for (int r = 0; r < 3; ++r) out.push_back(X.translation()(r));
  return out;
}

Eigen::Isometry3d pose_from(const Json& j) {
  if (!j.is_array() || j.size() != 12) throw Refused{"a pose needs 12 numbers"};
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X.linear()(r, c) = number(j[static_cast<std::size_t>(3 * r + c)]);
  }
  for (int r = 0; r < 3; ++r) X.translation()(r) = number(j[static_cast<std::size_t>(9 + r)]);
  return X;
}

template <typename Vector>
Json vector_json(const Vector& v) {
  Json out = Json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(v(i));
  return out;
}

Json robot_json(const Robot& robot) {
  Json links = Json::array();
  for (const Link& l : robot.links) {
    Json meshes = Json::array();
    for (const LinkMesh& m : l.meshes) meshes.push_back({m.node, m.volume, m.density});
    Json inertia = Json::array();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) inertia.push_back(l.inertial.inertia(r, c));
    }
    links.push_back({{"name", l.name}, {"node", l.node}, {"parent_joint", l.parent_joint},
                     {"child_joints", l.child_joints}, {"x_sl", pose_json(l.X_SL)}, {"meshes", meshes},
                     {"volume", l.inertial.volume}, {"mass", l.inertial.mass},
                     {"center_of_mass", vector_json(l.inertial.center_of_mass)}, {"inertia", inertia},
                     {"authored", l.inertial_source == InertialSource::kAuthored}, {"inertial_node", l.inertial_node},
                     {"ignored_inertial_extras", l.ignored_inertial_extras}});
  }
  Json joints = Json::array();
  for (const Joint& j : robot.joints) {
    Json limits = nullptr;
    if (j.limits) limits = {j.limits->lower, j.limits->upper, j.limits->effort, j.limits->velocity, j.limits->position};
    joints.push_back({{"name", j.name}, {"node", j.node}, {"frame_node", j.frame_node}, {"source_node", j.source_node},
                      {"source_is_entry", j.source_is_entry}, {"ignored_extras_node", j.ignored_extras_node},
                      {"parent_link", j.parent_link},
                      {"child_link", j.child_link}, {"kind", to_string(j.kind)}, {"x_pj", pose_json(j.X_PJ)},
                      {"axis", vector_json(j.axis)}, {"limits", limits}, {"damping", j.damping},
                      {"friction", j.friction}, {"spring_stiffness", j.spring_stiffness}});
  }
  return {{"name", robot.name}, {"links", links}, {"joints", joints}, {"root_links", robot.root_links}};
}

std::vector<int> indices(const Json& j) {
  if (!j.is_array()) throw Refused{"a list of indices is not an array"};
  std::vector<int> out;
  for (const Json& v : j) out.push_back(integer(v));
  return out;
}

Robot robot_from(const Json& j) {
  Robot robot;
  robot.name = text(at(j, "name"));
  robot.root_links = indices(at(j, "root_links"));
  for (const Json& l : at(j, "links")) {
    Link link;
    link.name = text(at(l, "name"));
    link.node = integer(at(l, "node"));
    link.parent_joint = integer(at(l, "parent_joint"));
    link.child_joints = indices(at(l, "child_joints"));
    link.X_SL = pose_from(at(l, "x_sl"));
    for (const Json& m : at(l, "meshes")) {
      if (!m.is_array() || m.size() != 3) throw Refused{"a link mesh needs 3 values"};
      link.meshes.push_back({integer(m[0]), number(m[1]), number(m[2])});
    }
    link.inertial.volume = number(at(l, "volume"));
    link.inertial.mass = number(at(l, "mass"));
    const Json& com = at(l, "center_of_mass");
    const Json& inertia = at(l, "inertia");
    if (!com.is_array() || com.size() != 3 || !inertia.is_array() || inertia.size() != 9) {
      throw Refused{"a centre of mass needs 3 numbers and an inertia 9"};
    }
    for (std::size_t i = 0; i < 3; ++i) link.inertial.center_of_mass(static_cast<Eigen::Index>(i)) = number(com[i]);
    for (std::size_t i = 0; i < 9; ++i) {
      link.inertial.inertia(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = number(inertia[i]);
    }
    link.inertial_source = flag(at(l, "authored")) ? InertialSource::kAuthored : InertialSource::kComputed;
    link.inertial_node = integer(at(l, "inertial_node"));
    link.ignored_inertial_extras = flag(at(l, "ignored_inertial_extras"));
    robot.links.push_back(std::move(link));
  }
  for (const Json& j2 : at(j, "joints")) {
    Joint joint;
    joint.name = text(at(j2, "name"));
    joint.node = integer(at(j2, "node"));
    joint.frame_node = integer(at(j2, "frame_node"));
    joint.source_node = integer(at(j2, "source_node"));
    joint.source_is_entry = flag(at(j2, "source_is_entry"));
    joint.ignored_extras_node = integer(at(j2, "ignored_extras_node"));
    joint.parent_link = integer(at(j2, "parent_link"));
    joint.child_link = integer(at(j2, "child_link"));
    const auto kind = joint_kind_from_string(text(at(j2, "kind")));
    if (!kind) throw Refused{"unknown joint kind"};
    joint.kind = *kind;
    joint.X_PJ = pose_from(at(j2, "x_pj"));
    const Json& axis = at(j2, "axis");
    if (!axis.is_array() || axis.size() != 3) throw Refused{"an axis needs 3 numbers"};
    for (std::size_t i = 0; i < 3; ++i) joint.axis(static_cast<Eigen::Index>(i)) = number(axis[i]);
    const Json& limits = at(j2, "limits");
    if (!limits.is_null()) {
      if (!limits.is_array() || limits.size() != 5 || !limits[4].is_boolean()) {
        throw Refused{"limits need 4 numbers and whether the range was given"};
      }
      joint.limits = JointLimits{number(limits[0]), number(limits[1]), number(limits[2]), number(limits[3]),
                                 limits[4].get<bool>()};
    }
    joint.damping = number(at(j2, "damping"));
    joint.friction = number(at(j2, "friction"));
    joint.spring_stiffness = number(at(j2, "spring_stiffness"));
    robot.joints.push_back(std::move(joint));
  }
  // Indices that point outside the robot would make a later reader index out of bounds.
  const auto links = static_cast<int>(robot.links.size()), joints = static_cast<int>(robot.joints.size());
  auto check = [](int index, int size, bool may_be_none) {
    if (index >= size || index < (may_be_none ? -1 : 0)) throw Refused{"an index is out of range"};
  };
  for (int root : robot.root_links) check(root, links, false);
  for (const Link& l : robot.links) {
    check(l.parent_joint, joints, true);
    for (int c : l.child_joints) check(c, joints, false);
  }
  for (const Joint& jt : robot.joints) {
    check(jt.parent_link, links, false);
    check(jt.child_link, links, false);
  }
  return robot;
}

// diagnostics_json's form with each file named byte for byte (json_bytes.h), so that a result
// read back names the model file it named (a name that is not UTF-8 came back with U+FFFD).
Json diagnostics_with_files(const Diagnostics& diagnostics) {
  Json out = diagnostics_json(diagnostics);
  for (std::size_t i = 0; i < out.size() && i < diagnostics.all().size(); ++i) {
    out[i]["file"] = bytes_to_json(diagnostics.all()[i].file);
  }
  return out;
}

// Only the fields a diagnostic carries through the daemon (diagnostics_json.h's form).
Diagnostics diagnostics_from(const Json& j, const std::string& file) {
  if (!j.is_array()) throw Refused{"diagnostics are not an array"};
  Diagnostics out(file);
  for (const Json& d : j) {
    const std::string severity = text(at(d, "severity"));
    Severity s = Severity::kInfo;
    if (severity == "error") {
      s = Severity::kError;
    } else if (severity == "warning") {
      s = Severity::kWarning;
    } else if (severity != "info") {
      throw Refused{"unknown severity"};
    }
    out.set_file(file_name(at(d, "file")));
    const std::string code = text(at(d, "code")), pointer = text(at(d, "pointer")), message = text(at(d, "message"));
    const int line = d.contains("line") ? integer(d["line"]) : 0;
    const std::string line_prefix = "line " + std::to_string(line) + ": ";
    if (d.contains("byteOffset") && s == Severity::kError && d["byteOffset"].is_number_unsigned()) {
      out.error_at_offset(code, d["byteOffset"].get<std::uint64_t>(), message);
    } else if (line > 0 && message.rfind(line_prefix, 0) == 0) {
      // add_at_line puts "line N: " before the message: the stored message has it already.
      out.add_at_line(s, code, pointer, line, message.substr(line_prefix.size()));
    } else if (d.contains("byteOffset") || line != 0) {
      throw Refused{"a diagnostic's place is malformed"};
    } else {
      out.add(s, code, pointer, message);
    }
  }
  out.set_file(file);
  return out;
}

Json validation_json(const ValidationSummary& v) {
  return {{"passed", v.passed}, {"simulated_time", v.simulated_time}, {"steps", v.steps},
          {"energy_drift", v.energy_drift}, {"worst_joint_error", v.worst_joint_error},
          {"wall_time", v.wall_time}, {"summary_line", v.summary_line},
          {"live_stepper", v.live_stepper == Stepper::kWorldStep   ? "world_step"
                           : v.live_stepper == Stepper::kQuickStep ? "quick_step"
                                                                   : "auto"},
          {"after_quickstep_failed", v.after_quickstep_failed},
          {"diagnostics", diagnostics_json(v.diagnostics)}};
}

ValidationSummary validation_from(const Json& j) {
  ValidationSummary v;
  v.passed = flag(at(j, "passed"));
  v.simulated_time = number(at(j, "simulated_time"));
  if (!at(j, "steps").is_number_unsigned()) throw Refused{"steps is not a count"};
  v.steps = j["steps"].get<std::uint64_t>();
  v.energy_drift = number(at(j, "energy_drift"));
  v.worst_joint_error = number(at(j, "worst_joint_error"));
  v.wall_time = number(at(j, "wall_time"));
  v.summary_line = text(at(j, "summary_line"));
  const std::string stepper = text(at(j, "live_stepper"));
  if (stepper != "world_step" && stepper != "quick_step" && stepper != "auto") throw Refused{"live_stepper is no stepper"};
  v.live_stepper = stepper == "world_step" ? Stepper::kWorldStep : stepper == "quick_step" ? Stepper::kQuickStep : Stepper::kAuto;
  v.after_quickstep_failed = flag(at(j, "after_quickstep_failed"));
  v.diagnostics = diagnostics_from(at(j, "diagnostics"), "");
  return v;
}

}  // namespace

std::string cache_entry_text(const CachedResult& r) {
  Json files = Json::array();
  for (const OutputFile& f : r.files) files.push_back({bytes_to_json(f.path), f.sha256, f.size, f.role});
  // The names of files byte for byte (json_bytes.h): a model named in bytes that are not UTF-8
  // finds its entry again after a restart.
  const Json body = {{"key", r.key}, {"source", bytes_to_json(r.source)}, {"content_hash", r.content_hash},
                     {"written", r.written}, {"output_name", bytes_to_json(r.output_name)}, {"rdtf_sha256", r.rdtf_sha256},
                     {"has_urdf", r.has_urdf}, {"urdf_sha256", r.urdf_sha256}, {"files", files},
                     {"validation", r.validation ? validation_json(*r.validation) : Json(nullptr)},
                     {"diagnostics", diagnostics_with_files(r.diagnostics)}, {"robot", robot_json(r.robot)},
                     {"facts", facts_to_json(r.facts)}};
  // Other text that is not UTF-8 is replaced.
  const std::string text = body.dump(-1, ' ', false, Json::error_handler_t::replace);
  return std::string(kFormat) + " " + sha256_hex(text) + "\n" + text;
}

std::optional<CachedResult> cache_entry_from_text(std::string_view all, std::string& why) {
  const std::size_t newline = all.find('\n');
  const std::size_t digest_at = kFormat.size() + 1;
  if (newline == std::string_view::npos || newline != digest_at + 64 || all.substr(0, kFormat.size()) != kFormat ||
      all[kFormat.size()] != ' ') {
    why = "not a result entry (no '" + std::string(kFormat) + " <sha256>' first line): torn or of another format";
    return std::nullopt;
  }
  const std::string_view body = all.substr(newline + 1);
  if (sha256_hex(body) != all.substr(digest_at, 64)) {
    why = "its checksum does not match its " + std::to_string(body.size()) + " bytes: torn or altered";
    return std::nullopt;
  }
  try {
    const Json j = Json::parse(body.begin(), body.end());
    CachedResult r;
    r.key = text(at(j, "key"));
    r.source = file_name(at(j, "source"));
    r.content_hash = text(at(j, "content_hash"));
    r.written = flag(at(j, "written"));
    r.output_name = file_name(at(j, "output_name"));
    r.rdtf_sha256 = text(at(j, "rdtf_sha256"));
    r.has_urdf = flag(at(j, "has_urdf"));
    r.urdf_sha256 = text(at(j, "urdf_sha256"));
    for (const Json& f : at(j, "files")) {
      if (!f.is_array() || f.size() != 4 || !f[2].is_number_integer()) throw Refused{"a file needs 4 values"};
      r.files.push_back({file_name(f[0]), text(f[1]), f[2].get<std::int64_t>(), text(f[3])});
    }
    if (!at(j, "validation").is_null()) r.validation = validation_from(j["validation"]);
    r.diagnostics = diagnostics_from(at(j, "diagnostics"), r.source);
    r.robot = robot_from(at(j, "robot"));
    std::string facts_why;
    auto facts = facts_from_json(at(j, "facts"), facts_why);
    if (!facts) throw Refused{"facts: " + facts_why};
    r.facts = std::move(*facts);
    return r;
  } catch (const Refused& refused) {
    why = "malformed: " + refused.why;
  } catch (const std::exception& error) {
    why = std::string("malformed: ") + error.what();
  }
  return std::nullopt;
}

}  // namespace rdtf::daemon
