#include <signal.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cctype>
#include <chrono>
#include <cerrno>
#include <iostream>
#include <string>
#include <system_error>

#include "../cli_numbers.h"
#include "commands.h"
#include "rdtf/atomic_file.h"
#include "rdtf/write.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/utf8.h"

namespace rdtf::cli {
namespace fs = std::filesystem;

namespace {

constexpr const char* kOutputInvalid = codes::OUTPUT_PATH_INVALID;

std::string file_type_name(fs::file_type type) {
  switch (type) {
    case fs::file_type::directory: return "a folder";
    case fs::file_type::fifo: return "a FIFO";
    case fs::file_type::socket: return "a socket";
    case fs::file_type::block:
    case fs::file_type::character: return "a device";
    default: return "not a regular file";
  }
}

// `path` without a trailing '/' ("out/" -> "out"), so that parent_path() climbs.
fs::path without_trailing_slash(fs::path path) {
  while (!path.empty() && path.filename().empty() && path != path.root_path()) path = path.parent_path();
  return path;
}

// The nearest existing folder above `path` (itself included) must be a folder for anything to be
// created below it; a file there is an error naming it.
bool can_be_created_in(const fs::path& folder, Diagnostics& diag) {
  for (fs::path at = without_trailing_slash(folder); !at.empty(); at = at.parent_path()) {
    std::error_code error;
    const fs::file_status status = fs::status(at, error);
    if (status.type() == fs::file_type::not_found) {
      if (at == at.parent_path()) break;
      continue;
    }
    // A folder, or one we may not look into: the write says so (an environment error) if it fails.
    if (error || fs::is_directory(status)) return true;
    const std::string type = fs::is_regular_file(status) ? "a file" : file_type_name(status.type());
    diag.error(kOutputInvalid, "", at.string() + " is " + type + ", not a folder: nothing can be written below it");
    return false;
  }
  return true;
}

// A file about to be written over must be a regular file (or nothing): renaming onto a folder
// fails, and onto a device would replace the device. Nor a symbolic link: the rename replaces the
// link itself, not what it points to (`-o /dev/stdout` replaced the system's /dev/stdout link with
// a file when stdout went to a file).
bool can_be_written_over(const fs::path& path, const char* what, Diagnostics& diag) {
  std::error_code error;
  if (fs::is_symlink(fs::symlink_status(path, error))) {
    const fs::path target = fs::read_symlink(path, error);
    diag.error(kOutputInvalid, "",
               std::string(what) + " " + path.string() + " is a symbolic link" +
                   (error ? std::string() : " (to " + target.string() + ")") +
                   ": rdtf writes a new file and renames it into place, which would replace the link, not "
                   "write through it. Give the file the link points to, or another path (rdtf writes no "
                   "model to standard output)");
    return false;
  }
  const fs::file_status status = fs::status(path, error);
  if (status.type() == fs::file_type::not_found || fs::is_regular_file(status) || error) return true;
  diag.error(kOutputInvalid, "", std::string(what) + " " + path.string() + " is " + file_type_name(status.type()) +
                                     ": a file cannot be written there");
  return false;
}

// A relative URI as the writer resolves it below the output's folder (percent-decoded, "." and
// ".." folded); nothing for a data: URI, a scheme, an absolute path or one climbing out, which
// the loader refused already.
std::optional<fs::path> relative_uri(const std::string& uri) {
  if (uri.rfind("data:", 0) == 0 || uri.empty()) return std::nullopt;
  const auto colon = uri.find(':');
  if (colon != std::string::npos && colon < uri.find('/')) return std::nullopt;
  std::string decoded;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      decoded += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      decoded += uri[i];
    }
  }
  if (decoded.front() == '/') return std::nullopt;
  fs::path relative;
  int depth = 0;
  for (std::size_t start = 0; start <= decoded.size();) {
    const std::size_t end = std::min(decoded.find('/', start), decoded.size());
    const std::string segment = decoded.substr(start, end - start);
    if (segment == "..") {
      if (depth-- == 0) return std::nullopt;
      relative = relative.parent_path();
    } else if (!segment.empty() && segment != ".") {
      relative /= segment;
      ++depth;
    }
    start = end + 1;
  }
  if (depth <= 0) return std::nullopt;
  return relative;
}

// The files write_rdtf writes beside a .gltf output, as it names them: every buffer not embedded
// as "<output stem>[_i].bin" (write.cc, external_buffers), every image under its relative URI,
// except an image that already is that very file (it is not written).
std::vector<fs::path> companion_files(const GltfAsset& asset, const fs::path& target) {
  std::vector<fs::path> files;
  const Json& document = asset.document;
  const fs::path folder = target.parent_path();
  if (document.contains("buffers")) {
    const Json& buffers = document["buffers"];
    for (std::size_t i = 0; i < buffers.size(); ++i) {
      const fs::path file = folder / (target.stem().string() + (i == 0 ? "" : "_" + std::to_string(i)) + ".bin");
      if (buffers[i].contains("uri")) {
        const std::string uri = buffers[i]["uri"].get<std::string>();
        if (uri.rfind("data:", 0) == 0) continue;
        // Written over itself (the output beside its input, of the same name): not written.
        std::error_code error;
        const auto relative = relative_uri(uri);
        if (relative && !asset.folder.empty() && fs::equivalent(asset.folder / *relative, file, error)) continue;
      }
      files.push_back(file);
    }
  }
  if (document.contains("images")) {
    for (const Json& image : document["images"]) {
      if (!image.contains("uri")) continue;
      const auto relative = relative_uri(image["uri"].get<std::string>());
      if (!relative) continue;
      std::error_code error;
      if (!asset.folder.empty() && fs::equivalent(asset.folder / *relative, folder / *relative, error)) continue;
      files.push_back(folder / *relative);
    }
  }
  return files;
}

}  // namespace

void add_conversion_options(CLI::App& command, ConvertOptions& options) {
  command.add_option("--density", options.default_density,
                     "Density (kg/m^3) of meshes whose nodes set no rdtf_density")
      ->check(rdtf::cli_numbers::kPositive)
      ->capture_default_str();
  command.add_option("--max-file-bytes", options.limits.max_file_bytes,
                     "Largest model or external file read")
      ->capture_default_str();
  command.add_option("--max-buffer-bytes", options.limits.max_buffer_bytes,
                     "Largest sum of buffer byteLengths")
      ->capture_default_str();
  command.add_option("--max-accessor-count", options.limits.max_accessor_count,
                     "Most elements in one accessor")
      ->capture_default_str();
  command.add_option("--max-triangles", options.limits.max_triangles,
                     "Most triangles in the whole model (a mesh counts per node using it; a vertex a weighed morph target moves, as one more)")
      ->capture_default_str();
}

void print_diagnostics(const Diagnostics& diag, bool include_infos) {
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kInfo && !include_infos) continue;
    // Names and paths come from the input: escaped, so that none can forge a line or drive the terminal.
    std::cerr << escape_for_terminal(format(d)) << "\n";
  }
}

void report_failure(const std::string& input, const char* verb, const Diagnostics& diag) {
  print_diagnostics(diag, true);
  std::cerr << input << ": not " << verb << " (" << diag.error_count() << " error"
            << (diag.error_count() == 1 ? "" : "s") << ")\n";
}

// Unix tools read "-" as standard output: a file or folder named "-" (and "-.bin" beside it) is
// not what was meant.
static bool not_standard_output(const fs::path& target, Diagnostics& diag) {
  if (target != "-") return true;
  diag.error(kOutputInvalid, "",
             "'-' (standard output): rdtf writes no model to standard output, since a .gltf or a URDF has "
             "files beside it; give a path to write (./- for one named '-')");
  return false;
}

bool check_output_file(const fs::path& target, const std::string& example, Diagnostics& diag) {
  const std::string name = target.filename().string();
  if (target.empty()) {
    diag.error(kOutputInvalid, "", "the output path is empty");
    return false;
  }
  if (!not_standard_output(target, diag)) return false;
  std::error_code error;
  const fs::file_status status = fs::status(target, error);
  if (name.empty() || name == "." || name == ".." || fs::is_directory(status)) {
    const fs::path folder = without_trailing_slash(target);
    diag.error(kOutputInvalid, "",
               std::string(fs::is_directory(status) ? "is a folder" : "names a folder (it ends in '/')") +
                   ", not a file: give the file to write, e.g. " + (folder / example).string());
    return false;
  }
  return can_be_written_over(target, "the output", diag) && can_be_created_in(target.parent_path(), diag);
}

bool check_output_folder(const fs::path& dir, const std::vector<std::string>& files, Diagnostics& diag) {
  if (!not_standard_output(dir, diag)) return false;
  std::error_code error;
  const fs::file_status status = fs::status(dir, error);
  if (fs::exists(status) && !fs::is_directory(status)) {
    diag.error(kOutputInvalid, "",
               "is " + (fs::is_regular_file(status) ? std::string("a file") : file_type_name(status.type())) +
                   ", not a folder: give the folder to write into");
    return false;
  }
  if (!can_be_created_in(dir, diag)) return false;
  // The first problem only: a file named meshes would otherwise be reported once per mesh.
  for (const std::string& file : files) {
    if (!can_be_created_in((dir / file).parent_path(), diag) || !can_be_written_over(dir / file, "the output", diag)) {
      return false;
    }
  }
  return true;
}

void OutputFiles::will_write(const fs::path& path) {
  std::error_code error;
  if (!fs::exists(fs::symlink_status(path, error))) new_files_.push_back(path);
}

bool OutputFiles::make_folder(const fs::path& folder, Diagnostics& diag) {
  const fs::path normal = without_trailing_slash(folder);
  if (normal.empty()) return true;
  std::vector<fs::path> missing;  // Deepest first.
  for (fs::path at = normal; !at.empty(); at = at.parent_path()) {
    std::error_code error;
    if (fs::exists(fs::symlink_status(at, error)) || at == at.parent_path()) break;
    missing.push_back(at);
  }
  std::error_code error;
  fs::create_directories(normal, error);
  new_folders_.insert(new_folders_.end(), missing.begin(), missing.end());
  if (error) {
    diag.error(codes::WRITE_FAILED, "", "cannot create the folder " + normal.string() + ": " + error.message());
    return false;
  }
  return true;
}

void OutputFiles::roll_back() {
  std::error_code error;
  for (const fs::path& file : new_files_) fs::remove(file, error);
  // Only empty folders go (fs::remove leaves a folder that holds anything).
  for (const fs::path& folder : new_folders_) fs::remove(folder, error);
}

namespace {

// `text` with the stage folder's path replaced by the folder it stands for: messages name the
// files where the user will find them.
std::string unstaged(std::string text, const std::string& stage, const std::string& folder) {
  for (auto at = text.find(stage); at != std::string::npos; at = text.find(stage, at + folder.size())) {
    text.replace(at, stage.size(), folder);
  }
  return text;
}

// Stage folders (".rdtf-stage.<pid>-<random>.tmp") in `folder` whose writer is gone: an rdtf
// killed mid-write (a CI job at its timeout) left them, tens of megabytes each, and nothing else
// would ever remove them. Only this user's, untouched for an hour, whose pid names no process
// here: a pid says nothing of a writer in another PID namespace (a container sharing the folder),
// so a stage anything wrote to within the hour stays, as does a live writer's here.
void remove_stale_stages(const fs::path& folder) {
  constexpr auto kUntouched = std::chrono::hours(1);
  std::error_code error;
  const auto now = fs::file_time_type::clock::now();
  const auto touched_lately = [&](const fs::path& stage) {
    std::error_code time_error;
    if (now - fs::last_write_time(stage, time_error) < kUntouched || time_error) return true;
    for (fs::recursive_directory_iterator it(stage, time_error), end; !time_error && it != end; it.increment(time_error)) {
      std::error_code entry_error;
      if (now - it->last_write_time(entry_error) < kUntouched || entry_error) return true;
    }
    return static_cast<bool>(time_error);
  };
  std::vector<fs::path> stale;
  for (fs::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    if (name.rfind(".rdtf-stage.", 0) != 0) continue;
    struct stat info {};
    if (::lstat(it->path().c_str(), &info) != 0 || !S_ISDIR(info.st_mode) || info.st_uid != ::geteuid()) continue;
    const auto pid = temporary_writer_pid(name);
    if (!pid || *pid <= 0 || *pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(*pid), 0) == 0 || errno != ESRCH) continue;
    if (touched_lately(it->path())) continue;
    stale.push_back(it->path());
  }
  for (const fs::path& path : stale) fs::remove_all(path, error);
}

// The output and every file beside it written into a stage folder next to the target first, then
// moved into place (the .gltf last): a disk that fills up midway leaves the previous output whole.
bool write_through_stage(const Conversion& conversion, const fs::path& target, bool glb, Durability durability,
                         Diagnostics& diag);

// The stage is removed when write_through_stage returns; one that could not be (out of descriptors:
// removing a tree lists it) is tried once more and else named, never left without a word.
bool write_staged(const Conversion& conversion, const fs::path& target, bool glb, Durability durability,
                  Diagnostics& diag) {
  const bool written = write_through_stage(conversion, target, glb, durability, diag);
  for (const fs::path& left : StagedOutput::remove_left_behind()) {
    diag.warning(codes::IO_ERROR, "", "could not remove the temporary folder " + left.string() + ": remove it by hand");
  }
  return written;
}

bool write_through_stage(const Conversion& conversion, const fs::path& target, bool glb, Durability durability,
                         Diagnostics& diag) {
  const fs::path folder = target.has_parent_path() ? target.parent_path() : fs::path(".");
  std::string why;
  remove_stale_stages(folder);
  auto stage = StagedOutput::create(folder, "rdtf-stage", why);
  if (!stage) {
    diag.error(codes::WRITE_FAILED, "", "cannot write " + target.string() + ": " + why);
    return false;
  }
  Diagnostics staged(target.string());
  WriteOptions options;
  options.format = glb ? OutputFormat::kGlb : OutputFormat::kGltf;
  options.staged_for = folder;
  const bool written = write_rdtf(conversion.asset, stage->folder() / target.filename(), options, staged);
  for (const Diagnostic& d : staged.all()) {
    diag.add(d.severity, d.code, d.pointer, unstaged(d.message, stage->folder().string(), folder.string()));
  }
  if (!written) return false;
  if (!stage->commit(folder, {target.filename()}, why, /*keep_identical=*/true, durability)) {
    diag.error(codes::WRITE_FAILED, "", "cannot move the output into place: " + why);
    return false;
  }
  return true;
}

}  // namespace

void add_sync_flag(CLI::App& command, bool& sync) {
  command.add_flag("--sync", sync,
                   "Make the output durable before exiting (fsync): it then survives a power loss. Without "
                   "it the output is moved into place whole but not synced, as most tools' outputs are");
}

int write_conversion(const Conversion& conversion, const fs::path& target, bool glb,
                     const Diagnostics& diag, bool verbose, Durability durability) {
  Diagnostics write_diag(target.string());
  // Every file of the output checked before the first is written: a folder where the .bin goes
  // would otherwise fail after the .bin beside it was written.
  const std::vector<fs::path> companions =
      glb ? std::vector<fs::path>{} : companion_files(conversion.asset, target);
  bool usable = true;
  for (const fs::path& file : companions) {
    if (file.lexically_normal() == target.lexically_normal()) {
      write_diag.error(kOutputInvalid, "",
                       "the output would be written over by its own buffer or image " + file.filename().string() +
                           ": name the output .gltf (or .glb)");
      usable = false;
    } else {
      usable = can_be_created_in(file.parent_path(), write_diag) &&
               can_be_written_over(file, "the buffer or image", write_diag) && usable;
    }
  }
  print_diagnostics(diag, verbose);
  if (!usable) {
    print_diagnostics(write_diag, true);
    return kExitInvalidInput;
  }
  OutputFiles output;
  bool written = output.make_folder(target.parent_path(), write_diag);
  for (const fs::path& file : companions) {
    written = written && output.make_folder(file.parent_path(), write_diag);
    output.will_write(file);
  }
  output.will_write(target);
  written = written && write_staged(conversion, target, glb, durability, write_diag);
  // No partial output: what this write created goes when any of it failed.
  if (!written) output.roll_back();
  print_diagnostics(write_diag, verbose || !written);
  if (!written) return kExitInternalError;
  std::cerr << "wrote " << target.string() << ": " << conversion.robot.links.size() << " links, "
            << conversion.robot.joints.size() << " joints\n";
  return kExitOk;
}

std::optional<Conversion> convert_or_report(const std::string& input, const ConvertOptions& options,
                                            Diagnostics& diag) {
  auto conversion = convert_file(input, options, diag);
  if (!conversion) report_failure(input, "converted", diag);
  return conversion;
}

}  // namespace rdtf::cli
