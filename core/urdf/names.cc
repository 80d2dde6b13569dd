#include "rdtf/urdf_names.h"

#include <unordered_map>
#include <unordered_set>

#include "rdtf/diagnostic_codes.h"

#include "urdf_internal.h"

namespace rdtf {

namespace {

// URDF names for one kind (links or joints), in robot order. A name URDF can hold as it is keeps
// it, whatever comes before it: a controller's configuration, an SRDF or a JOINT_COMMAND that
// names "elbow_joint" must reach the joint called so, not one called "elbow joint" that sanitises
// alike and happens to come first. The others become valid and take the first free suffix.
std::vector<std::string> choose_names(const std::vector<std::pair<const std::string*, int>>& items, const char* what,
                                      Diagnostics* diag) {
  using urdf_internal::valid_urdf_name;
  std::vector<std::string> chosen(items.size());
  std::unordered_set<std::string> taken;
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::string& name = *items[i].first;
    if (valid_urdf_name(name, what) == name && taken.insert(name).second) chosen[i] = name;
  }
  // Per name, the suffix to try next: every one below it was taken when last asked, and taken
  // names stay taken, so the first free one is the same as counting from 2 again (which made
  // 40,000 links of one name cost 40,000^2 / 2 tries, on rdtfd's loop at each publication).
  std::unordered_map<std::string, int> next_suffix;
  for (std::size_t i = 0; i < items.size(); ++i) {
    if (!chosen[i].empty()) continue;
    const std::string& name = *items[i].first;
    const std::string valid = valid_urdf_name(name, what);
    const auto [next, first] = next_suffix.try_emplace(valid, 2);
    std::string candidate = valid;
    if (!first || taken.count(valid) != 0) {  // After a first ask, `valid` is always taken.
      int n = next->second;
      while (taken.count(candidate = valid + "_" + std::to_string(n)) != 0) ++n;
      next->second = n + 1;
    }
    taken.insert(candidate);
    chosen[i] = candidate;
    if (diag != nullptr) {
      const int node = items[i].second;
      diag->warning(codes::URDF_NAME_CHANGED, node >= 0 ? json_pointer("/nodes", static_cast<std::size_t>(node)) : "",
                    std::string(what) + " '" + name + "' is named '" + candidate +
                        "' in the URDF (URDF names here are unique and use ASCII letters, digits, '_', "
                        "'-' and '.')");
    }
  }
  return chosen;
}

}  // namespace

UrdfNames urdf_names(const Robot& robot, Diagnostics* diag) {
  std::vector<std::pair<const std::string*, int>> links, joints;
  for (const Link& link : robot.links) links.emplace_back(&link.name, link.node);
  for (const Joint& joint : robot.joints) joints.emplace_back(&joint.name, joint.node);
  UrdfNames names;
  names.links = choose_names(links, "link", diag);
  names.joints = choose_names(joints, "joint", diag);
  return names;
}

}  // namespace rdtf
