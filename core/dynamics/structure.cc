// The robot's tree as the dynamics code needs it: order, roots, kinematics, reach, and where the
// massless links go.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "ode_model.h"

namespace rdtf::dynamics_internal {

std::string number(double value) { return format_number(value); }

std::string vector_text(const Eigen::Vector3d& v) {
  return "(" + number(v.x()) + ", " + number(v.y()) + ", " + number(v.z()) + ")";
}

std::string node_pointer(int node) { return node >= 0 ? json_pointer("/nodes", node) : std::string(); }

const char* kind_name(JointKind kind) { return to_string(kind); }

bool one_dof(JointKind kind) {
  return kind == JointKind::kRevolute || kind == JointKind::kContinuous ||
         kind == JointKind::kPrismatic;
}

bool is_massless(const Link& link) {
  return link.inertial.mass == 0 && link.inertial.inertia.isZero(0);
}

bool is_point_mass(const MassProperties& inertial, double extent) {
  if (!(inertial.mass > 0) || !std::isfinite(inertial.mass) || !inertial.inertia.allFinite()) return false;
  const double rounding = 4 * std::numeric_limits<double>::epsilon() * inertial.mass * extent * extent;
  return inertial.inertia.cwiseAbs().maxCoeff() <= rounding;
}

long adding_links(const Robot& robot, const WeldGroup& group) {
  return std::count_if(group.links.begin(), group.links.end(), [&](int l) {
    const MassProperties& m = robot.links[static_cast<std::size_t>(l)].inertial;
    return m.mass != 0 || !m.inertia.isZero(0);
  });
}

int largest_island(const Robot& robot, const WeldGroups& welds) {
  const std::size_t groups = welds.groups.size();
  std::vector<std::size_t> root(groups);
  for (std::size_t g = 0; g < groups; ++g) root[g] = g;
  const auto find = [&root](std::size_t g) {
    while (root[g] != g) g = root[g] = root[root[g]];
    return g;
  };
  for (const Joint& joint : robot.joints) {
    if (joint.kind == JointKind::kFixed || joint.kind == JointKind::kFloating || joint.kind == JointKind::kPlanar) {
      continue;
    }
    const auto a = static_cast<std::size_t>(welds.group_of[joint.parent_link]);
    const auto b = static_cast<std::size_t>(welds.group_of[joint.child_link]);
    if (!moves(welds.groups[a]) || !moves(welds.groups[b])) continue;
    root[find(b)] = find(a);
  }
  std::vector<int> count(groups, 0);
  int largest = 0;
  for (std::size_t g = 0; g < groups; ++g) {
    if (moves(welds.groups[g])) largest = std::max(largest, ++count[find(g)]);
  }
  return largest;
}

bool check_structure(const Robot& robot, const char* code, Diagnostics& diag) {
  const int links = static_cast<int>(robot.links.size());
  const int joints = static_cast<int>(robot.joints.size());
  const std::size_t before = diag.error_count();
  for (int j = 0; j < joints; ++j) {
    const Joint& joint = robot.joints[j];
    const std::string where = node_pointer(joint.node);
    if (joint.parent_link < 0 || joint.parent_link >= links || joint.child_link < 0 ||
        joint.child_link >= links || joint.parent_link == joint.child_link) {
      diag.error(code, where, "joint '" + joint.name + "' refers to links " +
                                  std::to_string(joint.parent_link) + " -> " +
                                  std::to_string(joint.child_link) + " of " + std::to_string(links));
      continue;
    }
    if (robot.links[joint.child_link].parent_joint != j) {
      diag.error(code, where, "joint '" + joint.name + "' has child link '" +
                                  robot.links[joint.child_link].name +
                                  "' whose parent joint is another");
    }
  }
  if (diag.error_count() > before) return false;
  for (int l = 0; l < links; ++l) {
    const Link& link = robot.links[l];
    if (link.parent_joint >= joints || (link.parent_joint >= 0 && robot.joints[link.parent_joint].child_link != l)) {
      diag.error(code, node_pointer(link.node),
                 "link '" + link.name + "' has parent joint " + std::to_string(link.parent_joint) +
                     ", which does not have it as its child");
    }
  }
  if (diag.error_count() > before) return false;
  // Every chain of parents ends within `links` steps, or there is a cycle.
  for (int l = 0; l < links; ++l) {
    int at = l;
    int steps = 0;
    while (robot.links[at].parent_joint >= 0 && steps <= links) {
      at = robot.joints[robot.links[at].parent_joint].parent_link;
      ++steps;
    }
    if (steps > links) {
      diag.error(code, node_pointer(robot.links[l].node),
                 "link '" + robot.links[l].name + "' is on a cycle of joints");
      return false;
    }
  }
  return true;
}

std::vector<int> tree_order(const Robot& robot) {
  std::vector<std::vector<int>> children(robot.links.size());
  for (const Joint& joint : robot.joints) children[joint.parent_link].push_back(joint.child_link);
  std::vector<int> order;
  order.reserve(robot.links.size());
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (robot.links[l].parent_joint >= 0) continue;
    std::vector<int> stack{static_cast<int>(l)};
    while (!stack.empty()) {
      const int at = stack.back();
      stack.pop_back();
      order.push_back(at);
      for (auto it = children[at].rbegin(); it != children[at].rend(); ++it) stack.push_back(*it);
    }
  }
  return order;
}

std::vector<int> root_of(const Robot& robot, const std::vector<int>& order) {
  std::vector<int> root(robot.links.size(), -1);
  for (int l : order) {
    const int pj = robot.links[l].parent_joint;
    root[l] = pj < 0 ? l : root[robot.joints[pj].parent_link];
  }
  return root;
}

WeldGroups weld_groups(const Robot& robot, const std::vector<int>& order,
                       const std::vector<Eigen::Isometry3d>& rest, bool floating_root, double bound_mass,
                       double bound_inertia) {
  WeldGroups out;
  out.group_of.assign(robot.links.size(), -1);
  // Parents come first in tree order: a link on a fixed joint joins its parent's group, any other
  // link starts one.
  for (int l : order) {
    const int pj = robot.links[l].parent_joint;
    if (pj >= 0 && robot.joints[pj].kind == JointKind::kFixed) {
      const int g = out.group_of[robot.joints[pj].parent_link];
      out.group_of[l] = g;
      out.groups[g].links.push_back(l);
      continue;
    }
    WeldGroup group;
    group.top = l;
    group.links.push_back(l);
    group.welded_to_world = pj < 0 && !floating_root;
    out.group_of[l] = static_cast<int>(out.groups.size());
    out.groups.push_back(std::move(group));
  }
  Eigen::AlignedBox3d box;
  for (std::size_t l = 0; l < robot.links.size(); ++l) {
    if (!rest[l].matrix().allFinite()) continue;
    box.extend(rest[l].translation());
    if (robot.links[l].inertial.center_of_mass.allFinite()) box.extend(rest[l] * robot.links[l].inertial.center_of_mass);
  }
  out.extent = box.isEmpty() ? 0 : box.diagonal().norm();
  for (WeldGroup& group : out.groups) {
    const Eigen::Isometry3d X_TS = rest[group.top].inverse();
    // Two passes: the centre of mass, then every inertia about it (parallel-axis theorem), so that
    // no large offset is subtracted from a sum about a far point.
    double mass = 0;
    Eigen::Vector3d moment = Eigen::Vector3d::Zero();
    for (int l : group.links) {
      const MassProperties& in = robot.links[l].inertial;
      if (!(in.mass > 0) || !std::isfinite(in.mass) || !in.center_of_mass.allFinite() || !in.inertia.allFinite()) {
        continue;
      }
      const Eigen::Isometry3d X_TL = X_TS * rest[l];
      mass += in.mass;
      moment += in.mass * (X_TL * in.center_of_mass);
    }
    if (mass > 0) {
      const Eigen::Vector3d p_ToBcm_T = moment / mass;
      Eigen::Matrix3d I_Bcm_T = Eigen::Matrix3d::Zero();
      // A link of mass 0 with an inertia (pybullet's Panda hangs 0 kg, 0.1 kg m^2 frames on its
      // flange) adds its inertia alone, as MuJoCo's fusestatic adds it: it has no centre of mass
      // to carry.
      for (int l : group.links) {
        const MassProperties& in = robot.links[l].inertial;
        if (!(in.mass >= 0) || !std::isfinite(in.mass) || !in.center_of_mass.allFinite() || !in.inertia.allFinite()) {
          continue;
        }
        const Eigen::Isometry3d X_TL = X_TS * rest[l];
        const Eigen::Matrix3d R_TL = X_TL.linear();
        const Eigen::Vector3d d = X_TL * in.center_of_mass - p_ToBcm_T;  // Lcm from Bcm, in T
        const Eigen::Matrix3d I_Lcm_L = 0.5 * (in.inertia + in.inertia.transpose());
        I_Bcm_T += R_TL * I_Lcm_L * R_TL.transpose() +
                   in.mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
      }
      group.merged.mass = mass;
      group.merged.center_of_mass = p_ToBcm_T;
      group.merged.inertia = I_Bcm_T;
    } else if (!group.welded_to_world && bound_mass > 0 && bound_inertia > 0) {
      group.merged.mass = bound_mass;
      group.merged.inertia = bound_inertia * Eigen::Matrix3d::Identity();
      group.bounded = true;
    }
  }
  return out;
}

bool moves(const WeldGroup& group) { return !group.welded_to_world && group.merged.mass > 0; }

Eigen::Isometry3d joint_motion(const Joint& joint, double q) {
  Eigen::Isometry3d X = joint.X_PJ;
  if (q == 0 || joint.axis.norm() == 0) return X;
  const Eigen::Vector3d axis = joint.axis.normalized();
  if (joint.kind == JointKind::kRevolute || joint.kind == JointKind::kContinuous) {
    X.rotate(Eigen::AngleAxisd(q, axis));
  } else if (joint.kind == JointKind::kPrismatic) {
    X.translate(q * axis);
  }
  return X;
}

std::vector<Eigen::Isometry3d> forward_kinematics(const Robot& robot, const std::vector<int>& order,
                                                  const std::vector<double>& q) {
  std::vector<Eigen::Isometry3d> X(robot.links.size(), Eigen::Isometry3d::Identity());
  for (int l : order) {
    const int pj = robot.links[l].parent_joint;
    if (pj < 0) {
      X[l] = robot.links[l].X_SL;
    } else {
      const Joint& joint = robot.joints[pj];
      X[l] = X[joint.parent_link] * joint_motion(joint, q[pj]);
    }
  }
  return X;
}

std::vector<double> reach_bounds(const Robot& robot, const std::vector<int>& order) {
  std::vector<double> reach(robot.links.size(), 0.0);
  for (int l : order) {
    const int pj = robot.links[l].parent_joint;
    if (pj < 0) continue;
    const Joint& joint = robot.joints[pj];
    double travel = 0;
    if (joint.kind == JointKind::kPrismatic) {
      travel = position_limited(joint) ? std::max(std::abs(joint.limits->lower), std::abs(joint.limits->upper))
                                       : kInfinity;
    } else if (joint.kind == JointKind::kFloating || joint.kind == JointKind::kPlanar) {
      travel = kInfinity;
    }
    reach[l] = reach[joint.parent_link] + joint.X_PJ.translation().norm() + travel;
  }
  return reach;
}

}  // namespace rdtf::dynamics_internal
