// The pre-check of a URDF, so that bad input gets an error naming the element, the attribute and
// its line. urdfdom only logs a sentence, accepts some broken trees (a link with two parents, a
// loop beside a proper tree), and (3.0) keeps a link whose <inertial>, <visual> or <collision> it
// could not read, with a zero mass or without that geometry. So every attribute import depends on
// is read here, as urdfdom reads it, and checked: present where urdfdom requires it, numbers where
// numbers are due, finite, and in the range that means something.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <map>
#include <set>
#include <string_view>

#include <tinyxml.h>

#include "import_internal.h"
#include "urdf_internal.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::urdf_internal {
namespace {

const std::set<std::string>& known_joint_types() {
  static const std::set<std::string> types{"fixed",    "revolute", "continuous",
                                           "prismatic", "floating", "planar"};
  return types;
}


std::string attribute(const TiXmlElement* e, const char* name) {
  const char* value = e->Attribute(name);
  return value != nullptr ? value : "";
}

// The link named in <parent link=...> or <child link=...>.
std::string link_reference(const TiXmlElement* joint, const char* which) {
  const TiXmlElement* e = joint->FirstChildElement(which);
  return e != nullptr ? attribute(e, "link") : "";
}

// An attribute's text in a message: control characters escaped, and cut short when long.
std::string shown(std::string_view text) {
  constexpr std::size_t kLongest = 80;
  std::string out;
  for (std::size_t i = 0; i < text.size() && i < kLongest; ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c == '\t') {
      out += "\\t";
    } else if (c == '\n') {
      out += "\\n";
    } else if (c < 0x20 || c == 0x7f) {
      static const char* const kHex = "0123456789abcdef";
      out += std::string("\\x") + kHex[c >> 4] + kHex[c & 15];
    } else {
      out += static_cast<char>(c);
    }
  }
  if (text.size() > kLongest) out += "...";
  return out;
}

// The first xacro substitution in `text` ("$(find pkg)", "${pi/2}"), up to its closing bracket
// (or the end when unclosed); empty when there is none.
std::string_view xacro_expression(std::string_view text) {
  for (std::size_t i = 0; i + 1 < text.size(); ++i) {
    if (text[i] != '$' || (text[i + 1] != '(' && text[i + 1] != '{')) continue;
    const char close = text[i + 1] == '(' ? ')' : '}';
    const std::size_t end = text.find(close, i + 2);
    return text.substr(i, end == std::string_view::npos ? std::string_view::npos : end + 1 - i);
  }
  return {};
}

// Whether a decimal number that is beyond double's range is tiny (an underflow) rather than huge:
// its order of magnitude (digits before the point, or minus the zeros after it, plus the exponent)
// is not above 0.
bool underflows(std::string_view text) {
  std::size_t i = (!text.empty() && (text[0] == '-' || text[0] == '+')) ? 1 : 0;
  long long order = 0;
  bool nonzero = false, after_point = false;
  for (; i < text.size() && text[i] != 'e' && text[i] != 'E'; ++i) {
    if (text[i] == '.') {
      after_point = true;
    } else if (nonzero) {
      if (!after_point) ++order;  // A further digit before the point.
    } else if (text[i] != '0') {
      nonzero = true;
      if (!after_point) ++order;  // The first significant digit, before the point.
    } else if (after_point) {
      --order;  // A zero between the point and the first significant digit.
    }
  }
  long long exponent = 0;
  bool negative = false;
  if (i < text.size()) ++i;
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) negative = text[i++] == '-';
  for (; i < text.size(); ++i) exponent = std::min<long long>(exponent * 10 + (text[i] - '0'), 1'000'000'000);
  return order + (negative ? -exponent : exponent) <= 0;
}

enum class NumberError { kNone, kNotANumber, kNotFinite, kBeyondDouble };

// One number as urdfdom reads it (C locale, an optional sign, digits, a fraction, an exponent).
// Like urdfdom, a number too small for a double reads as 0; too large is an error.
NumberError parse_number(std::string_view text, double& value) {
  if (!text.empty() && text[0] == '+') {
    text.remove_prefix(1);
    if (!text.empty() && (text[0] == '+' || text[0] == '-')) return NumberError::kNotANumber;
  }
  const char* end = text.data() + text.size();
  const auto [stop, error] = std::from_chars(text.data(), end, value);
  if (error == std::errc::invalid_argument || stop != end || text.empty()) return NumberError::kNotANumber;
  if (error == std::errc::result_out_of_range) {
    if (!underflows(text)) return NumberError::kBeyondDouble;
    value = 0;
  }
  return std::isfinite(value) ? NumberError::kNone : NumberError::kNotFinite;
}

enum class Range { kAny, kNonNegative, kPositive, kUnit, kNonZero, kSize, kScale };

// The largest size or scale a shape may have, in metres: a million kilometres. Beyond it a box's
// volume and inertia overflow double (1e200 made them infinite, and the import failed inside the
// glTF it builds, at a pointer into a file the user never saw).
constexpr double kLargestSize = 1e9;

// What an attribute holds: how many numbers, their range, and what one is ("a mass") for messages.
struct Rule {
  std::size_t count;
  Range range;
  const char* what;
};

constexpr const char* kInvalidNumber = codes::URDF_INVALID_NUMBER;
constexpr const char* kInvalidInertial = codes::URDF_INVALID_INERTIAL;

// Reads and checks attributes, reporting each problem (every one, not only the first) with the
// attribute's pointer ("/robot/joint[@name='elbow']/limit/@effort") and the element's line.
class Checker {
 public:
  explicit Checker(Diagnostics& diag) : diag_(diag) {}
  bool ok() const { return ok_; }

  void error(const char* code, const std::string& pointer, int row, const std::string& message) {
    diag_.error_at_line(code, pointer, row, message);
    ok_ = false;
  }

  // The `rule.count` numbers of attribute `name` of `e` (several are separated by spaces, as
  // urdfdom splits them), each finite and in range; nothing (and an error under `code`) when they
  // are not, or when the attribute is missing and `required` (URDF_INVALID, or
  // URDF_INVALID_INERTIAL inside an <inertial>).
  std::optional<std::vector<double>> numbers(const TiXmlElement* e, const std::string& pointer, const char* name,
                                             const Rule& rule, bool required, const char* code = kInvalidNumber) {
    const char* value = e->Attribute(name);
    const std::string element = "<" + std::string(e->Value());
    if (value == nullptr) {
      if (required) {
        error(code == kInvalidInertial ? kInvalidInertial : codes::URDF_INVALID, pointer, e->Row(),
              element + "> has no " + name + " attribute, which URDF requires");
      }
      return std::nullopt;
    }
    const std::string at = pointer + "/@" + name;
    const std::string said = element + " " + name + "=\"" + shown(value) + "\">: ";
    // `$(arg x)` or `${pi/2}` left in a value: the file was saved before xacro expanded it (or
    // by a tool that copied a .urdf.xacro's text), which counting numbers would not say.
    if (const std::string_view expression = xacro_expression(value); !expression.empty()) {
      error(code, at, e->Row(),
            said + "'" + shown(expression) +
                "' is a xacro expression, not a number: expand the file with xacro first (xacro robot.urdf.xacro > robot.urdf)");
      return std::nullopt;
    }
    std::vector<std::string_view> pieces;
    std::string_view text(value);
    if (rule.count == 1) {
      // urdfdom skips leading white space before a single number, not trailing.
      while (!text.empty() && std::isspace(static_cast<unsigned char>(text.front()))) text.remove_prefix(1);
      pieces.push_back(text);
    } else {
      for (std::size_t start = 0; start <= text.size();) {
        const std::size_t space = std::min(text.find(' ', start), text.size());
        if (space > start) pieces.push_back(text.substr(start, space - start));
        start = space + 1;
      }
    }
    if (pieces.size() != rule.count) {
      error(code, at, e->Row(),
            said + std::to_string(rule.count) + " numbers separated by spaces expected, " +
                std::to_string(pieces.size()) + " found");
      return std::nullopt;
    }
    std::vector<double> out;
    for (const std::string_view piece : pieces) {
      const std::string quoted = "'" + shown(piece) + "'";
      double number = 0;
      switch (parse_number(piece, number)) {
        case NumberError::kNotANumber:
          error(code, at, e->Row(), said + quoted + " is not a number");
          return std::nullopt;
        case NumberError::kNotFinite:
          error(code, at, e->Row(), said + quoted + " is not a finite number");
          return std::nullopt;
        case NumberError::kBeyondDouble:
          error(code, at, e->Row(), said + quoted + " is beyond the range of a double");
          return std::nullopt;
        case NumberError::kNone:
          break;
      }
      std::string why;
      switch (rule.range) {
        case Range::kAny:
          break;
        case Range::kNonNegative:
          if (number < 0) why = " is negative: " + std::string(rule.what) + " is 0 or more";
          break;
        case Range::kPositive:
          if (!(number > 0)) why = " is not positive: " + std::string(rule.what) + " is greater than 0";
          break;
        case Range::kUnit:
          if (number < 0 || number > 1) why = " is outside 0..1: " + std::string(rule.what) + " is between 0 and 1";
          break;
        case Range::kNonZero:
          if (number == 0) why = " is zero: " + std::string(rule.what) + " of 0 flattens the shape";
          break;
        case Range::kSize:
          if (number < 0) why = " is negative: " + std::string(rule.what) + " is 0 or more";
          if (number > kLargestSize) why = " is over 1e9 m: no robot part is that large (a size in other units?)";
          break;
        case Range::kScale:
          if (number == 0) why = " is zero: " + std::string(rule.what) + " of 0 flattens the shape";
          if (std::abs(number) > kLargestSize) why = " is over 1e9: no robot part is scaled that much";
          break;
      }
      if (!why.empty()) {
        error(code, at, e->Row(), said + quoted + why);
        return std::nullopt;
      }
      out.push_back(number);
    }
    return out;
  }

 private:
  Diagnostics& diag_;
  bool ok_ = true;
};

const Rule kPosition{3, Range::kAny, "a position"};
const Rule kAngles{3, Range::kAny, "an angle"};
const Rule kAnyNumber{1, Range::kAny, "a number"};

void check_origin(Checker& c, const TiXmlElement* parent, const std::string& pointer, const char* code) {
  if (const TiXmlElement* origin = parent->FirstChildElement("origin")) {
    c.numbers(origin, pointer + "/origin", "xyz", kPosition, false, code);
    c.numbers(origin, pointer + "/origin", "rpy", kAngles, false, code);
  }
}

// <inertial>: what urdfdom needs (a <mass value>, an <inertia> with all six terms) and import
// uses; urdfdom 3.0 would otherwise keep the link with a zero mass and tensor.
// The largest |term| of any link's <inertia> (the first <inertial> of each, as urdfdom reads):
// the robot's scale of inertia, against which a frame's all-noise tensor is judged.
double largest_inertia_term(const TiXmlElement* robot_element) {
  double largest = 0;
  for (const TiXmlElement* e = robot_element->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    const TiXmlElement* inertial = e->FirstChildElement("inertial");
    const TiXmlElement* inertia = inertial != nullptr ? inertial->FirstChildElement("inertia") : nullptr;
    if (inertia == nullptr) continue;
    for (const char* term : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) {
      const char* text = inertia->Attribute(term);
      double value = 0;
      if (text != nullptr && parse_number(text, value) == NumberError::kNone) largest = std::max(largest, std::abs(value));
    }
  }
  return largest;
}

void check_inertial(Checker& c, const TiXmlElement* inertial, const std::string& pointer, double robot_largest) {
  check_origin(c, inertial, pointer, kInvalidInertial);
  if (const TiXmlElement* mass = inertial->FirstChildElement("mass")) {
    c.numbers(mass, pointer + "/mass", "value", {1, Range::kNonNegative, "a mass"}, true, kInvalidInertial);
  } else {
    c.error(kInvalidInertial, pointer, inertial->Row(), "<inertial> has no <mass value=\"...\"/>");
  }
  if (const TiXmlElement* inertia = inertial->FirstChildElement("inertia")) {
    std::map<std::string, double> moments;
    double largest = 0;
    for (const char* term : {"ixx", "ixy", "ixz", "iyy", "iyz", "izz"}) {
      const auto value = c.numbers(inertia, pointer + "/inertia", term, {1, Range::kAny, "an inertia term"}, true,
                                   kInvalidInertial);
      if (value) largest = std::max(largest, std::abs(value->front()));
      if (value && term[1] == term[2]) moments[term] = value->front();
    }
    // A moment (ixx, iyy, izz) of no body is negative; a product of inertia may be (s100err D7: a
    // negative ixx imported without a word, and only the dynamics check refused it later). A
    // rounding's worth below 0 is not refused: 1e-9 of the link's largest term (an exporter's
    // -1e-30 for a thin rod's axis), or a few roundings (16 eps) of the robot's largest for a
    // tensor that is all noise (a sensor frame's ixx="-1e-30" beside moments of 1e-30, written
    // where the exporter computed zero from the robot's values). A sign error on a small part
    // (-1e-8 beside a base's 16) is still refused.
    const double noise = std::max(1e-9 * largest, 16 * std::numeric_limits<double>::epsilon() * robot_largest);
    for (const auto& [term, value] : moments) {
      if (value >= -noise) continue;
      c.error(kInvalidInertial, pointer + "/inertia/@" + term, inertia->Row(),
              "<inertia " + term + "=\"" + inertia->Attribute(term.c_str()) + "\">: '" + inertia->Attribute(term.c_str()) +
                  "' is negative: a moment of inertia is 0 or more (no body has a negative one)");
    }
  } else {
    c.error(kInvalidInertial, pointer, inertial->Row(),
            "<inertial> has no <inertia ixx=... ixy=... ixz=... iyy=... iyz=... izz=.../>");
  }
}

// A <visual> or <collision>: its origin, its one shape and the shape's sizes (not negative: a
// shape with a size of 0 is skipped with a warning at import, as Drake and Gazebo load it; a
// mesh scale of 0 would flatten it); a visual's material colour.
void check_geometry(Checker& c, const TiXmlElement* holder, const std::string& pointer) {
  check_origin(c, holder, pointer, kInvalidNumber);
  const std::string holder_name = holder->Value();
  const TiXmlElement* geometry = holder->FirstChildElement("geometry");
  if (geometry == nullptr) {
    c.error(codes::URDF_INVALID, pointer, holder->Row(), "<" + holder_name + "> has no <geometry>");
    return;
  }
  const TiXmlElement* shape = geometry->FirstChildElement();
  if (shape == nullptr) {
    c.error(codes::URDF_INVALID, pointer + "/geometry", geometry->Row(),
            "<geometry> holds no shape: give it a <box>, <cylinder>, <sphere> or <mesh>");
    return;
  }
  const std::string kind = shape->Value();
  const std::string at = pointer + "/geometry/" + kind;
  if (kind == "box") {
    c.numbers(shape, at, "size", {3, Range::kSize, "a box size"}, true);
  } else if (kind == "cylinder") {
    c.numbers(shape, at, "radius", {1, Range::kSize, "a cylinder radius"}, true);
    c.numbers(shape, at, "length", {1, Range::kSize, "a cylinder length"}, true);
  } else if (kind == "sphere") {
    c.numbers(shape, at, "radius", {1, Range::kSize, "a sphere radius"}, true);
  } else if (kind == "mesh") {
    if (shape->Attribute("filename") == nullptr) {
      c.error(codes::URDF_INVALID, at, shape->Row(), "<mesh> has no filename attribute");
    }
    c.numbers(shape, at, "scale", {3, Range::kScale, "a mesh scale"}, false);
  } else {
    c.error(codes::URDF_INVALID, at, shape->Row(),
            "<" + shown(kind) + "> is no URDF shape: the shapes are <box>, <cylinder>, <sphere> and <mesh>");
  }
  if (holder_name != "visual") return;
  if (const TiXmlElement* material = holder->FirstChildElement("material")) {
    if (material->Attribute("name") == nullptr) {
      c.error(codes::URDF_INVALID, pointer + "/material", material->Row(), "<material> in a <visual> has no name attribute");
    }
    if (const TiXmlElement* color = material->FirstChildElement("color")) {
      c.numbers(color, pointer + "/material/color", "rgba", {4, Range::kUnit, "a colour component"}, false);
    }
  }
}

// A joint's numbers as import uses them, and the elements urdfdom requires (a <limit> with effort
// and velocity on revolute and prismatic joints; without it urdfdom refuses the whole file).
void check_joint(Checker& c, const TiXmlElement* e, const XmlJoint& joint, const std::string& pointer) {
  check_origin(c, e, pointer, kInvalidNumber);
  // urdfdom reads <axis> of these kinds only (fixed and floating joints have none).
  const bool has_axis = joint.type == "revolute" || joint.type == "continuous" || joint.type == "prismatic" ||
                        joint.type == "planar";
  if (const TiXmlElement* axis = e->FirstChildElement("axis"); axis != nullptr && has_axis) {
    if (axis->Attribute("xyz") == nullptr) {
      c.error(codes::URDF_INVALID, pointer + "/axis", axis->Row(),
              "<axis> has no xyz attribute (urdfdom then takes the zero vector, which is no direction)");
    } else if (const auto xyz = c.numbers(axis, pointer + "/axis", "xyz", {3, Range::kAny, "an axis"}, true)) {
      if ((*xyz)[0] == 0 && (*xyz)[1] == 0 && (*xyz)[2] == 0) {
        c.error(kInvalidNumber, pointer + "/axis/@xyz", axis->Row(),
                "<axis xyz=\"" + shown(axis->Attribute("xyz")) +
                    "\">: the zero vector is no direction; give the axis the joint turns about or slides along");
      }
    }
  }
  if (const TiXmlElement* limit = e->FirstChildElement("limit")) {
    const std::string at = pointer + "/limit";
    const auto lower = c.numbers(limit, at, "lower", {1, Range::kAny, "a limit"}, false);
    const auto upper = c.numbers(limit, at, "upper", {1, Range::kAny, "a limit"}, false);
    c.numbers(limit, at, "effort", {1, Range::kNonNegative, "an effort limit"}, true);
    c.numbers(limit, at, "velocity", {1, Range::kNonNegative, "a velocity limit"}, true);
    // A missing bound is 0 (urdfdom's default); one that is not a number is reported above.
    const bool lower_read = lower || limit->Attribute("lower") == nullptr;
    const bool upper_read = upper || limit->Attribute("upper") == nullptr;
    const double low = lower ? (*lower)[0] : 0, high = upper ? (*upper)[0] : 0;
    // URDF reads lower and upper on revolute and prismatic joints only: a continuous joint's are
    // ignored (import does too), whatever they say.
    const bool ranged = joint.type == "revolute" || joint.type == "prismatic";
    if (ranged && lower_read && upper_read && low > high) {
      // pybullet reads lower above upper as "no limits"; URDF, urdfdom's users and MuJoCo do not.
      const std::string instead = joint.type == "revolute" ? "make it type=\"continuous\" if it turns freely"
                                                           : "give its range of travel (URDF requires one)";
      c.error(kInvalidNumber, at, limit->Row(),
              "<limit>: lower " + exact_number(low) + " is above upper " + exact_number(high) +
                  " (pybullet reads that as no limits; URDF has no such convention: " + instead + ")");
    }
  } else if (joint.type == "revolute" || joint.type == "prismatic") {
    c.error(codes::URDF_INVALID, pointer, e->Row(),
            "joint '" + joint.name + "' is " + joint.type +
                " and has no <limit lower upper effort velocity/>, which URDF requires for that kind");
  }
  if (const TiXmlElement* dynamics = e->FirstChildElement("dynamics")) {
    const std::string at = pointer + "/dynamics";
    if (dynamics->Attribute("damping") == nullptr && dynamics->Attribute("friction") == nullptr) {
      c.error(codes::URDF_INVALID, at, dynamics->Row(), "<dynamics> has neither damping nor friction");
    }
    c.numbers(dynamics, at, "damping", {1, Range::kNonNegative, "damping"}, false);
    c.numbers(dynamics, at, "friction", {1, Range::kNonNegative, "friction"}, false);
  }
  // Not imported, but urdfdom refuses the whole file when they are not numbers.
  if (const TiXmlElement* safety = e->FirstChildElement("safety_controller")) {
    const std::string at = pointer + "/safety_controller";
    for (const char* name : {"soft_lower_limit", "soft_upper_limit", "k_position"}) {
      c.numbers(safety, at, name, kAnyNumber, false);
    }
    c.numbers(safety, at, "k_velocity", kAnyNumber, true);
  }
  if (const TiXmlElement* calibration = e->FirstChildElement("calibration")) {
    for (const char* name : {"rising", "falling"}) {
      c.numbers(calibration, pointer + "/calibration", name, kAnyNumber, false);
    }
  }
  if (const TiXmlElement* mimic = e->FirstChildElement("mimic")) {
    if (mimic->Attribute("joint") == nullptr) {
      c.error(codes::URDF_INVALID, pointer + "/mimic", mimic->Row(), "<mimic> has no joint attribute");
    }
    for (const char* name : {"multiplier", "offset"}) c.numbers(mimic, pointer + "/mimic", name, kAnyNumber, false);
  }
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
      diag.error_at_line(codes::URDF_LINK_TWO_PARENTS, joint_pointer(joint.name), joint.row,
                 "link '" + joint.child + "' is the child of joint '" + joint.name +
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
    diag.error_at_line(codes::URDF_JOINT_LOOP, joint_pointer(robot.joints[parent_joint[at]].name), first_row,
               "joints " + joints + " form a loop (link '" + robot.links[at].name +
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
    diag.error(codes::URDF_MULTIPLE_ROOTS, "/robot",
               std::to_string(roots.size()) + " links have no parent joint: " + names +
                   "; a URDF has exactly one root link");
    return false;
  }
  return true;
}

// TinyXML parses an element's children by recursion, one stack frame per level: 50,000 nested
// elements in a 350 KB file overflow the stack. No URDF nests deeper than a dozen levels (a
// <gazebo> block of SDF a few more), so deeper text is refused before it is parsed. Returns the
// line of the first element past `limit`, or 0. Comments and CDATA are skipped, processing
// instructions and declarations up to their first '>' (as TinyXML 2.6 reads them); quoted
// attribute values may hold '>'.
int line_past_depth(const std::string& text, int limit) {
  int depth = 0;
  int line = 1;
  const std::size_t n = text.size();
  // From the '<' at `from` past the first `end` found from `search`, counting the lines passed.
  const auto skip_to = [&](std::size_t from, std::size_t search, const char* end) {
    const std::size_t at = text.find(end, search);
    const std::size_t stop = at == std::string::npos ? n : at + std::strlen(end);
    line += static_cast<int>(std::count(text.begin() + static_cast<std::ptrdiff_t>(from),
                                        text.begin() + static_cast<std::ptrdiff_t>(stop), '\n'));
    return stop;
  };
  for (std::size_t i = 0; i < n;) {
    if (text[i] == '\n') ++line;
    if (text[i] != '<') {
      ++i;
      continue;
    }
    if (text.compare(i, 4, "<!--") == 0) {
      i = skip_to(i, i, "-->");
    } else if (text.compare(i, 9, "<![CDATA[") == 0) {
      i = skip_to(i, i, "]]>");
    } else if (text.compare(i, 2, "<?") == 0 || text.compare(i, 2, "<!") == 0) {
      // A declaration or processing instruction ends at its first '>', as TinyXML ends it: what
      // follows is parsed as elements (a DOCTYPE's internal subset included), so it is counted.
      i = skip_to(i, i, ">");
    } else if (text.compare(i, 2, "</") == 0) {
      --depth;
      i = skip_to(i, i, ">");
    } else {
      // A start tag: to its '>' outside quotes; "/>" closes it at once.
      const int at_line = line;
      char quote = 0;
      std::size_t j = i + 1;
      for (; j < n; ++j) {
        const char c = text[j];
        if (c == '\n') ++line;
        if (quote != 0) {
          if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
          quote = c;
        } else if (c == '>') {
          break;
        }
      }
      if (j >= n || text[j - 1] != '/') {
        if (++depth > limit) return at_line;
      }
      i = j + 1;
    }
  }
  return 0;
}

constexpr int kMaxXmlDepth = 256;

// The first child of `e` named one of `names` that repeats an earlier sibling of its name, or
// nullptr: URDF allows one of each (urdfdom reads the first, MuJoCo refuses the file).
const TiXmlElement* repeated_child(const TiXmlElement* e, std::initializer_list<const char*> names) {
  for (const char* name : names) {
    if (const TiXmlElement* first = e->FirstChildElement(name)) {
      if (const TiXmlElement* second = first->NextSiblingElement(name)) return second;
    }
  }
  return nullptr;
}


// The first element in document order named "xacro:..." (depth-bounded by kMaxXmlDepth).
const TiXmlElement* first_xacro_element(const TiXmlElement* element) {
  for (; element != nullptr; element = element->NextSiblingElement()) {
    if (std::string_view(element->Value()).rfind("xacro:", 0) == 0) return element;
    if (const TiXmlElement* inner = first_xacro_element(element->FirstChildElement())) return inner;
  }
  return nullptr;
}

}  // namespace

std::string link_pointer(const std::string& name) { return "/robot/link[@name='" + name + "']"; }
std::string joint_pointer(const std::string& name) { return "/robot/joint[@name='" + name + "']"; }

std::optional<XmlRobot> scan_urdf_xml(const std::string& text, Diagnostics& diag) {
  if (const int line = line_past_depth(text, kMaxXmlDepth)) {
    diag.error_at_line(codes::URDF_MALFORMED_XML, "", line,
                       "elements nest more than " + std::to_string(kMaxXmlDepth) +
                           " deep here: no URDF does, and the XML parser would run out of stack; is this a URDF?");
    return std::nullopt;
  }
  // TinyXML reports an empty document at "line 0, column 0" as "Error document empty". A byte order
  // mark alone (Notepad's "empty" UTF-8 file) is empty too.
  const std::size_t bom = text.rfind("\xEF\xBB\xBF", 0) == 0 ? 3 : 0;
  if (text.find_first_not_of(" \t\r\n", bom) == std::string::npos) {
    diag.error(codes::URDF_MALFORMED_XML, "",
               text.empty() ? std::string("the file is empty (0 bytes): a URDF is one <robot> element")
                            : "the file holds only " + std::string(bom != 0 ? "a byte order mark and " : "") +
                                  "whitespace (" + std::to_string(text.size()) + " bytes): a URDF is one <robot> element");
    return std::nullopt;
  }
  TiXmlDocument document;
  document.Parse(text.c_str(), nullptr, TIXML_ENCODING_UTF8);
  if (document.Error()) {
    diag.error_at_line(codes::URDF_MALFORMED_XML, "", document.ErrorRow(),
               "column " + std::to_string(document.ErrorCol()) +
                   ": malformed XML: " + document.ErrorDesc());
    return std::nullopt;
  }
  const TiXmlElement* robot_element = document.RootElement();
  if (robot_element == nullptr || std::string(robot_element->Value()) != "robot") {
    diag.error(codes::URDF_NOT_A_ROBOT, "",
               robot_element != nullptr
                   ? "the root element is <" + std::string(robot_element->Value()) + ">, not <robot>: this is not a URDF"
                   : std::string("the XML parser found no root element (a <!DOCTYPE> with entities is not read): "
                                 "a URDF is one <robot> element"));
    return std::nullopt;
  }
  // A xacro file is no URDF: its macros, includes and properties would be dropped without a
  // word, and with them the links a macro makes.
  if (const TiXmlElement* xacro = first_xacro_element(robot_element)) {
    diag.error_at_line(codes::URDF_INVALID, "", xacro->Row(),
                       "<" + std::string(xacro->Value()) +
                           ">: this is a xacro file, not a URDF; expand it first (xacro robot.urdf.xacro > robot.urdf)");
    return std::nullopt;
  }
  XmlRobot robot;
  robot.row = robot_element->Row();
  bool ok = true;
  Checker checker(diag);
  // A second <inertial>, <origin>, <limit>... where URDF has one: urdfdom silently reads the
  // first (a 50 kg inertial after a 1 kg one was dropped), MuJoCo refuses the file.
  const auto no_repeats = [&](const TiXmlElement* e, const std::string& pointer,
                              std::initializer_list<const char*> names) {
    const TiXmlElement* second = repeated_child(e, names);
    if (second == nullptr) return true;
    const std::string name = second->Value();
    diag.error_at_line(codes::URDF_INVALID, pointer + "/" + name + "[2]", second->Row(),
                       "<" + std::string(e->Value()) + "> has a second <" + name + "> (the first is on line " +
                           std::to_string(e->FirstChildElement(name.c_str())->Row()) +
                           "): URDF allows one; urdfdom would read the first alone and MuJoCo refuses the file");
    return false;
  };
  for (const TiXmlNode* after = robot_element->NextSibling(); after != nullptr; after = after->NextSibling()) {
    if (after->ToComment() != nullptr || after->ToDeclaration() != nullptr) continue;
    diag.error_at_line(codes::URDF_MALFORMED_XML, "", after->Row(),
                       after->ToElement() != nullptr
                           ? "a second root element <" + std::string(after->Value()) +
                                 "> after </robot>: a URDF is one <robot> element (urdfdom would read the first "
                                 "alone)"
                           : std::string("text after </robot>: a URDF is one <robot> element"));
    return std::nullopt;
  }
  // Text after the root element, which TinyXML drops without a word (xmllint and MuJoCo refuse
  // it). Read backward from the end, past white space, comments and processing instructions (a
  // "</robot>" inside a comment is no end tag): what is left must end with a tag.
  {
    std::size_t end = text.size();
    for (;;) {
      while (end > 0 && std::isspace(static_cast<unsigned char>(text[end - 1]))) --end;
      const std::string_view head = std::string_view(text).substr(0, end);
      std::size_t open = std::string_view::npos;
      if (head.ends_with("-->")) open = head.rfind("<!--");
      else if (head.ends_with("?>")) open = head.rfind("<?");
      if (open == std::string_view::npos) break;
      end = open;
    }
    // The last tag must close the root ("</robot>", or "<robot .../>"): a second element after it
    // is refused above, so any other is text that looks like a tag ("trailing <junk>").
    const std::size_t last_open = end > 0 ? text.rfind('<', end - 1) : std::string::npos;
    const bool closes = end > 0 && text[end - 1] == '>' && last_open != std::string::npos &&
                        (text.compare(last_open, 2, "</") == 0 || text.compare(end - 2, 2, "/>") == 0);
    if (end > 0 && !closes) {
      std::size_t at = text[end - 1] == '>' && last_open != std::string::npos && last_open > 0
                           ? text.rfind('>', last_open - 1)
                           : text.rfind('>', end - 1);
      at = at == std::string::npos ? 0 : at + 1;
      while (at < end && std::isspace(static_cast<unsigned char>(text[at]))) ++at;
      const int line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
      diag.error_at_line(codes::URDF_MALFORMED_XML, "", line,
                         "text after </robot> ('" + shown(std::string_view(text).substr(at, std::min<std::size_t>(20, end - at))) +
                             "'): a URDF is one <robot> element");
      return std::nullopt;
    }
  }
  const double robot_largest_inertia = largest_inertia_term(robot_element);
  std::set<std::string> link_names, joint_names;
  for (const TiXmlElement* m = robot_element->FirstChildElement("material"); m; m = m->NextSiblingElement("material")) {
    const char* name = m->Attribute("name");
    const std::string pointer = name != nullptr ? "/robot/material[@name='" + std::string(name) + "']" : "/robot/material";
    if (name != nullptr && !robot.material_rows.emplace(name, m->Row()).second) {
      // urdfdom refuses it too, but at the line of the last one.
      diag.error_at_line(codes::URDF_DUPLICATE_NAME, pointer, m->Row(),
                         "a second material is named '" + std::string(name) + "' (the first is on line " +
                             std::to_string(robot.material_rows[name]) + ")");
      ok = false;
    }
    if (const TiXmlElement* color = m->FirstChildElement("color")) {
      checker.numbers(color, pointer + "/color", "rgba", {4, Range::kUnit, "a colour component"}, false);
    }
  }
  for (const TiXmlElement* e = robot_element->FirstChildElement("link"); e; e = e->NextSiblingElement("link")) {
    XmlLink link{attribute(e, "name"), e->Row(), {}, {}};
    if (link.name.empty()) {
      diag.error_at_line(codes::URDF_INVALID, "/robot/link", e->Row(), "a <link> has no name");
      ok = false;
      continue;
    }
    if (!link_names.insert(link.name).second) {
      diag.error_at_line(codes::URDF_DUPLICATE_NAME, link_pointer(link.name), e->Row(),
                 "a second link is named '" + link.name + "'");
      ok = false;
      continue;
    }
    const std::string pointer = link_pointer(link.name);
    for (const TiXmlElement* v = e->FirstChildElement("visual"); v; v = v->NextSiblingElement("visual")) {
      link.visual_rows.push_back(v->Row());
      check_geometry(checker, v, pointer + "/visual[" + std::to_string(link.visual_rows.size()) + "]");
    }
    for (const TiXmlElement* c = e->FirstChildElement("collision"); c; c = c->NextSiblingElement("collision")) {
      link.collision_rows.push_back(c->Row());
      check_geometry(checker, c, pointer + "/collision[" + std::to_string(link.collision_rows.size()) + "]");
    }
    bool repeats = !no_repeats(e, pointer, {"inertial"});
    int visuals = 0, collisions = 0;  // Counted as the pointers count them: /visual[1], ...
    for (const TiXmlElement* v = e->FirstChildElement(); v; v = v->NextSiblingElement()) {
      const std::string name = v->Value();
      if (name == "visual" || name == "collision") {
        const int n = name == "visual" ? ++visuals : ++collisions;
        repeats = !no_repeats(v, pointer + "/" + name + "[" + std::to_string(n) + "]", {"origin", "geometry"}) || repeats;
      }
      if (name == "inertial") repeats = !no_repeats(v, pointer + "/inertial", {"origin", "mass", "inertia"}) || repeats;
    }
    if (repeats) {
      ok = false;
      continue;
    }
    if (const TiXmlElement* inertial = e->FirstChildElement("inertial")) {
      check_inertial(checker, inertial, pointer + "/inertial", robot_largest_inertia);
    }
    robot.links.push_back(std::move(link));
  }
  for (const TiXmlElement* e = robot_element->FirstChildElement("joint"); e; e = e->NextSiblingElement("joint")) {
    XmlJoint joint{attribute(e, "name"), attribute(e, "type"), link_reference(e, "parent"),
                   link_reference(e, "child"), e->Row()};
    if (const TiXmlElement* mimic = e->FirstChildElement("mimic")) joint.mimic_row = mimic->Row();
    for (const char* ignored : {"safety_controller", "calibration"}) {
      if (const TiXmlElement* element = e->FirstChildElement(ignored); element != nullptr && joint.ignored_row == 0) {
        joint.ignored_row = element->Row();
      }
    }
    const std::string pointer = joint.name.empty() ? "/robot/joint" : joint_pointer(joint.name);
    if (joint.name.empty()) {
      diag.error_at_line(codes::URDF_INVALID, pointer, e->Row(), "a <joint> has no name");
      ok = false;
      continue;
    }
    if (!joint_names.insert(joint.name).second) {
      diag.error_at_line(codes::URDF_DUPLICATE_NAME, pointer, e->Row(), "a second joint is named '" + joint.name + "'");
      ok = false;
      continue;
    }
    if (!no_repeats(e, pointer,
                    {"parent", "child", "origin", "axis", "limit", "dynamics", "mimic", "calibration",
                     "safety_controller"})) {
      ok = false;
      continue;
    }
    if (!known_joint_types().count(joint.type)) {
      diag.error_at_line(codes::URDF_UNKNOWN_JOINT_TYPE, pointer, e->Row(),
                 "joint '" + joint.name + "' has type '" + joint.type +
                     "'; URDF's types are fixed, revolute, continuous, prismatic, floating and planar");
      ok = false;
    } else {
      check_joint(checker, e, joint, pointer);
    }
    for (const auto& [which, link] : {std::pair<const char*, const std::string&>{"parent", joint.parent},
                                      std::pair<const char*, const std::string&>{"child", joint.child}}) {
      if (link.empty()) {
        diag.error_at_line(codes::URDF_INVALID, pointer, e->Row(),
                   "joint '" + joint.name + "' has no <" + which + " link=\"...\"/>");
        ok = false;
      } else if (!link_names.count(link)) {
        diag.error_at_line(codes::URDF_UNKNOWN_LINK, pointer, e->Row(),
                   "joint '" + joint.name + "' names " + which + " link '" + link +
                       "', which no <link> defines");
        ok = false;
      }
    }
    if (!joint.parent.empty() && joint.parent == joint.child) {
      diag.error_at_line(codes::URDF_JOINT_LOOP, pointer, e->Row(),
                 "joint '" + joint.name + "' joins link '" + joint.parent + "' to itself");
      ok = false;
    }
    robot.joints.push_back(std::move(joint));
  }
  if (robot.links.empty() && ok) {
    diag.error(codes::URDF_INVALID, "/robot", "the robot has no <link>");
    return std::nullopt;
  }
  if (!ok || !check_tree(robot, diag) || !checker.ok()) return std::nullopt;
  return robot;
}

}  // namespace rdtf::urdf_internal
