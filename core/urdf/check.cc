#include <urdf_parser/urdf_parser.h>

#include "urdf_check.h"
#include "urdf_internal.h"

namespace rdtf::urdf_internal {
namespace {

class Comparison {
 public:
  void number(const std::string& where, double ours, double read) {
    // Bit for bit (both zeros count as equal: -0 is written as 0).
    if (!(ours == read) && why_.empty()) {
      why_ = where + " is " + exact_number(ours) + " but reads back as " + exact_number(read);
    }
  }
  void vector(const std::string& where, const urdf::Vector3& ours, const urdf::Vector3& read) {
    number(where + ".x", ours.x, read.x);
    number(where + ".y", ours.y, read.y);
    number(where + ".z", ours.z, read.z);
  }
  void pose(const std::string& where, const urdf::Pose& ours, const urdf::Pose& read) {
    vector(where + " xyz", ours.position, read.position);
    number(where + " rotation.x", ours.rotation.x, read.rotation.x);
    number(where + " rotation.y", ours.rotation.y, read.rotation.y);
    number(where + " rotation.z", ours.rotation.z, read.rotation.z);
    number(where + " rotation.w", ours.rotation.w, read.rotation.w);
  }
  void truth(const std::string& what, bool ok) {
    if (!ok && why_.empty()) why_ = what;
  }
  const std::string& why() const { return why_; }

 private:
  std::string why_;
};

void compare_link(const urdf::Link& ours, const urdf::Link& read, Comparison& c) {
  const std::string where = "link '" + ours.name + "'";
  c.truth(where + ": inertial present or not", !ours.inertial == !read.inertial);
  if (ours.inertial && read.inertial) {
    const urdf::Inertial& a = *ours.inertial;
    const urdf::Inertial& b = *read.inertial;
    c.number(where + " mass", a.mass, b.mass);
    c.pose(where + " inertial origin", a.origin, b.origin);
    c.number(where + " ixx", a.ixx, b.ixx);
    c.number(where + " ixy", a.ixy, b.ixy);
    c.number(where + " ixz", a.ixz, b.ixz);
    c.number(where + " iyy", a.iyy, b.iyy);
    c.number(where + " iyz", a.iyz, b.iyz);
    c.number(where + " izz", a.izz, b.izz);
  }
  c.truth(where + ": visual count", ours.visual_array.size() == read.visual_array.size());
  c.truth(where + ": collision count", ours.collision_array.size() == read.collision_array.size());
}

void compare_joint(const urdf::Joint& ours, const urdf::Joint& read, Comparison& c) {
  const std::string where = "joint '" + ours.name + "'";
  c.truth(where + ": type", ours.type == read.type);
  c.truth(where + ": parent", ours.parent_link_name == read.parent_link_name);
  c.truth(where + ": child", ours.child_link_name == read.child_link_name);
  c.pose(where + " origin", ours.parent_to_joint_origin_transform, read.parent_to_joint_origin_transform);
  if (ours.type != urdf::Joint::FIXED && ours.type != urdf::Joint::FLOATING) {
    c.vector(where + " axis", ours.axis, read.axis);
  }
  c.truth(where + ": limits present or not", !ours.limits == !read.limits);
  if (ours.limits && read.limits) {
    c.number(where + " lower", ours.limits->lower, read.limits->lower);
    c.number(where + " upper", ours.limits->upper, read.limits->upper);
    c.number(where + " effort", ours.limits->effort, read.limits->effort);
    c.number(where + " velocity", ours.limits->velocity, read.limits->velocity);
  }
  c.truth(where + ": dynamics present or not", !ours.dynamics == !read.dynamics);
  if (ours.dynamics && read.dynamics) {
    c.number(where + " damping", ours.dynamics->damping, read.dynamics->damping);
    c.number(where + " friction", ours.dynamics->friction, read.dynamics->friction);
  }
}

}  // namespace

bool reads_back_exactly(const std::string& text, const urdf::ModelInterface& model, std::string& why) {
  urdf::ModelInterfaceSharedPtr read;
  const urdf_internal::FlatRelease flat_release(read);
  const std::string messages = with_console_captured([&] { read = urdf::parseURDF(text); });
  if (!read) {
    why = "urdfdom cannot parse it: " + messages;
    return false;
  }
  Comparison c;
  c.truth("robot name", read->getName() == model.getName());
  c.truth("number of links", read->links_.size() == model.links_.size());
  c.truth("number of joints", read->joints_.size() == model.joints_.size());
  c.truth("root link", read->getRoot() && model.getRoot() && read->getRoot()->name == model.getRoot()->name);
  for (const auto& [name, link] : model.links_) {
    const auto found = read->links_.find(name);
    c.truth("link '" + name + "' is missing", found != read->links_.end());
    if (found != read->links_.end()) compare_link(*link, *found->second, c);
  }
  for (const auto& [name, joint] : model.joints_) {
    const auto found = read->joints_.find(name);
    c.truth("joint '" + name + "' is missing", found != read->joints_.end());
    if (found != read->joints_.end()) compare_joint(*joint, *found->second, c);
  }
  why = c.why();
  return why.empty();
}

}  // namespace rdtf::urdf_internal
