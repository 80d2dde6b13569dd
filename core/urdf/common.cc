#include <array>
#include <charconv>
#include <cmath>

#include <console_bridge/console.h>

#include "import_internal.h"
#include "urdf_internal.h"

namespace rdtf::urdf_internal {

Eigen::Matrix3d y_up_to_z_up() {
  Eigen::Matrix3d C;
  C << 1, 0, 0,  //
      0, 0, -1,  //
      0, 1, 0;
  return C;
}

Eigen::Isometry3d conjugate(const Eigen::Matrix3d& C, const Eigen::Isometry3d& X) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = C * X.linear() * C.transpose();
  out.translation() = C * X.translation();
  return out;
}

Eigen::Vector3d rpy_from_rotation(const Eigen::Matrix3d& R) {
  // R = Rz(y) Ry(p) Rx(r): R(2,0) = -sin p, R(1,0) = sin y cos p, R(0,0) = cos y cos p.
  const double cos_pitch = std::hypot(R(0, 0), R(1, 0));
  const double pitch = std::atan2(-R(2, 0), cos_pitch);
  // At the lock itself (cos p at rounding level: 6e-17 for the double nearest pi/2) only
  // roll - yaw (pitch +90) or roll + yaw (pitch -90) is defined: yaw is 0 and roll holds it, as a
  // modeller would write it. Forcing 0 any further out would drop cos p's share of R.
  const double yaw = cos_pitch > 1e-15 ? std::atan2(R(1, 0), R(0, 0)) : 0.0;
  // Away from gimbal lock roll comes from R(2,1) = cos p sin r and R(2,2) = cos p cos r, to
  // rounding over cos p: at most twice the rounding while pitch is within 60 degrees.
  if (cos_pitch >= 0.5) return {std::atan2(R(2, 1), R(2, 2)), pitch, yaw};
  // Nearer the lock (pitch near +-90 degrees) those entries are small, and roll and yaw each
  // carry rounding of 1e-16 / cos p: 6e-6 rad at 1e-11 from the lock, which the URDF then turned
  // every link below by. So roll comes from Rz(y)^T R = Ry(p) Rx(r), whose middle row
  // (0, cos r, -sin r) has full-size entries: the angles give R back to rounding, lock or not.
  const double c = std::cos(yaw);
  const double s = std::sin(yaw);
  const double cos_roll = c * R(1, 1) - s * R(0, 1);
  const double sin_roll = s * R(0, 2) - c * R(1, 2);
  return {std::atan2(sin_roll, cos_roll), pitch, yaw};
}

Eigen::Matrix3d rotation_from_rpy(const Eigen::Vector3d& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(rpy.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

std::string exact_number(double value) {
  if (value == 0.0) return "0";
  std::array<char, 64> buffer{};
  const auto result = std::to_chars(buffer.data(), buffer.data() + buffer.size(), value);
  return std::string(buffer.data(), result.ptr);
}

std::string valid_urdf_name(const std::string& text, const std::string& fallback) {
  std::string out;
  for (unsigned char c : text) {
    // One '_' for each character another would be: a UTF-8 sequence's continuation bytes
    // (10xxxxxx) add none, so "ä" is "_", not "__".
    if ((c & 0xC0) == 0x80) continue;
    const bool keep = (c < 0x80 && std::isalnum(c)) || c == '_' || c == '-' || c == '.';
    out += keep ? static_cast<char>(c) : '_';
  }
  return out.empty() ? fallback : out;
}

std::string unique_name(const std::string& name, std::vector<std::string>& taken) {
  auto used = [&](const std::string& candidate) {
    for (const std::string& t : taken) {
      if (t == candidate) return true;
    }
    return false;
  };
  std::string candidate = name;
  for (int n = 2; used(candidate); ++n) candidate = name + "_" + std::to_string(n);
  taken.push_back(candidate);
  return candidate;
}

namespace {

class Capture : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_WARN) return;
    (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR ? messages.errors : messages.warnings).push_back(text);
    all.push_back(text);
  }
  ConsoleMessages messages;
  std::vector<std::string> all;  // Warnings and errors in the order logged.
};

// Runs `body` with console_bridge's output going to `capture` (one lock for the whole process:
// console_bridge's handler is global).
void run_captured(const std::function<void()>& body, Capture& capture) {
  static std::mutex mutex;
  const std::lock_guard<std::mutex> lock(mutex);
  const auto level = console_bridge::getLogLevel();
  console_bridge::setLogLevel(console_bridge::CONSOLE_BRIDGE_LOG_WARN);
  console_bridge::useOutputHandler(&capture);
  try {
    body();
  } catch (...) {
    console_bridge::restorePreviousOutputHandler();
    console_bridge::setLogLevel(level);
    throw;
  }
  console_bridge::restorePreviousOutputHandler();
  console_bridge::setLogLevel(level);
}

}  // namespace

std::string with_console_captured(const std::function<void()>& body) {
  Capture capture;
  run_captured(body, capture);
  std::string text;
  for (const std::string& message : capture.all) text += (text.empty() ? "" : "\n") + message;
  return text;
}

FlatRelease::~FlatRelease() {
  if (!model_) return;
  for (auto& [name, link] : model_->links_) {
    if (!link) continue;
    link->child_links.clear();
    link->child_joints.clear();
  }
}

ConsoleMessages capture_console(const std::function<void()>& body) {
  Capture capture;
  run_captured(body, capture);
  return std::move(capture.messages);
}

}  // namespace rdtf::urdf_internal
