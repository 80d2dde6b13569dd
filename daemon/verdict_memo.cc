#include "verdict_memo.h"

#include <algorithm>
#include <cstring>

namespace rdtf::daemon {
namespace {

// A field added to these types must be compared below, or a robot that differs in it would
// reuse a verdict computed for another robot: the sizes catch the addition (on the platform CI
// builds on; elsewhere the sizes may differ and the check is left out).
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(LinkMesh) == 24, "a field was added to LinkMesh: compare it in same_robot");
static_assert(sizeof(MassProperties) == 112, "a field was added to MassProperties: compare it in same_robot");
static_assert(sizeof(Link) == 336, "a field was added to Link: compare it in same_robot");
static_assert(sizeof(JointLimits) == 32, "a field was added to JointLimits: compare it in same_robot");
static_assert(sizeof(Joint) == 288, "a field was added to Joint: compare it in same_robot");
static_assert(sizeof(Robot) == 104, "a field was added to Robot: compare it in same_robot");
#endif

// Bit for bit: the check's arithmetic on two doubles of the same bits is the same.
bool same_bits(const double* a, const double* b, std::size_t count) {
  return std::memcmp(a, b, count * sizeof(double)) == 0;
}
bool same(double a, double b) { return same_bits(&a, &b, 1); }
template <typename Matrix>
bool same(const Matrix& a, const Matrix& b) {
  return same_bits(a.data(), b.data(), static_cast<std::size_t>(a.size()));
}

bool same(const MassProperties& a, const MassProperties& b) {
  return same(a.volume, b.volume) && same(a.mass, b.mass) && same(a.center_of_mass, b.center_of_mass) &&
         same(a.inertia, b.inertia);
}

bool same(const LinkMesh& a, const LinkMesh& b) {
  return a.node == b.node && same(a.volume, b.volume) && same(a.density, b.density);
}

bool same(const Link& a, const Link& b) {
  return a.name == b.name && a.node == b.node && a.parent_joint == b.parent_joint &&
         a.child_joints == b.child_joints && same(a.X_SL.matrix(), b.X_SL.matrix()) &&
         std::equal(a.meshes.begin(), a.meshes.end(), b.meshes.begin(), b.meshes.end(),
                    [](const LinkMesh& x, const LinkMesh& y) { return same(x, y); }) &&
         same(a.inertial, b.inertial) && a.inertial_source == b.inertial_source && a.inertial_node == b.inertial_node;
}

bool same(const std::optional<JointLimits>& a, const std::optional<JointLimits>& b) {
  if (a.has_value() != b.has_value()) return false;
  return !a || (same(a->lower, b->lower) && same(a->upper, b->upper) && same(a->effort, b->effort) &&
                same(a->velocity, b->velocity));
}

bool same(const Joint& a, const Joint& b) {
  return a.name == b.name && a.node == b.node && a.frame_node == b.frame_node && a.source_node == b.source_node &&
         a.source_is_entry == b.source_is_entry && a.parent_link == b.parent_link && a.child_link == b.child_link &&
         a.kind == b.kind && same(a.X_PJ.matrix(), b.X_PJ.matrix()) && same(a.axis, b.axis) &&
         same(a.limits, b.limits) && same(a.damping, b.damping) && same(a.friction, b.friction) &&
         same(a.spring_stiffness, b.spring_stiffness);
}

}  // namespace

bool same_robot(const Robot& a, const Robot& b) {
  return a.name == b.name && a.root_links == b.root_links &&
         std::equal(a.links.begin(), a.links.end(), b.links.begin(), b.links.end(),
                    [](const Link& x, const Link& y) { return same(x, y); }) &&
         std::equal(a.joints.begin(), a.joints.end(), b.joints.begin(), b.joints.end(),
                    [](const Joint& x, const Joint& y) { return same(x, y); });
}

bool same_bounds(const LinkBounds& a, const LinkBounds& b) {
  return std::equal(a.begin(), a.end(), b.begin(), b.end(),
                    [](const std::optional<Eigen::AlignedBox3d>& x, const std::optional<Eigen::AlignedBox3d>& y) {
                      if (x.has_value() != y.has_value()) return false;
                      return !x || (same(x->min(), y->min()) && same(x->max(), y->max()));
                    });
}

bool verdict_applies(const VerdictMemo& memo, const std::string& source, const std::string& settings_key,
                     const Robot& robot, const LinkBounds& bounds) {
  return !memo.settings_key.empty() && memo.settings_key == settings_key && memo.source == source &&
         same_robot(memo.robot, robot) && same_bounds(memo.bounds, bounds);
}

}  // namespace rdtf::daemon
