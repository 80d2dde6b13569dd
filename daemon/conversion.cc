#include "conversion.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/evp.h>

#include <cerrno>
#include <memory>

#include "rdtf/write.h"

namespace rdtf::daemon {
namespace {

// Reads a regular file of at most max_bytes. Opened without blocking (a FIFO put where a model
// was must not hang a worker) and checked with fstat on the open descriptor, so a file swapped
// for a FIFO or a directory between a check and the open is still refused.
// With `folder`, the file's real location (through /proc, after every symlink) must lie inside it:
// even the content hash never reads a file the loader would refuse.
std::optional<std::vector<std::uint8_t>> read_bytes(const std::filesystem::path& path,
                                                    std::uint64_t max_bytes,
                                                    const std::filesystem::path* folder = nullptr) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK | O_NOCTTY);
  if (fd < 0) return std::nullopt;
  struct stat info {};
  std::optional<std::vector<std::uint8_t>> result;
  bool inside = true;
  if (folder != nullptr) {
    std::error_code ec;
    const auto real = std::filesystem::read_symlink("/proc/self/fd/" + std::to_string(fd), ec);
    const auto relative = real.lexically_relative(*folder);
    inside = !ec && !relative.empty() && *relative.begin() != "..";
  }
  if (inside && ::fstat(fd, &info) == 0 && S_ISREG(info.st_mode) &&
      static_cast<std::uint64_t>(info.st_size) <= max_bytes) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(info.st_size));
    std::size_t done = 0;
    for (;;) {
      if (done == bytes.size()) {
        result = std::move(bytes);
        break;
      }
      const ssize_t n = ::read(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;  // An error, or the file shrank while read: the writer's next event follows.
      done += static_cast<std::size_t>(n);
    }
  }
  ::close(fd);
  return result;
}

// The model is gone for us: deleted, or a directory (or a symlink to one) stands in its place.
bool model_gone(const std::filesystem::path& source) {
  std::error_code ec;
  const auto status = std::filesystem::status(source, ec);
  return !std::filesystem::exists(status) || std::filesystem::is_directory(status);
}

bool has_code(const Diagnostics& diag, const char* code) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError && d.code == code) return true;
  }
  return false;
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

std::string output_digest(std::span<const std::uint8_t> bytes) {
  return sha256_hex(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

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
  if (model_gone(job.source)) {
    outcome.kind = ConversionOutcome::Kind::kVanished;
    return finish();
  }
  const auto model_bytes = read_bytes(job.source, job.options.limits.max_file_bytes);
  if (!model_bytes) {
    if (model_gone(job.source)) {
      outcome.kind = ConversionOutcome::Kind::kVanished;
    } else {
      outcome.diagnostics.error("IO_ERROR", "",
                                "cannot read the model (too large, unreadable, or not a regular file)");
    }
    return finish();
  }
  const auto folder = std::filesystem::canonical(job.source.parent_path(), ec);
  outcome.dependencies = referenced_files(*model_bytes, folder);

  // The content hash covers the model and every file it refers to, so a new .bin alone counts.
  std::vector<std::vector<std::uint8_t>> referenced;
  for (const auto& file : outcome.dependencies) {
    referenced.push_back(read_bytes(file, job.options.limits.max_file_bytes, &folder).value_or(std::vector<std::uint8_t>{}));
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

  // The check runs before anything is written: a revision it rejects must never replace the live
  // revision's files (docs/daemon.md, "Outputs").
  std::optional<ValidationSummary> validation;
  if (job.validation) {
    ValidationReport report = validate_dynamics(*conversion, *job.validation, job.source.string());
    if (report.cancelled) {
      outcome.cancelled = true;
      outcome.diagnostics.append(report.diagnostics);
      return finish();
    }
    ValidationSummary summary;
    summary.passed = report.passed;
    summary.simulated_time = report.simulated_time;
    summary.steps = report.steps;
    summary.energy_drift = report.energy_drift;
    summary.worst_joint_error = report.worst_joint_error;
    summary.wall_time = report.wall_time;
    summary.summary_line = validation_summary_line(report);
    summary.diagnostics = std::move(report.diagnostics);
    validation = std::move(summary);
  }
  const bool write = !(validation && !validation->passed) || job.write_failed;
  ConvertedModel converted;
  converted.content_hash = outcome.content_hash;
  converted.validation = std::move(validation);
  if (write) {
    std::filesystem::create_directories(job.output_dir, ec);
    if (ec) {
      outcome.diagnostics.error("WRITE_FAILED", "", "cannot create " + job.output_dir.string() + ": " + ec.message());
      outcome.retry = true;
      return finish();
    }
    converted.output_path = job.output_dir / (job.source.stem().string() + ".rdtf.gltf");
    Diagnostics write_diag(converted.output_path.string());
    WriteOptions write_options;
    write_options.content_digest = output_digest;
    if (!write_rdtf(conversion->asset, converted.output_path, write_options, write_diag, &converted.rdtf_json)) {
      outcome.diagnostics.append(write_diag);
      outcome.retry = has_code(write_diag, "WRITE_FAILED");
      return finish();
    }
    outcome.diagnostics.append(write_diag);
    if (job.urdf) {
      // URDF is a second output: a model URDF cannot express (a ball joint) still converts.
      Diagnostics urdf_diag(converted.output_path.string());
      const auto urdf_dir = job.output_dir / "urdf";
      UrdfOptions urdf_options = *job.urdf;
      urdf_options.mesh_digest = output_digest;
      if (write_urdf(*conversion, urdf_dir, urdf_options, urdf_diag, &converted.urdf)) {
        converted.urdf_path = urdf_dir / "robot.urdf";
        outcome.diagnostics.append(urdf_diag);  // Its warnings (URDF_NAME_CHANGED, ...).
      } else if (has_code(urdf_diag, "WRITE_FAILED")) {
        // The disk, not the model: fail the revision and try again, so no output is left behind.
        outcome.diagnostics.append(urdf_diag);
        outcome.retry = true;
        return finish();
      } else {
        for (const Diagnostic& d : urdf_diag.all()) {
          outcome.diagnostics.warning("URDF_NOT_WRITTEN", d.pointer, d.message);
        }
      }
    }
    converted.written = true;
  }
  converted.totals = robot_totals(conversion->robot);
  converted.robot = std::move(conversion->robot);
  outcome.converted = std::move(converted);
  outcome.kind = ConversionOutcome::Kind::kConverted;
  return finish();
}

}  // namespace rdtf::daemon
