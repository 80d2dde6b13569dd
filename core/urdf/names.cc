#include "rdtf/urdf_names.h"

#include "rdtf/diagnostic_codes.h"

#include "urdf_internal.h"

namespace rdtf {

UrdfNames urdf_names(const Robot& robot, Diagnostics* diag) {
  using urdf_internal::unique_name;
  using urdf_internal::valid_urdf_name;
  UrdfNames names;
  std::vector<std::string> taken_links, taken_joints;
  auto choose = [&](const std::string& name, int node, const char* what, std::vector<std::string>& taken) {
    const std::string chosen = unique_name(valid_urdf_name(name, what), taken);
    if (diag != nullptr && chosen != name) {
      diag->warning(codes::URDF_NAME_CHANGED, node >= 0 ? json_pointer("/nodes", static_cast<std::size_t>(node)) : "",
                    std::string(what) + " '" + name + "' is named '" + chosen +
                        "' in the URDF (URDF names here are unique and use letters, digits, '_', "
                        "'-' and '.')");
    }
    return chosen;
  };
  names.links.reserve(robot.links.size());
  for (const Link& link : robot.links) names.links.push_back(choose(link.name, link.node, "link", taken_links));
  names.joints.reserve(robot.joints.size());
  for (const Joint& joint : robot.joints) names.joints.push_back(choose(joint.name, joint.node, "joint", taken_joints));
  return names;
}

}  // namespace rdtf
