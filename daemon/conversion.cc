#include "conversion.h"

#include <openssl/evp.h>

#include <fstream>
#include <memory>

#include "rdtf/write.h"

namespace rdtf::daemon {
namespace {

std::optional<std::vector<std::uint8_t>> read_bytes(const std::filesystem::path& path,
                                                    std::uint64_t max_bytes) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(path, ec);
  if (ec || size > max_bytes || !std::filesystem::is_regular_file(path, ec)) return std::nullopt;
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> bytes(size);
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size))) {
    return std::nullopt;
  }
  return bytes;
}

std::string to_hex(const unsigned char* digest, unsigned int length) {
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 15];
  }
  return out;
}

}  // namespace

std::string sha256_hex(const std::vector<const std::vector<std::uint8_t>*>& parts) {
  std::unique_ptr<EVP_MD_CTX, decltype(&EVP_MD_CTX_free)> context(EVP_MD_CTX_new(), EVP_MD_CTX_free);
  EVP_DigestInit_ex(context.get(), EVP_sha256(), nullptr);
  for (const auto* part : parts) {
    // Length first, so that moving bytes between parts changes the hash.
    const std::uint64_t size = part->size();
    EVP_DigestUpdate(context.get(), &size, sizeof(size));
    EVP_DigestUpdate(context.get(), part->data(), part->size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context.get(), digest, &length);
  return to_hex(digest, length);
}

std::string sha256_hex(std::string_view text) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(text.data(), text.size(), digest, &length, EVP_sha256(), nullptr);
  return to_hex(digest, length);
}

ConversionOutcome run_conversion(const ConversionJob& job) {
  const auto start = std::chrono::steady_clock::now();
  ConversionOutcome outcome;
  outcome.model_id = job.model_id;
  outcome.source = job.source;
  outcome.diagnostics.set_file(job.source.string());
  auto finish = [&]() -> ConversionOutcome {
    outcome.duration = std::chrono::duration_cast<std::chrono::microseconds>(
        std::chrono::steady_clock::now() - start);
    return std::move(outcome);
  };

  std::error_code ec;
  if (!std::filesystem::exists(job.source, ec)) {
    outcome.kind = ConversionOutcome::Kind::kVanished;
    return finish();
  }
  const auto model_bytes = read_bytes(job.source, job.options.limits.max_file_bytes);
  if (!model_bytes) {
    if (!std::filesystem::exists(job.source, ec)) {
      outcome.kind = ConversionOutcome::Kind::kVanished;
    } else {
      outcome.diagnostics.error("IO_ERROR", "", "cannot read the model (too large, or not a regular file)");
    }
    return finish();
  }
  const auto folder = std::filesystem::canonical(job.source.parent_path(), ec);
  outcome.dependencies = referenced_files(*model_bytes, folder);

  // The content hash covers the model and every file it refers to, so a new .bin alone counts.
  std::vector<std::vector<std::uint8_t>> referenced;
  for (const auto& file : outcome.dependencies) {
    referenced.push_back(read_bytes(file, job.options.limits.max_file_bytes).value_or(std::vector<std::uint8_t>{}));
  }
  std::vector<const std::vector<std::uint8_t>*> parts{&*model_bytes};
  for (const auto& bytes : referenced) parts.push_back(&bytes);
  outcome.content_hash = sha256_hex(parts);
  if (outcome.content_hash == job.previous_hash) {
    outcome.kind = ConversionOutcome::Kind::kUnchanged;
    return finish();
  }

  auto asset = load_gltf_from_memory(*model_bytes, job.source, folder, job.options.limits,
                                     outcome.diagnostics);
  if (!asset) return finish();
  auto conversion = convert(std::move(*asset), job.options, outcome.diagnostics);
  if (!conversion) return finish();

  std::filesystem::create_directories(job.output_dir, ec);
  ConvertedModel converted;
  converted.content_hash = outcome.content_hash;
  converted.output_path = job.output_dir / (job.source.stem().string() + ".rdtf.gltf");
  Diagnostics write_diag(converted.output_path.string());
  if (!write_rdtf(conversion->asset, converted.output_path, OutputFormat::kGltf, write_diag,
                  &converted.rdtf_json)) {
    outcome.diagnostics.append(write_diag);
    return finish();
  }
  outcome.diagnostics.append(write_diag);
  if (job.urdf) {
    // URDF is a second output: a model URDF cannot express (a ball joint) still converts.
    Diagnostics urdf_diag(converted.output_path.string());
    const auto urdf_dir = job.output_dir / "urdf";
    if (write_urdf(*conversion, urdf_dir, *job.urdf, urdf_diag, &converted.urdf)) {
      converted.urdf_path = urdf_dir / "robot.urdf";
    } else {
      for (const Diagnostic& d : urdf_diag.all()) {
        outcome.diagnostics.warning("URDF_NOT_WRITTEN", d.pointer, d.message);
      }
    }
  }
  if (job.validation) {
    ValidationReport report = validate_dynamics(*conversion, *job.validation, job.source.string());
    ValidationSummary summary;
    summary.passed = report.passed;
    summary.simulated_time = report.simulated_time;
    summary.steps = report.steps;
    summary.energy_drift = report.energy_drift;
    summary.worst_joint_error = report.worst_joint_error;
    summary.wall_time = report.wall_time;
    summary.summary_line = validation_summary_line(report);
    summary.diagnostics = std::move(report.diagnostics);
    converted.validation = std::move(summary);
  }
  converted.totals = robot_totals(conversion->robot);
  converted.robot = std::move(conversion->robot);
  outcome.converted = std::move(converted);
  outcome.kind = ConversionOutcome::Kind::kConverted;
  return finish();
}

}  // namespace rdtf::daemon
