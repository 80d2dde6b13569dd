// What a page may ask rdtf-view over its WebSocket, checked before anything reaches the bus.
//
// A page sends one JSON object per WebSocket message:
//   {"type": "set_joint", "model": "arm3.gltf", "joint": "elbow", "value": 0.5}
//   {"type": "release", "model": "arm3.gltf"}            // stop commanding every joint of it
// parse_page_message() turns a message into a request or a refusal with its reason. It refuses
// anything else: text that is not JSON, not an object, bigger than kMaxPageMessageBytes, other or
// extra keys, a model the viewer does not hold live, a joint that is not a one-degree-of-freedom
// joint of the model's live revision (by its URDF name, as JOINT_STATE's `name`), a value that is
// not a finite number or lies outside the joint's limits. A refused message never becomes a
// JOINT_COMMAND. Pure: no I/O, no clock (the rate limit is RateLimiter, below).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <variant>

namespace rdtf::view {

inline constexpr std::size_t kMaxPageMessageBytes = 4096;
// Largest |value| of a joint without limits (continuous): rad (turns count), far beyond any slider.
inline constexpr double kMaxUnlimitedJointValue = 1e4;

// A joint that takes commands: a one-degree-of-freedom joint of the live revision.
struct MovableJoint {
  std::optional<double> lower, upper;  // rad or m; absent for a continuous joint
};

// The models a page may command, by model id: their movable joints by URDF name.
struct CommandableModel {
  std::int64_t revision = 0;
  bool simulated = false;  // a JOINT_STATE of this revision was heard: rdtfd runs it
  std::map<std::string, MovableJoint> joints;
};
using Catalog = std::map<std::string, CommandableModel>;

struct SetJoint {
  std::string model_id;
  std::string joint;  // URDF name
  double value = 0;
};
struct Release {
  std::string model_id;
};
struct Refusal {
  std::string reason;
};
using PageRequest = std::variant<SetJoint, Release, Refusal>;

PageRequest parse_page_message(std::string_view text, const Catalog& catalog);

// Messages per second a page may send: a token bucket (`rate` a second, `burst` at once). Time is
// passed in (seconds, any monotonic origin), so the tests need no clock.
class RateLimiter {
 public:
  RateLimiter(double rate, double burst) : rate_(rate), burst_(burst), tokens_(burst) {}
  bool allow(double now_s);

 private:
  double rate_, burst_, tokens_;
  std::optional<double> last_;
};

}  // namespace rdtf::view
