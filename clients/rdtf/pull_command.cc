// rdtf pull MODEL_ID -o DIR: the live revision of a model from the bus alone (rdtf_client with
// every blob), written into DIR as the files rdtfd's output folder holds for it (the manifest's
// paths, the same bytes). DIR appears whole or not at all: the files go into a fresh folder
// beside it, which is renamed to DIR at the end.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <set>
#include <iostream>

#include <lcm/lcm-cpp.hpp>

#include "commands.h"
#include "lcm_ready.h"
#include "rdtf/client.h"

namespace rdtf::cli {
namespace {

namespace fs = std::filesystem;

struct PullArguments {
  std::string model_id;
  std::string dir;
  std::string url;
  std::string prefix = "RDTF";
  double timeout = 10;
};

// Writes all of `bytes` to a new file `path` (never through a symlink, never over a file).
std::string write_new_file(const fs::path& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0666);
  if (fd < 0) return "cannot create " + path.string() + ": " + std::strerror(errno);
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const std::string why = std::strerror(errno);
      ::close(fd);
      return "cannot write " + path.string() + ": " + why;
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0 || ::close(fd) != 0) return "cannot write " + path.string() + ": " + std::strerror(errno);
  return "";
}

// DIR may not exist yet (its parent is created) or be an empty folder; anything else is refused.
std::string check_target(const fs::path& dir) {
  std::error_code ec;
  const auto status = fs::symlink_status(dir, ec);
  if (!fs::exists(status)) return "";
  if (!fs::is_directory(status)) return dir.string() + " exists and is not a folder";
  if (!fs::is_empty(dir, ec)) return dir.string() + " exists and is not empty (pull writes a new folder)";
  return "";
}

// The snapshot's files into a stage folder beside `dir`, then the stage renamed to `dir`.
std::string write_snapshot(const rdtf::client::Snapshot& snapshot, const fs::path& dir) {
  const fs::path target = fs::absolute(dir).lexically_normal();
  const fs::path parent = target.parent_path();
  std::error_code ec;
  fs::create_directories(parent, ec);
  if (ec) return "cannot create " + parent.string() + ": " + ec.message();
  std::string pattern = (parent / ("." + target.filename().string() + ".pull-XXXXXX")).string();
  if (::mkdtemp(pattern.data()) == nullptr) return "cannot create a folder in " + parent.string() + ": " + std::strerror(errno);
  const fs::path stage = pattern;
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::chmod(stage.c_str(), 0777 & ~mask);
  auto fail = [&](const std::string& why) {
    fs::remove_all(stage, ec);
    return why;
  };
  for (const auto& file : snapshot.manifest) {
    // The client checked every path already; a second check costs nothing where files are written.
    if (const std::string why = rdtf::client::check_relative_path(file.path); !why.empty()) {
      return fail("manifest path refused: " + why);
    }
    const std::string* bytes = snapshot.file(file.path);
    if (bytes == nullptr) return fail("no bytes for " + file.path);
    const fs::path path = stage / file.path;
    // Folders made here, in a folder made here: no symlink can be on the way.
    fs::create_directories(path.parent_path(), ec);
    if (ec) return fail("cannot create " + path.parent_path().string() + ": " + ec.message());
    if (const std::string why = write_new_file(path, *bytes); !why.empty()) return fail(why);
  }
  if (const std::string why = check_target(target); !why.empty()) return fail(why);
  if (::rename(stage.c_str(), target.c_str()) != 0) {
    return fail("cannot rename " + stage.string() + " to " + target.string() + ": " + std::strerror(errno));
  }
  return "";
}

std::string joined(const std::set<std::string>& ids) {
  if (ids.empty()) return "none (no rdtfd heard: check --lcm-url and the multicast route)";
  std::string out;
  for (const auto& id : ids) out += (out.empty() ? "" : ", ") + id;
  return out;
}

int run_pull(const PullArguments& args) {
  if (const std::string why = check_target(args.dir); !why.empty()) {
    std::cerr << "rdtf pull: " << why << "\n";
    return kExitInvalidInput;
  }
  lcm::LCM lcm(args.url);
  if (const std::string problem = rdtf::lcm_safe::lcm_receive_problem(lcm, args.url); !problem.empty()) {
    std::cerr << "rdtf pull: " << problem << "\n";
    return kExitInternalError;
  }
  rdtf::client::Options options;
  options.prefix = args.prefix;
  options.model = args.model_id;
  options.blobs = rdtf::client::Blobs::kAll;
  options.states = false;
  std::shared_ptr<const rdtf::client::Snapshot> snapshot;
  std::set<std::string> problems;
  rdtf::client::Callbacks callbacks;
  callbacks.on_revision = [&](std::shared_ptr<const rdtf::client::Snapshot> s) { snapshot = std::move(s); };
  callbacks.on_problem = [&](const std::string&, const std::string& text) {
    if (problems.insert(text).second) std::cerr << "rdtf pull: " << text << "\n";
  };
  callbacks.on_error = [&](const rdtf::model_error_t& e) {
    std::cerr << "rdtf pull: " << args.model_id << ": rdtfd reports an error (the live revision "
              << e.live_revision << " stays)\n";
  };
  const auto start = std::chrono::steady_clock::now();
  rdtf::client::Client client(lcm, options, callbacks);
  const auto deadline = start + std::chrono::duration<double>(args.timeout);
  while (!snapshot && std::chrono::steady_clock::now() < deadline) {
    if (lcm.handleTimeout(20) < 0) {
      if (errno == EINTR) continue;  // A signal with a handler (a debugger's, a profiler's).
      std::cerr << "rdtf pull: LCM failed: " << std::strerror(errno) << "\n";
      return kExitInternalError;
    }
    client.tick();
  }
  const auto stats = client.stats();
  if (!snapshot) {
    const auto seen = client.models_seen();
    if (!seen.count(args.model_id)) {
      std::cerr << "rdtf pull: no model '" << args.model_id << "' on the bus within " << args.timeout
                << " s; models seen: " << joined(seen) << "\n";
      return kExitInvalidInput;
    }
    const std::string missing = client.waiting_for(args.model_id);
    std::cerr << "rdtf pull: " << args.model_id << ": no complete revision within " << args.timeout << " s; "
              << (missing.empty() ? std::string("no part of a revision arrived") : "missing " + missing) << " ("
              << stats.blobs_fetched << " blobs received; " << stats.blob_chunks << " chunks used, "
              << stats.blob_chunks_ignored << " ignored, " << stats.blob_chunks_reasked << " asked for again in "
              << stats.blob_retries << " re-requests; " << stats.dropped << " datagrams dropped)\n";
    if (stats.blob_retries > 0 && stats.blob_chunk_size > 1400) {
      // Chunks were lost and asked for again: on a lossy link (Wi-Fi) a chunk of 60,000 bytes is
      // about 41 IP fragments and arrives only when all of them do.
      std::cerr << "rdtf pull: chunks were lost on the way; on a lossy network set rdtfd's max_chunk_bytes to 1400, "
                   "so that each chunk is one packet (docs/lcm.md, \"Lossy links\")\n";
    }
    return kExitInternalError;
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (const std::string why = write_snapshot(*snapshot, args.dir); !why.empty()) {
    std::cerr << "rdtf pull: " << why << "\n";
    return kExitInternalError;
  }
  std::int64_t bytes = 0;
  for (const auto& file : snapshot->manifest) bytes += file.size;
  std::cout << "rdtf pull: " << args.model_id << " revision " << snapshot->revision() << " ("
            << snapshot->content_hash().substr(0, 12) << "): " << snapshot->manifest.size() << " files, " << bytes
            << " bytes into " << args.dir << "; from the bus in " << seconds << " s: " << stats.bytes
            << " bytes in " << stats.datagrams << " datagrams, of which " << stats.blob_bytes << " blob bytes in "
            << stats.blob_chunks << " chunks; " << stats.blob_retries << " blob re-requests (" << stats.blob_chunks_reasked
            << " chunks asked for again), " << stats.requests_sent
            << " description requests\n";
  return kExitOk;
}

}  // namespace

void add_pull_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<PullArguments>();
  CLI::App* command = app.add_subcommand(
      "pull", "Write the live revision of a model from the bus into a folder, as rdtfd's output holds it");
  command->add_option("model_id", args->model_id, "The model's id (its channel name, e.g. arm3.gltf)")->required();
  command->add_option("-o,--output", args->dir, "The folder to create (must not exist, or be empty)")->required();
  command->add_option("--lcm-url", args->url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  command->add_option("--channel-prefix", args->prefix, "rdtfd's channel prefix")->capture_default_str();
  command->add_option("--timeout", args->timeout, "Seconds to wait for the model")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 86400.0));
  command->callback([args, &exit_code] { exit_code = run_pull(*args); });
}

}  // namespace rdtf::cli
