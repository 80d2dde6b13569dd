#include "robot_models.h"

#include <stdexcept>

#include "rdtf/convert.h"

namespace rdtf::bench {
namespace {

constexpr double kLinkMass = 0.5;               // kg
const Eigen::Vector3d kLinkSize{0.04, 0.2, 0.04};  // m, along the link axes
constexpr double kLinkLength = 0.2;             // m between a link's joint and its children's

// A solid box hanging along -Y from its link origin: I_cm = m/12 diag(y^2 + z^2, x^2 + z^2, x^2 + y^2).
MassProperties hanging_box() {
  MassProperties inertial;
  inertial.mass = kLinkMass;
  inertial.volume = kLinkSize.prod();
  inertial.center_of_mass = Eigen::Vector3d(0, -kLinkLength / 2, 0);
  const Eigen::Vector3d s2 = kLinkSize.cwiseProduct(kLinkSize);
  inertial.inertia = (kLinkMass / 12.0) * Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()).asDiagonal();
  return inertial;
}

// Node indices in creation order (joint node, then its child link), as the converter assigns them.
class RobotBuilder {
 public:
  explicit RobotBuilder(const std::string& name) { robot_.name = name; }

  void root() {
    Link link;
    link.name = "link_0";
    link.node = next_node_++;
    link.inertial = hanging_box();
    link.inertial_source = InertialSource::kAuthored;
    robot_.links.push_back(link);
    robot_.root_links.push_back(0);
  }

  // A revolute joint at the lower end of `parent`, about Z for even link numbers and X for odd.
  void child(int parent) {
    const int l = static_cast<int>(robot_.links.size());
    const int j = static_cast<int>(robot_.joints.size());
    Joint joint;
    joint.name = "joint_" + std::to_string(l);
    joint.node = next_node_++;
    joint.kind = JointKind::kRevolute;
    joint.parent_link = parent;
    joint.child_link = l;
    joint.X_PJ = Eigen::Isometry3d(Eigen::Translation3d(0, -kLinkLength, 0));
    joint.axis = l % 2 == 0 ? Eigen::Vector3d::UnitZ() : Eigen::Vector3d::UnitX();
    joint.limits = JointLimits{-3.0, 3.0, 0, 0};
    joint.damping = 0.01;
    Link link;
    link.name = "link_" + std::to_string(l);
    link.node = next_node_++;
    link.parent_joint = j;
    link.inertial = hanging_box();
    link.inertial_source = InertialSource::kAuthored;
    link.X_SL = robot_.links[parent].X_SL * joint.X_PJ;
    robot_.joints.push_back(joint);
    robot_.links.push_back(link);
    robot_.links[parent].child_joints.push_back(j);
  }

  Robot take() { return std::move(robot_); }

 private:
  Robot robot_;
  int next_node_ = 0;
};

}  // namespace

Robot chain_robot(int links) {
  RobotBuilder builder("chain_" + std::to_string(links));
  builder.root();
  for (int l = 1; l < links; ++l) builder.child(l - 1);
  return builder.take();
}

Robot tree_robot(int links) {
  RobotBuilder builder("tree_" + std::to_string(links));
  builder.root();
  for (int l = 1; l < links; ++l) builder.child((l - 1) / 2);
  return builder.take();
}

Robot arm3_robot() {
  const std::filesystem::path path = std::filesystem::path(RDTF_BENCH_DATA_DIR) / "blender" / "arm3.gltf";
  Diagnostics diag;
  auto conversion = convert_file(path, ConvertOptions{}, diag);
  if (!conversion) throw std::runtime_error("cannot convert " + path.string());
  return std::move(conversion->robot);
}

std::map<std::string, double> bent_pose(const Robot& robot, double angle) {
  std::map<std::string, double> pose;
  for (const Joint& joint : robot.joints) {
    if (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kContinuous) pose[joint.name] = angle;
  }
  return pose;
}

}  // namespace rdtf::bench
