// The structural pre-check of a URDF, so that bad input gets an error naming the element and
// its line (urdfdom only logs a sentence, and accepts some broken trees: a link with two parents,
// a loop beside a proper tree).
#include <map>
#include <set>

#include <tinyxml.h>

#include "import_internal.h"

namespace rdtf::urdf_internal {
namespace {

const std::set<std::string>& known_joint_types() {
  static const std::set<std::string> types{"fixed",    "revolute", "continuous",
                                           "prismatic", "floating", "planar"};
  return types;
}

std::string line(int row) { return "line " + std::to_string(row) + ": "; }

std::string attribute(const TiXmlElement* e, const char* name) {
  const char* value = e->Attribute(name);
  return value != nullptr ? value : "";
}

// The link named in <parent link=...> or <child link=...>.
std::string link_reference(const TiXmlElement* joint, const char* which) {
  const TiXmlElement* e = joint->FirstChildElement(which);
  return e != nullptr ? attribute(e, "link") : "";
}

bool check_tree(XmlRobot& robot, Diagnostics& diag) {
  std::map<std::string, std::size_t> link_index;
  for (std::size_t i = 0; i < robot.links.size(); ++i) link_index[robot.links[i].name] = i;
  std::vector<int> parent_joint(robot.links.size(), -1);
  bool ok = true;
  for (std::size_t j = 0; j < robot.joints.size(); ++j) {
    const XmlJoint& joint = robot.joints[j];
    const std::size_t child = link_index.at(joint.child);
    if (parent_joint[child] >= 0) {
      const XmlJoint& first = robot.joints[parent_joint[child]];
      diag.error("URDF_LINK_TWO_PARENTS", joint_pointer(joint.name),
                 line(joint.row) + "link '" + joint.child + "' is the child of joint '" + joint.name +
                     "' and of joint '" + first.name + "' (line " + std::to_string(first.row) +
                     "): a URDF is a tree, each link has one parent");
      ok = false;
      continue;
    }
    parent_joint[child] = static_cast<int>(j);
  }
  if (!ok) return false;
  // Walk up from every link; a walk that comes back to a link it passed is a loop.
  // Links known to reach a root are not walked again, so this is linear in the number of links.
  std::vector<char> reported(robot.links.size(), 0), reaches_root(robot.links.size(), 0);
  std::vector<std::size_t> walk_of(robot.links.size(), 0);  // Which walk passed the link (start + 1).
  for (std::size_t start = 0; start < robot.links.size(); ++start) {
    std::vector<std::size_t> path;
    std::size_t at = start;
    while (parent_joint[at] >= 0 && walk_of[at] != start + 1 && !reaches_root[at] && !reported[at]) {
      walk_of[at] = start + 1;
      path.push_back(at);
      at = link_index.at(robot.joints[parent_joint[at]].parent);
    }
    if (parent_joint[at] < 0 || reaches_root[at]) {
      for (std::size_t p : path) reaches_root[p] = 1;
      continue;
    }
    if (reported[at]) continue;
    // `at` is on a loop: name its joints, starting there.
    std::string joints;
    std::size_t l = at;
    int first_row = robot.joints[parent_joint[at]].row;
    do {
      reported[l] = 1;
      const XmlJoint& joint = robot.joints[parent_joint[l]];
      joints += (joints.empty() ? "" : ", ") + ("'" + joint.name + "'");
      l = link_index.at(joint.parent);
    } while (l != at);
    diag.error("URDF_JOINT_LOOP", joint_pointer(robot.joints[parent_joint[at]].name),
               line(first_row) + "joints " + joints + " form a loop (link '" + robot.links[at].name +
                   "' is its own ancestor): a URDF is a tree");
    ok = false;
  }
  if (!ok) return false;
  std::vector<std::string> roots;
  for (std::size_t i = 0; i < robot.links.size(); ++i) {
    if (parent_joint[i] < 0) {
      if (roots.empty()) robot.root = i;
      roots.push_back("'" + robot.links[i].name + "' (line " + std::to_string(robot.links[i].row) + ")");
    }
  }
  if (roots.size() > 1) {
    std::string names;
    for (const std::string& r : roots) names += (names.empty() ? "" : ", ") + r;
    diag.error("URDF_MULTIPLE_ROOTS", "/robot",
               std::to_string(roots.size()) + " links have no parent joint: " + names +
                   "; a URDF has exactly one root link");
    return false;
  }
  return true;
}

}  // namespace

std::string link_pointer(const std::string& name) { return "/robot/link[@name='" + name + "']"; }
std::string joint_pointer(const std::string& name) { return "/robot/joint[@name='" + name + "']"; }

std::optional<XmlRobot> scan_urdf_xml(const std::string& text, Diagnostics& diag) {
  TiXmlDocument document;
  document.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (document.Error()) {
    diag.error("URDF_MALFORMED_XML", "",
               line(document.ErrorRow()) + "column " + std::to_string(document.ErrorCol()) +
                   ": malformed XML: " + document.ErrorDesc());
    return std::nullopt;
  }
  const TiXmlElement* robot_element = document.RootElement();
  if (robot_element == nullptr || std::string(robot_element->Value()) != "robot") {
    diag.error("URDF_NOT_A_ROBOT", "",
               "the root element is <" + std::string(robot_element ? robot_element->Value() : "") +
                   ">, not <robot>: this is not a URDF");
    return std::nullopt;
  }
  XmlRobot robot;
  bool ok = true;
  std::set<std::string> link_names, joint_names;
  for (const TiXmlElement* e = robot_element->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    XmlLink link{attribute(e, "name"), e->Row(), {}, {}, 0};
    if (link.name.empty()) {
      diag.error("URDF_INVALID", "/robot/link", line(e->Row()) + "a <link> has no name");
      ok = false;
      continue;
    }
    if (!link_names.insert(link.name).second) {
      diag.error("URDF_DUPLICATE_NAME", link_pointer(link.name),
                 line(e->Row()) + "a second link is named '" + link.name + "'");
      ok = false;
      continue;
    }
    for (const TiXmlElement* v = e->FirstChildElement("visual"); v; v = v->NextSiblingElement("visual")) {
      link.visual_rows.push_back(v->Row());
    }
    for (const TiXmlElement* c = e->FirstChildElement("collision"); c; c = c->NextSiblingElement("collision")) {
      link.collision_rows.push_back(c->Row());
    }
    if (const TiXmlElement* inertial = e->FirstChildElement("inertial")) link.inertial_row = inertial->Row();
    robot.links.push_back(std::move(link));
  }
  for (const TiXmlElement* e = robot_element->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    XmlJoint joint{attribute(e, "name"), attribute(e, "type"), link_reference(e, "parent"),
                   link_reference(e, "child"), e->Row()};
    const std::string pointer = joint.name.empty() ? "/robot/joint" : joint_pointer(joint.name);
    if (joint.name.empty()) {
      diag.error("URDF_INVALID", pointer, line(e->Row()) + "a <joint> has no name");
      ok = false;
      continue;
    }
    if (!joint_names.insert(joint.name).second) {
      diag.error("URDF_DUPLICATE_NAME", pointer, line(e->Row()) + "a second joint is named '" + joint.name + "'");
      ok = false;
      continue;
    }
    if (!known_joint_types().count(joint.type)) {
      diag.error("URDF_UNKNOWN_JOINT_TYPE", pointer,
                 line(e->Row()) + "joint '" + joint.name + "' has type '" + joint.type +
                     "'; URDF's types are fixed, revolute, continuous, prismatic, floating and planar");
      ok = false;
    }
    for (const auto& [which, link] : {std::pair<const char*, const std::string&>{"parent", joint.parent},
                                      std::pair<const char*, const std::string&>{"child", joint.child}}) {
      if (link.empty()) {
        diag.error("URDF_INVALID", pointer,
                   line(e->Row()) + "joint '" + joint.name + "' has no <" + which + " link=\"...\"/>");
        ok = false;
      } else if (!link_names.count(link)) {
        diag.error("URDF_UNKNOWN_LINK", pointer,
                   line(e->Row()) + "joint '" + joint.name + "' names " + which + " link '" + link +
                       "', which no <link> defines");
        ok = false;
      }
    }
    if (!joint.parent.empty() && joint.parent == joint.child) {
      diag.error("URDF_JOINT_LOOP", pointer,
                 line(e->Row()) + "joint '" + joint.name + "' joins link '" + joint.parent + "' to itself");
      ok = false;
    }
    robot.joints.push_back(std::move(joint));
  }
  if (robot.links.empty() && ok) {
    diag.error("URDF_INVALID", "/robot", "the robot has no <link>");
    return std::nullopt;
  }
  if (!ok || !check_tree(robot, diag)) return std::nullopt;
  return robot;
}

}  // namespace rdtf::urdf_internal
