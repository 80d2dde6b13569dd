// One conversion of one model, as a worker thread runs it: read, hash, convert, write the
// outputs. Plain values in and out; the event loop decides what to publish.
#pragma once

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "rdtf/convert.h"
#include "rdtf/diagnostics.h"
#include "rdtf/robot.h"
#include "rdtf/summary.h"

namespace rdtf::daemon {

struct ConversionJob {
  std::string model_id;
  std::filesystem::path source;      // The model file.
  std::filesystem::path output_dir;  // This model's own output folder.
  ConvertOptions options;
  std::string previous_hash;         // Content last converted (good or bad): skip when equal.
};

// What a good conversion leaves behind: all a publisher needs, no reference to the document.
struct ConvertedModel {
  std::string content_hash;
  std::filesystem::path output_path;
  std::string rdtf_json;
  Robot robot;
  RobotTotals totals;
};

struct ConversionOutcome {
  enum class Kind { kConverted, kUnchanged, kRejected, kVanished };
  Kind kind = Kind::kRejected;
  std::string model_id;
  std::filesystem::path source;
  std::string content_hash;                  // Of what was read ("" when nothing could be).
  std::optional<ConvertedModel> converted;   // For kConverted.
  Diagnostics diagnostics;                   // Errors for kRejected; warnings otherwise.
  std::vector<std::filesystem::path> dependencies;  // Files the model refers to.
  std::chrono::microseconds duration{0};
};

ConversionOutcome run_conversion(const ConversionJob& job);

// Hex SHA-256 of the concatenation of the given byte strings.
std::string sha256_hex(const std::vector<const std::vector<std::uint8_t>*>& parts);
std::string sha256_hex(std::string_view text);

}  // namespace rdtf::daemon
