#include "page_protocol.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "safe_decode.h"

namespace rdtf::view {
namespace {

using Json = nlohmann::json;

// Quoted for a reason, made printable and short: the text came from anyone.
std::string in_quotes(std::string_view text) { return "'" + rdtf::lcm_safe::printable(text, 80) + "'"; }

// The shortest text that reads back as the same double: "1.58", not "1.5800000000000001".
std::string number_text(double value) {
  char text[32];
  const auto result = std::to_chars(text, text + sizeof(text), value);
  return std::string(text, result.ptr);
}

Refusal refuse(std::string reason) { return Refusal{std::move(reason)}; }

// The keys of `object` must be exactly `allowed`.
std::optional<Refusal> check_keys(const Json& object, const std::set<std::string>& allowed, const std::string& type) {
  for (const auto& [key, value] : object.items()) {
    if (!allowed.count(key)) return refuse("unknown key " + in_quotes(key) + " in a " + type + " message");
  }
  for (const auto& key : allowed) {
    if (!object.contains(key)) return refuse("a " + type + " message needs \"" + key + "\"");
  }
  return std::nullopt;
}

// The model id: a string naming a model the viewer holds live.
std::variant<const CommandableModel*, Refusal> find_model(const Json& object, const Catalog& catalog) {
  const Json& model = object.at("model");
  if (!model.is_string()) return refuse("\"model\" must be a string (a model id)");
  const auto found = catalog.find(model.get<std::string>());
  if (found == catalog.end()) return refuse("unknown model " + in_quotes(model.get<std::string>()) + " (not live on the bus)");
  return &found->second;
}

}  // namespace

PageRequest parse_page_message(std::string_view text, const Catalog& catalog) {
  if (text.size() > kMaxPageMessageBytes) {
    return refuse("message of " + std::to_string(text.size()) + " bytes, more than " +
                  std::to_string(kMaxPageMessageBytes));
  }
  const Json message = Json::parse(text.begin(), text.end(), nullptr, /*allow_exceptions=*/false);
  if (message.is_discarded()) return refuse("not JSON");
  if (!message.is_object()) return refuse("not a JSON object");
  const auto type = message.find("type");
  if (type == message.end() || !type->is_string()) return refuse("no \"type\" string");

  if (*type == "set_joint") {
    if (auto bad = check_keys(message, {"type", "model", "joint", "value"}, "set_joint")) return *bad;
    const auto model = find_model(message, catalog);
    if (const auto* why = std::get_if<Refusal>(&model)) return *why;
    const CommandableModel& m = *std::get<const CommandableModel*>(model);
    const std::string model_id = message.at("model").get<std::string>();
    if (!m.simulated) return refuse("model " + in_quotes(model_id) + " is not simulated (no JOINT_STATE heard)");
    const Json& joint = message.at("joint");
    if (!joint.is_string()) return refuse("\"joint\" must be a string (a joint's URDF name)");
    const auto found = m.joints.find(joint.get<std::string>());
    if (found == m.joints.end()) {
      return refuse("model " + in_quotes(model_id) + " revision " + std::to_string(m.revision) +
                    " has no movable joint " + in_quotes(joint.get<std::string>()));
    }
    const Json& value = message.at("value");
    if (!value.is_number()) return refuse("\"value\" must be a number, not " + std::string(value.type_name()));
    const double v = value.get<double>();
    if (!std::isfinite(v)) return refuse("\"value\" is not finite");
    const MovableJoint& limits = found->second;
    const double lower = limits.lower.value_or(-kMaxUnlimitedJointValue);
    const double upper = limits.upper.value_or(kMaxUnlimitedJointValue);
    if (v < lower || v > upper) {
      return refuse("value " + number_text(v) + " of joint " + in_quotes(found->first) + " outside its limits [" +
                    number_text(lower) + ", " + number_text(upper) + "]");
    }
    return SetJoint{model_id, found->first, v};
  }
  if (*type == "release") {
    if (auto bad = check_keys(message, {"type", "model"}, "release")) return *bad;
    const auto model = find_model(message, catalog);
    if (const auto* why = std::get_if<Refusal>(&model)) return *why;
    return Release{message.at("model").get<std::string>()};
  }
  return refuse("unknown type " + in_quotes(type->get<std::string>()));
}

bool RateLimiter::allow(double now_s) {
  if (last_) tokens_ = std::min(burst_, tokens_ + std::max(0.0, now_s - *last_) * rate_);
  last_ = now_s;
  if (tokens_ < 1) return false;
  tokens_ -= 1;
  return true;
}

}  // namespace rdtf::view
