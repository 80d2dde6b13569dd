// Small robots for the dynamics tests, built as values (no file): boxes of known mass and inertia
// on joints of each kind, with glTF node indices so that diagnostics can be checked to name them.
#pragma once

#include <gtest/gtest.h>

#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/diagnostics.h"
#include "rdtf/dynamics.h"
#include "rdtf/robot.h"

namespace rdtf::dynamics_test {

// A solid box of `mass` kg and edges `size` m along the link axes, its centre at `center` (link
// frame): I_cm = m/12 diag(y^2 + z^2, x^2 + z^2, x^2 + y^2).
inline MassProperties box_inertial(double mass, const Eigen::Vector3d& size,
                                   const Eigen::Vector3d& center = Eigen::Vector3d::Zero()) {
  MassProperties inertial;
  inertial.mass = mass;
  inertial.volume = size.prod();
  inertial.center_of_mass = center;
  const Eigen::Vector3d s2 = size.cwiseProduct(size);
  inertial.inertia = (mass / 12.0) * Eigen::Vector3d(s2.y() + s2.z(), s2.x() + s2.z(), s2.x() + s2.y()).asDiagonal();
  return inertial;
}

inline Eigen::Isometry3d translation(double x, double y, double z) {
  return Eigen::Isometry3d(Eigen::Translation3d(x, y, z));
}

// Builds a Robot as the converter would: node indices in creation order (links and joints share
// the glTF node numbering), parent/child cross references, X_SL from the joints at rest.
class RobotBuilder {
 public:
  // A root link at X_SL.
  int root(const std::string& name, const MassProperties& inertial,
           const Eigen::Isometry3d& X_SL = Eigen::Isometry3d::Identity()) {
    Link link;
    link.name = name;
    link.node = next_node_++;
    link.X_SL = X_SL;
    link.inertial = inertial;
    link.inertial_source = InertialSource::kAuthored;
    robot_.links.push_back(link);
    const int index = static_cast<int>(robot_.links.size()) - 1;
    robot_.root_links.push_back(index);
    return index;
  }

  // A child link of `parent` on joint `joint_name` (the joint node comes first, as in a glTF
  // where the joint empty is the child link's parent). Returns the child link's index.
  int child(int parent, const std::string& joint_name, JointKind kind, const Eigen::Isometry3d& X_PJ,
            const Eigen::Vector3d& axis, const std::string& name, const MassProperties& inertial) {
    Joint joint;
    joint.name = joint_name;
    joint.node = next_node_++;
    joint.kind = kind;
    joint.parent_link = parent;
    joint.X_PJ = X_PJ;
    joint.axis = axis;
    Link link;
    link.name = name;
    link.node = next_node_++;
    link.inertial = inertial;
    link.inertial_source = InertialSource::kAuthored;
    link.X_SL = robot_.links[parent].X_SL * X_PJ;
    const int j = static_cast<int>(robot_.joints.size());
    const int l = static_cast<int>(robot_.links.size());
    joint.child_link = l;
    link.parent_joint = j;
    robot_.joints.push_back(joint);
    robot_.links.push_back(link);
    robot_.links[parent].child_joints.push_back(j);
    return l;
  }

  Joint& joint(int j) { return robot_.joints[j]; }
  Link& link(int l) { return robot_.links[l]; }
  const Robot& robot() const { return robot_; }

 private:
  Robot robot_;
  int next_node_ = 0;
};

// A three-link arm like the arm3 fixture: a 2 kg base held by the world, an upper arm and a
// forearm (1 kg, 0.5 kg boxes hanging along -Y) on revolute joints about Z with limits +-1.5 rad
// (shoulder) and none (elbow, continuous).
// Links: base (node 0), shoulder (1), upper_arm (2), elbow (3), forearm (4).
inline RobotBuilder arm_builder() {
  RobotBuilder b;
  const int base = b.root("base", box_inertial(2.0, {0.2, 0.2, 0.2}));
  const int upper = b.child(base, "shoulder", JointKind::kRevolute, translation(0, -0.1, 0), Eigen::Vector3d::UnitZ(),
                            "upper_arm", box_inertial(1.0, {0.05, 0.4, 0.05}, {0, -0.2, 0}));
  b.joint(0).limits = JointLimits{-1.5, 1.5, 0, 0};
  b.child(upper, "elbow", JointKind::kContinuous, translation(0, -0.4, 0), Eigen::Vector3d::UnitZ(), "forearm",
          box_inertial(0.5, {0.04, 0.3, 0.04}, {0, -0.15, 0}));
  return b;
}

// The diagnostics with `code`.
inline std::vector<Diagnostic> with_code(const Diagnostics& diag, const std::string& code) {
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == code) found.push_back(d);
  }
  return found;
}

inline std::string all_text(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += format(d) + "\n";
  return text;
}

// A simulation of `robot` that must build without errors (a test failure names them).
inline std::unique_ptr<Simulation> simulate(const Robot& robot, const SimulationOptions& options,
                                            const std::map<std::string, double>& initial = {}) {
  Diagnostics diag;
  auto sim = Simulation::create(robot, options, initial, diag);
  EXPECT_FALSE(diag.has_errors()) << all_text(diag);
  if (!sim) throw std::runtime_error("the model was not built");
  return sim;
}

// Exactly one error `code`, at glTF node `node`, its message naming `name`.
inline void expect_one_error(const Diagnostics& diag, const std::string& code, int node, const std::string& name) {
  const std::vector<Diagnostic> found = with_code(diag, code);
  ASSERT_EQ(found.size(), 1u) << code << " expected once in:\n" << all_text(diag);
  EXPECT_EQ(found[0].severity, Severity::kError) << format(found[0]);
  EXPECT_EQ(found[0].pointer, "/nodes/" + std::to_string(node)) << format(found[0]);
  EXPECT_NE(found[0].message.find("'" + name + "'"), std::string::npos) << format(found[0]);
}

}  // namespace rdtf::dynamics_test
