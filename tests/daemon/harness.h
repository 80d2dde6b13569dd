// Harness for the rdtfd integration tests (tests/daemon/*_itest.cc, program rdtf_itests).
//
// How these tests run
// -------------------
// - ctest runs every test case of rdtf_itests as its own process inside a fresh network namespace
//   (tests/support/in_netns.sh: `unshare -n`, loopback up with multicast, a route for
//   224.0.0.0/4). LCM's default URL (udpm://239.255.76.67:7667?ttl=0) therefore works, no traffic
//   leaves the machine, and parallel test cases never hear each other. Run them with
//     ctest --test-dir build -L integration --output-on-failure
//   or one case by hand:
//     tests/support/in_netns.sh build/tests/rdtf_itests --gtest_filter='DaemonWatch.Delete*'
//   (running rdtf_itests outside a namespace would multicast on the host's network: don't).
// - Each test starts the real `rdtfd` (RDTFD_PATH) as a child process on a temporary watched
//   folder and a temporary output folder, with a config file written by the test
//   (status_period_ms 100 so that tests can synchronise on the heartbeat; "validate": false and
//   "simulate": false unless a test is about them: the ODE check adds a VALIDATION message per
//   revision and the live simulation a JOINT_STATE stream, both covered by the dynamics tests
//   and by DaemonLife.DefaultsValidateEveryRevisionBeforePublishingIt) and the command line
//   options --watch, --output, --settle-ms and --republish-ms (0 unless the test is about
//   republishing). rdtfd's stdout and stderr (its log) go to a file; on a failure the test prints
//   it.
// - A Subscriber (an lcm::LCM on the default URL, its own thread) records every message on
//   `RDTF/.*` with its channel, its bytes and its decoding by clients/echo/message_json.h. It is
//   created before the daemon starts, so nothing is missed.
// - Tests synchronise on messages, never on fixed sleeps: wait_for() polls the recorded messages
//   until a condition holds or a deadline of a few seconds passes. "Nothing else happened" is
//   checked after the daemon reports quiet: wait_idle() waits for STATUS heartbeats (published
//   after everything queued before them) showing no pending model and unchanged counters.
//   Sleeps appear only where a test deliberately spaces writes (partial writes, a slow writer).
// - Expected content comes from the files the test wrote: content_hash is computed here the way
//   the daemon does (SHA-256 over each file's 64-bit length and bytes: the model, then every file
//   it refers to, in the order of its buffers/images); masses come from `rdtf inspect --json`
//   (RDTF_CLI_PATH) run on the same file.
// - Models are either fixtures (tests/data/blender) or generated here (box_model()): chains of
//   boxes whose masses are known in closed form, with an external .bin or an embedded buffer;
//   many_parts_model() gives a small file whose RDTF JSON needs several DESCRIPTION_CHUNKs.
// - The inotify overflow test holds rdtfd with SIGSTOP while it makes 20,000 events (more than
//   the kernel's max_queued_events, 16384, which is global and left alone), then SIGCONT.
// - Other programs (lcm-logger, lcm-logplayer, rdtf-echo) run as ChildProcess, their output to a
//   file. Every child is killed by its destructor if a test ends early; temporary folders go too.
// - Budget: each case has deadlines of a few seconds; the whole label runs in about 30 s.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <openssl/evp.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>

#include <rdtf/description_chunk_t.hpp>
#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "message_json.h"
#include "support/test_support.h"

extern char** environ;

namespace rdtf::itest {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using Json = nlohmann::json;
using namespace std::chrono_literals;
using testing::TempDir;

inline constexpr const char* kPrefix = "RDTF";

// ------------------------------------------------------------------------------------------------
// Hashes

inline std::string to_hex(const unsigned char* data, unsigned int size) {
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < size; ++i) {
    out += kHex[data[i] >> 4];
    out += kHex[data[i] & 15];
  }
  return out;
}

// SHA-256 of the given parts. length_prefixed: each part preceded by its size as a host-order
// 64-bit integer (the daemon's content_hash scheme); otherwise the plain SHA-256 of the bytes.
inline std::string sha256(const std::vector<std::string>& parts, bool length_prefixed) {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  EVP_DigestInit_ex(context, EVP_sha256(), nullptr);
  for (const auto& part : parts) {
    if (length_prefixed) {
      const std::uint64_t size = part.size();
      EVP_DigestUpdate(context, &size, sizeof(size));
    }
    EVP_DigestUpdate(context, part.data(), part.size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest, &length);
  EVP_MD_CTX_free(context);
  return to_hex(digest, length);
}

// The plain SHA-256 of a byte string (what `sha256sum` prints).
inline std::string sha256_plain(const std::string& bytes) { return sha256({bytes}, false); }

// content_hash as the daemon computes it: the model file, then each file it refers to.
inline std::string content_hash(const std::string& model, const std::vector<std::string>& referenced = {}) {
  std::vector<std::string> parts{model};
  parts.insert(parts.end(), referenced.begin(), referenced.end());
  return sha256(parts, true);
}

inline std::string short_hash(const std::string& hash) { return hash.substr(0, 12); }

// ------------------------------------------------------------------------------------------------
// Files

inline std::string read(const fs::path& path) { return testing::read_file(path); }

// Writes in place (open with O_TRUNC, write, close), as Blender does.
inline void write_in_place(const fs::path& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("open " + path.string());
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n <= 0) throw std::runtime_error("write " + path.string());
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
}

// Writes `temp` in full, then renames it over `path` (what most editors do).
inline void write_by_rename(const fs::path& path, const std::string& bytes, const std::string& temp_name) {
  const fs::path temp = path.parent_path() / temp_name;
  write_in_place(temp, bytes);
  fs::rename(temp, path);
}

// An open file written in several pieces, closed at the end (or by the destructor).
class OpenFile {
 public:
  explicit OpenFile(const fs::path& path, int flags = O_WRONLY | O_CREAT | O_TRUNC)
      : fd_(::open(path.c_str(), flags | O_CLOEXEC, 0644)) {
    if (fd_ < 0) throw std::runtime_error("open " + path.string());
  }
  ~OpenFile() { close(); }
  OpenFile(const OpenFile&) = delete;
  OpenFile& operator=(const OpenFile&) = delete;
  void write(const std::string& bytes) {
    if (::write(fd_, bytes.data(), bytes.size()) != static_cast<ssize_t>(bytes.size())) {
      throw std::runtime_error("short write");
    }
  }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_;
};

// ------------------------------------------------------------------------------------------------
// Generated models: a chain of `links` boxes (cube half-size `half` metres each, default density:
// 1000 * (2 half)^3 kg per link), joined by revolute joints. The base link is named `name`, so the
// RDTF JSON shows which version a description carries. With `bin_name` empty the buffer is
// embedded as a data: URI; otherwise the model refers to `bin_name` and `bin` holds its bytes.

struct GeneratedModel {
  std::string gltf;
  std::string bin;       // "" when embedded.
  std::string bin_name;  // "" when embedded.
  int links = 0;
  double link_mass = 0;  // Each box at 1000 kg/m^3.
};

inline std::string base64(const std::string& bytes) {
  static const char* const kTable = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const unsigned v = (static_cast<unsigned char>(bytes[i]) << 16) |
                       (static_cast<unsigned char>(bytes[i + 1]) << 8) | static_cast<unsigned char>(bytes[i + 2]);
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += kTable[v >> 6 & 63];
    out += kTable[v & 63];
  }
  if (i < bytes.size()) {
    unsigned v = static_cast<unsigned char>(bytes[i]) << 16;
    if (i + 1 < bytes.size()) v |= static_cast<unsigned char>(bytes[i + 1]) << 8;
    out += kTable[v >> 18 & 63];
    out += kTable[v >> 12 & 63];
    out += i + 1 < bytes.size() ? kTable[v >> 6 & 63] : '=';
    out += '=';
  }
  return out;
}

inline GeneratedModel box_model(const std::string& name, double half, int links = 1,
                                const std::string& bin_name = "") {
  // 8 corners (bit 0: +x, bit 1: +y, bit 2: +z), 12 triangles wound outwards.
  std::string bin;
  auto put_float = [&](float f) { bin.append(reinterpret_cast<const char*>(&f), 4); };
  auto put_u16 = [&](std::uint16_t v) { bin.append(reinterpret_cast<const char*>(&v), 2); };
  const float h = static_cast<float>(half);
  for (int c = 0; c < 8; ++c) {
    put_float(c & 1 ? h : -h);
    put_float(c & 2 ? h : -h);
    put_float(c & 4 ? h : -h);
  }
  const int quads[6][4] = {{1, 3, 7, 5}, {0, 4, 6, 2}, {2, 6, 7, 3}, {0, 1, 5, 4}, {4, 5, 7, 6}, {0, 2, 3, 1}};
  for (const auto& q : quads) {
    for (int v : {q[0], q[1], q[2], q[0], q[2], q[3]}) put_u16(static_cast<std::uint16_t>(v));
  }
  const std::size_t size = bin.size();  // 96 + 72 = 168 bytes.

  Json nodes = Json::array();
  if (links == 1) {
    nodes.push_back({{"name", name}, {"mesh", 0}});
  } else {
    // base (mesh) -> joint_1 -> link_1 -> [geom_1, joint_2 -> link_2 -> ...]
    nodes.push_back({{"name", name}, {"mesh", 0}, {"children", {1}}});
    for (int i = 1; i < links; ++i) {
      const int joint = static_cast<int>(nodes.size());
      const int link = joint + 1;
      const int geom = joint + 2;
      nodes.push_back({{"name", "joint_" + std::to_string(i)},
                       {"translation", {0.0, 2 * half + 0.01, 0.0}},
                       {"extras", {{"rdtf_joint", "revolute"}, {"rdtf_axis", {0.0, 0.0, 1.0}}}},
                       {"children", {link}}});
      Json link_node = {{"name", "link_" + std::to_string(i)}, {"children", {geom}}};
      if (i + 1 < links) link_node["children"].push_back(geom + 1);
      nodes.push_back(link_node);
      nodes.push_back({{"name", "geom_" + std::to_string(i)}, {"mesh", 0}});
    }
  }
  Json buffer = {{"byteLength", size}};
  buffer["uri"] = bin_name.empty() ? "data:application/octet-stream;base64," + base64(bin) : bin_name;
  const Json document = {
      {"asset", {{"version", "2.0"}, {"generator", "rdtf itest"}}},
      {"scene", 0},
      {"scenes", {{{"nodes", {0}}}}},
      {"nodes", nodes},
      {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
      {"accessors",
       {{{"bufferView", 0}, {"componentType", 5126}, {"count", 8}, {"type", "VEC3"},
         {"min", {-h, -h, -h}}, {"max", {h, h, h}}},
        {{"bufferView", 1}, {"componentType", 5123}, {"count", 36}, {"type", "SCALAR"}}}},
      {"bufferViews",
       {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 96}, {"target", 34962}},
        {{"buffer", 0}, {"byteOffset", 96}, {"byteLength", 72}, {"target", 34963}}}},
      {"buffers", {buffer}}};
  GeneratedModel model;
  model.gltf = document.dump(1);
  if (!bin_name.empty()) {
    model.bin = bin;
    model.bin_name = bin_name;
  }
  model.links = links;
  const double edge = 2.0 * static_cast<double>(h);
  model.link_mass = 1000.0 * edge * edge * edge;
  return model;
}

// One link made of `parts` boxes side by side (one mesh used by `parts` nodes): a small file with
// a large document, for descriptions that need chunks. Buffer embedded.
inline GeneratedModel many_parts_model(const std::string& name, int parts, double half) {
  GeneratedModel model = box_model(name, half);
  Json document = Json::parse(model.gltf);
  Json nodes = Json::array();
  Json root = {{"name", name}, {"children", Json::array()}};
  nodes.push_back(root);
  for (int i = 0; i < parts; ++i) {
    char part[32];
    std::snprintf(part, sizeof(part), "part_%05d", i);
    nodes[0]["children"].push_back(i + 1);
    nodes.push_back({{"name", part}, {"mesh", 0}, {"translation", {3.0 * half * i, 0.0, 0.0}}});
  }
  document["nodes"] = nodes;
  model.gltf = document.dump(1);
  model.link_mass *= parts;  // All in one link.
  return model;
}

// Writes a generated model into `folder` as `file_name` (and its .bin), in place.
inline fs::path write_model(const fs::path& folder, const std::string& file_name, const GeneratedModel& model) {
  if (!model.bin_name.empty()) write_in_place(folder / model.bin_name, model.bin);
  write_in_place(folder / file_name, model.gltf);
  return folder / file_name;
}

// The daemon's content_hash for a generated model.
inline std::string content_hash(const GeneratedModel& model) {
  return model.bin_name.empty() ? content_hash(model.gltf) : content_hash(model.gltf, {model.bin});
}

// A model that parses but cannot be converted: a mesh refers to an accessor that does not exist.
inline std::string broken_model() {
  Json document = Json::parse(box_model("broken", 0.1).gltf);
  document["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = 7;
  return document.dump(1);
}

// A two-link chain that converts but fails the dynamics check: link_1 weighs a millionth of the
// base (JOINT_MASS_RATIO, beyond the default bound of 1e3; docs/dynamics.md).
inline GeneratedModel gate_failing_model(const std::string& name, double half, const std::string& bin_name = "") {
  GeneratedModel model = box_model(name, half, 2, bin_name);
  Json document = Json::parse(model.gltf);
  document["nodes"][2]["extras"]["rdtf_mass"] = model.link_mass * 1e-6;
  model.gltf = document.dump(1);
  return model;
}

// Every regular file below `folder` (relative path -> bytes): what a reader of the outputs finds.
// The daemon's revision state (<output>/.rdtfd-state, docs/daemon.md) is no output: left out.
inline std::map<std::string, std::string> snapshot(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (auto it = fs::recursive_directory_iterator(folder); it != fs::recursive_directory_iterator(); ++it) {
    if (it->is_directory() && it->path().filename() == ".rdtfd-state") {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file()) files[fs::relative(it->path(), folder).string()] = read(it->path());
  }
  return files;
}

// A fixture (tests/data/blender/<stem>.gltf and its .bin) copied into `folder`.
inline fs::path copy_fixture(const fs::path& folder, const std::string& stem, const std::string& as = "") {
  const fs::path source = testing::data_dir() / "blender";
  const std::string name = as.empty() ? stem : as;
  // The .bin keeps its name: the .gltf refers to it.
  fs::copy_file(source / (stem + ".bin"), folder / (stem + ".bin"), fs::copy_options::overwrite_existing);
  fs::copy_file(source / (stem + ".gltf"), folder / (name + ".gltf"), fs::copy_options::overwrite_existing);
  fs::permissions(folder / (name + ".gltf"), fs::perms::owner_write, fs::perm_options::add);
  fs::permissions(folder / (stem + ".bin"), fs::perms::owner_write, fs::perm_options::add);
  return folder / (name + ".gltf");
}

inline std::string fixture_hash(const std::string& stem) {
  const fs::path source = testing::data_dir() / "blender";
  return content_hash(read(source / (stem + ".gltf")), {read(source / (stem + ".bin"))});
}

// `rdtf inspect --json` of a file: {"links": [{"name", "mass", ...}], ...}.
inline Json inspect(const fs::path& model, const std::string& options = "") {
  const auto run = testing::run_command("'" + testing::cli_path() + "' inspect --json " + options + " '" +
                                        model.string() + "'");
  if (run.exit_code != 0) throw std::runtime_error("rdtf inspect failed on " + model.string() + ": " + run.err);
  return Json::parse(run.out);
}

// ------------------------------------------------------------------------------------------------
// Waiting

template <typename Predicate>
bool wait_until(Predicate predicate, Clock::duration timeout) {
  // Deadlines only bound how long a failing test hangs; sanitizer builds run several times slower
  // (RDTF_TEST_DEADLINE_SCALE, set by CMake), so their deadlines stretch by that factor.
  const auto deadline = Clock::now() + timeout * RDTF_TEST_DEADLINE_SCALE;
  for (;;) {
    if (predicate()) return true;
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(5ms);
  }
}

// ------------------------------------------------------------------------------------------------
// LCM subscriber

struct Message {
  std::string channel;
  std::vector<std::uint8_t> bytes;
  Json json;  // message_to_json(bytes), null when not an rdtf type.
  Clock::time_point received;

  template <typename T>
  T as() const {
    T message;
    if (message.decode(bytes.data(), 0, static_cast<int>(bytes.size())) < 0) {
      throw std::runtime_error("message on " + channel + " does not decode as the type asked for");
    }
    return message;
  }
  // "<prefix>/<model_id>/<KIND>": KIND and model_id ("" for STATUS and REQUEST).
  std::string kind() const { return channel.substr(channel.rfind('/') + 1); }
  std::string model_id() const {
    const auto first = channel.find('/');
    const auto last = channel.rfind('/');
    return first == last ? "" : channel.substr(first + 1, last - first - 1);
  }
};

class Subscriber {
 public:
  explicit Subscriber(const std::string& channels = std::string(kPrefix) + "/.*", const std::string& url = "")
      : lcm_(url) {
    if (!lcm_.good()) throw std::runtime_error("cannot open LCM (is this running in tests/support/in_netns.sh?)");
    auto* subscription = lcm_.subscribe(channels, &Subscriber::on_message, this);
    subscription->setQueueCapacity(100000);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~Subscriber() {
    stop_ = true;
    thread_.join();
  }
  Subscriber(const Subscriber&) = delete;
  Subscriber& operator=(const Subscriber&) = delete;

  std::vector<Message> messages() const {
    std::lock_guard lock(mutex_);
    return messages_;
  }
  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return messages_.size();
  }

  template <typename T>
  void publish(const std::string& channel, const T& message) {
    if (lcm_.publish(channel, &message) != 0) throw std::runtime_error("publish failed on " + channel);
  }

  // Waits until `predicate(messages)` holds; false at the deadline.
  bool wait_for(const std::function<bool(const std::vector<Message>&)>& predicate,
                Clock::duration timeout = 5s) const {
    return wait_until(
        [&] {
          std::lock_guard lock(mutex_);
          return predicate(messages_);
        },
        timeout);
  }

 private:
  void on_message(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
    Message message;
    message.channel = channel;
    const auto* data = static_cast<const std::uint8_t*>(buffer->data);
    message.bytes.assign(data, data + buffer->data_size);
    if (auto json = rdtf::clients::message_to_json(buffer->data, buffer->data_size)) {
      message.json = Json::parse(json->dump());
    }
    message.received = Clock::now();
    std::lock_guard lock(mutex_);
    messages_.push_back(std::move(message));
  }

  lcm::LCM lcm_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable std::mutex mutex_;
  std::vector<Message> messages_;
};

// ------------------------------------------------------------------------------------------------
// Views of recorded messages

inline std::vector<Message> on_kind(const std::vector<Message>& all, const std::string& kind,
                                    const std::string& model_id = "*") {
  std::vector<Message> out;
  for (const auto& m : all) {
    if (m.kind() == kind && (model_id == "*" || m.model_id() == model_id)) out.push_back(m);
  }
  return out;
}

template <typename T>
std::vector<T> decoded(const std::vector<Message>& all, const std::string& kind, const std::string& model_id = "*") {
  std::vector<T> out;
  for (const auto& m : on_kind(all, kind, model_id)) out.push_back(m.as<T>());
  return out;
}

inline std::vector<rdtf::status_t> statuses(const std::vector<Message>& all) {
  return decoded<rdtf::status_t>(all, "STATUS");
}

// One line per message about models (not STATUS or REQUEST), in arrival order:
//   "arm.gltf DESCRIPTION r2 0123456789ab", "arm.gltf INERTIA r2 ...", "arm.gltf ERROR live=1 ...",
//   "arm.gltf REMOVED last=2", "big.gltf DESCRIPTION_CHUNK r1 0/3", "big.gltf URDF_CHUNK r1 0/2"
inline std::string describe(const Message& m) {
  const std::string kind = m.kind();
  const std::string head = m.model_id() + " " + kind;
  if (kind == "DESCRIPTION") {
    const auto d = m.as<rdtf::description_t>();
    return head + " r" + std::to_string(d.revision) + " " + short_hash(d.content_hash);
  }
  if (kind == "INERTIA") {
    const auto t = m.as<rdtf::inertia_table_t>();
    return head + " r" + std::to_string(t.revision) + " " + short_hash(t.content_hash);
  }
  if (kind == "DESCRIPTION_CHUNK" || kind == "URDF_CHUNK") {
    const auto c = m.as<rdtf::description_chunk_t>();
    return head + " r" + std::to_string(c.revision) + " " + std::to_string(c.index) + "/" + std::to_string(c.count);
  }
  if (kind == "ERROR") {
    const auto e = m.as<rdtf::model_error_t>();
    return head + " live=" + std::to_string(e.live_revision) + " " + short_hash(e.content_hash);
  }
  if (kind == "VALIDATION") {
    const auto v = m.as<rdtf::validation_report_t>();
    return head + " r" + std::to_string(v.revision) + " " + short_hash(v.content_hash) +
           (v.passed ? " passed" : " failed");
  }
  if (kind == "REMOVED") {
    return head + " last=" + std::to_string(m.as<rdtf::model_removed_t>().last_revision);
  }
  return head;
}

// Left out: the MANIFEST that precedes every DESCRIPTION (blobs_itest.cc checks it and its place)
// and the DELTA that follows each new revision's INERTIA, never a republication (revisions_itest.cc).
inline std::vector<std::string> model_events(const std::vector<Message>& all, const std::string& model_id = "*") {
  std::vector<std::string> out;
  for (const auto& m : all) {
    if (m.model_id().empty() || m.kind() == "MANIFEST" || m.kind() == "DELTA") continue;
    if (model_id != "*" && m.model_id() != model_id) continue;
    out.push_back(describe(m));
  }
  return out;
}

// What one accepted revision looks like to a subscriber (small models: no chunks).
inline std::vector<std::string> revision_events(const std::string& id, int revision, const std::string& hash) {
  return {id + " DESCRIPTION r" + std::to_string(revision) + " " + short_hash(hash),
          id + " INERTIA r" + std::to_string(revision) + " " + short_hash(hash)};
}

inline std::vector<std::string> concat(std::vector<std::vector<std::string>> parts) {
  std::vector<std::string> out;
  for (auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

// True when a DESCRIPTION of `id` with this revision and hash has arrived.
inline bool has_revision(const std::vector<Message>& all, const std::string& id, std::int64_t revision,
                         const std::string& hash) {
  for (const auto& d : decoded<rdtf::description_t>(all, "DESCRIPTION", id)) {
    if (d.revision == revision && d.content_hash == hash) return true;
  }
  return false;
}

inline std::optional<rdtf::description_t> last_description(const std::vector<Message>& all, const std::string& id) {
  auto all_of = decoded<rdtf::description_t>(all, "DESCRIPTION", id);
  if (all_of.empty()) return std::nullopt;
  return all_of.back();
}

inline std::optional<rdtf::inertia_table_t> last_inertia(const std::vector<Message>& all, const std::string& id) {
  auto all_of = decoded<rdtf::inertia_table_t>(all, "INERTIA", id);
  if (all_of.empty()) return std::nullopt;
  return all_of.back();
}

// ------------------------------------------------------------------------------------------------
// Content checks

// A description's document: valid JSON, a glTF with extras.RDTF, the announced size and link count.
inline void expect_document(const rdtf::description_t& d, const std::string& base_name = "") {
  SCOPED_TRACE("description of " + d.model_id + " r" + std::to_string(d.revision));
  EXPECT_EQ(d.num_chunks, 0);
  EXPECT_EQ(static_cast<std::size_t>(d.rdtf_json_size), d.rdtf_json.size());
  Json document;
  ASSERT_NO_THROW(document = Json::parse(d.rdtf_json));
  ASSERT_TRUE(document.contains("extras") && document["extras"].contains("RDTF")) << d.rdtf_json.substr(0, 300);
  EXPECT_TRUE(document["extras"]["RDTF"].is_object());
  EXPECT_EQ(document["asset"]["version"], "2.0");
  if (!base_name.empty()) {
    bool found = false;
    for (const auto& node : document["nodes"]) found |= node.value("name", "") == base_name;
    EXPECT_TRUE(found) << "no node named " << base_name << " in the published document";
  }
  // The published document is the output file the daemon wrote.
  EXPECT_TRUE(fs::exists(d.output_path)) << d.output_path;
}

// The inertia table against `rdtf inspect --json` of the same file (the same conversion).
inline void expect_inertia_matches(const rdtf::inertia_table_t& table, const Json& inspected) {
  SCOPED_TRACE("inertia of " + table.model_id + " r" + std::to_string(table.revision));
  ASSERT_EQ(table.num_links, static_cast<std::int32_t>(table.links.size()));
  ASSERT_EQ(table.links.size(), inspected["links"].size());
  double total = 0;
  for (std::size_t i = 0; i < table.links.size(); ++i) {
    const Json& link = inspected["links"][i];
    // `rdtf inspect` names links as the glTF does; the table's `name` is the URDF's.
    EXPECT_EQ(table.links[i].gltf_name, link["name"].get<std::string>());
    const double mass = link["mass"].get<double>();
    EXPECT_NEAR(table.links[i].mass, mass, 1e-9 * std::max(1.0, mass)) << table.links[i].name;
    total += mass;
  }
  EXPECT_NEAR(table.total_mass, total, 1e-9 * std::max(1.0, total));
}

// ------------------------------------------------------------------------------------------------
// The daemon

struct DaemonOptions {
  std::vector<fs::path> watch;
  fs::path output;
  int settle_ms = 50;
  int republish_ms = 0;
  Json config = Json::object();  // Config file keys, over the defaults of write_config().
  std::vector<std::string> extra_args;
  bool folders_on_command_line = true;  // false: "watch" and "output" come from `config` only.
  fs::path working_directory;  // The daemon's; empty: the test's. "/" is what systemd gives.
  std::vector<std::string> environment;  // "NAME=value" entries added to the test's environment.

  DaemonOptions& with_settle(int ms) { settle_ms = ms; return *this; }
  DaemonOptions& with_republish(int ms) { republish_ms = ms; return *this; }
  DaemonOptions& with_output(fs::path folder) { output = std::move(folder); return *this; }
  DaemonOptions& with_watch(std::vector<fs::path> folders) { watch = std::move(folders); return *this; }
  DaemonOptions& with(const std::string& key, Json value) { config[key] = std::move(value); return *this; }
  DaemonOptions& with_args(std::vector<std::string> args) { extra_args = std::move(args); return *this; }
  DaemonOptions& with_folders_in_config() { folders_on_command_line = false; return *this; }
  DaemonOptions& in_directory(fs::path folder) { working_directory = std::move(folder); return *this; }
  DaemonOptions& with_env(std::string entry) { environment.push_back(std::move(entry)); return *this; }
};

class DaemonProcess {
 public:
  explicit DaemonProcess(DaemonOptions options) : options_(std::move(options)) {
    config_path_ = files_ / "rdtfd.json";
    log_path_ = files_ / "rdtfd.log";
    write_config(options_.config);
    start();
  }
  ~DaemonProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }
  DaemonProcess(const DaemonProcess&) = delete;
  DaemonProcess& operator=(const DaemonProcess&) = delete;

  pid_t pid() const { return pid_; }
  pid_t last_pid() const { return last_pid_; }  // Still known after it exited.
  const fs::path& config_path() const { return config_path_; }
  std::string log() const {
    std::ifstream in(log_path_);
    std::stringstream text;
    text << in.rdbuf();
    return text.str();
  }
  // Writes the config file: `config` over the tests' defaults.
  void write_config(const Json& config) {
    Json full = {{"status_period_ms", 100}, {"validate", false}, {"simulate", false}};
    full.update(config);
    testing::write_file(config_path_, full.dump(2));
  }
  void signal(int number) const {
    if (pid_ > 0) ::kill(pid_, number);
  }
  // SIGTERM, then the exit code (nothing if it has not exited by the deadline).
  std::optional<int> stop(Clock::duration timeout = 5s) {
    signal(SIGTERM);
    return wait_exit(timeout);
  }
  // Starts the daemon again with the same options (after it exited or was killed); the log
  // continues in the same file.
  void restart() {
    if (running()) throw std::runtime_error("restart: rdtfd is still running");
    start();
  }
  // Waits until the log contains `text` (for events that send no message).
  bool wait_log(const std::string& text, Clock::duration timeout = 5s) const {
    return wait_until([&] { return log().find(text) != std::string::npos; }, timeout);
  }
  bool running() {
    if (pid_ <= 0) return false;
    int status = 0;
    const pid_t done = ::waitpid(pid_, &status, WNOHANG);
    if (done == pid_) {
      exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      pid_ = -1;
      return false;
    }
    return true;
  }
  // The exit code (128 + signal when killed) once it exits; nothing at the deadline.
  std::optional<int> wait_exit(Clock::duration timeout) {
    wait_until([&] { return !running(); }, timeout);
    if (pid_ > 0) return std::nullopt;
    return exit_code_;
  }

 private:
  void start() {
    std::vector<std::string> args = {RDTFD_PATH, "--config", config_path_.string()};
    if (options_.folders_on_command_line) {
      for (const auto& folder : options_.watch) {
        args.push_back("--watch");
        args.push_back(folder.string());
      }
      args.push_back("--output");
      args.push_back(options_.output.string());
    }
    args.push_back("--settle-ms");
    args.push_back(std::to_string(options_.settle_ms));
    args.push_back("--republish-ms");
    args.push_back(std::to_string(options_.republish_ms));
    args.insert(args.end(), options_.extra_args.begin(), options_.extra_args.end());
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, log_path_.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    if (!options_.working_directory.empty()) {
      posix_spawn_file_actions_addchdir_np(&actions, options_.working_directory.c_str());
    }
    std::vector<std::string> environment = options_.environment;
    for (char** entry = environ; *entry != nullptr; ++entry) environment.emplace_back(*entry);
    std::vector<char*> envp;
    for (auto& entry : environment) envp.push_back(entry.data());
    envp.push_back(nullptr);
    const int error = posix_spawn(&pid_, RDTFD_PATH, &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) throw std::runtime_error(std::string("cannot start rdtfd: ") + std::strerror(error));
    last_pid_ = pid_;
  }

  DaemonOptions options_;
  TempDir files_;
  fs::path config_path_;
  fs::path log_path_;
  pid_t pid_ = -1;
  pid_t last_pid_ = -1;
  int exit_code_ = -1;
};

// Any other program run by a test (lcm-logger, lcm-logplayer, rdtf-echo), stdout and stderr to
// `output`. Killed by the destructor if still running.
class ChildProcess {
 public:
  ChildProcess(std::vector<std::string> args, const fs::path& output) : output_(output) {
    std::vector<char*> argv;
    for (auto& arg : args) argv.push_back(arg.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    const int error = posix_spawnp(&pid_, argv[0], &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    if (error != 0) throw std::runtime_error("cannot start " + args[0] + ": " + std::strerror(error));
  }
  ~ChildProcess() {
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      int status = 0;
      ::waitpid(pid_, &status, 0);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  void signal(int number) const {
    if (pid_ > 0) ::kill(pid_, number);
  }
  std::optional<int> wait_exit(Clock::duration timeout) {
    wait_until(
        [&] {
          int status = 0;
          if (pid_ > 0 && ::waitpid(pid_, &status, WNOHANG) == pid_) {
            exit_code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
            pid_ = -1;
          }
          return pid_ <= 0;
        },
        timeout);
    if (pid_ > 0) return std::nullopt;
    return exit_code_;
  }
  std::string output() const { return testing::read_file(output_); }

 private:
  fs::path output_;
  pid_t pid_ = -1;
  int exit_code_ = -1;
};

// A watched folder, an output folder, a subscriber started first, and rdtfd.
struct Session {
  // prefix: the daemon's channel prefix (give the daemon --channel-prefix too when not RDTF).
  explicit Session(std::string channel_prefix = kPrefix)
      : prefix(std::move(channel_prefix)), subscriber(prefix + "/.*") {
    fs::create_directories(watch);
    fs::create_directories(output);
  }
  std::string prefix;
  TempDir root;
  fs::path watch = root / "models";
  fs::path output = root / "out";
  Subscriber subscriber;
  std::unique_ptr<DaemonProcess> daemon;

  ~Session() {
    if (::testing::Test::HasFailure() && daemon) {
      std::cerr << "---- rdtfd log ----\n" << daemon->log() << "-------------------\n";
    }
  }

  // Starts rdtfd and waits for its first heartbeat.
  DaemonProcess& start(DaemonOptions options = {}) {
    if (options.folders_on_command_line && options.watch.empty()) options.watch = {watch};
    if (options.folders_on_command_line && options.output.empty()) options.output = output;
    daemon = std::make_unique<DaemonProcess>(std::move(options));
    const pid_t pid = daemon->pid();
    const bool up = subscriber.wait_for(
        [&](const std::vector<Message>& all) {
          for (const auto& s : statuses(all)) {
            if (s.pid == pid) return true;
          }
          return false;
        },
        10s);
    if (!up) throw std::runtime_error("rdtfd sent no STATUS within 10 s; log:\n" + daemon->log());
    return *daemon;
  }

  std::vector<Message> messages() const { return subscriber.messages(); }

  // Waits for a condition on the recorded messages.
  bool wait_for(const std::function<bool(const std::vector<Message>&)>& predicate, Clock::duration timeout = 5s) {
    return subscriber.wait_for(predicate, timeout);
  }
  bool wait_revision(const std::string& id, std::int64_t revision, const std::string& hash,
                     Clock::duration timeout = 5s) {
    // The INERTIA too: it follows the DESCRIPTION, and a test that reads it next must not see the
    // previous revision's table.
    return wait_for(
        [&](const auto& all) {
          if (!has_revision(all, id, revision, hash)) return false;
          for (const auto& t : decoded<rdtf::inertia_table_t>(all, "INERTIA", id)) {
            if (t.revision == revision && t.content_hash == hash) return true;
          }
          return false;
        },
        timeout);
  }

  // Waits until the daemon is idle: `quiet` consecutive STATUS messages, all received after
  // this call, with nothing pending and the same counters. Returns the last of them.
  std::optional<rdtf::status_t> wait_idle(int quiet = 3, Clock::duration timeout = 5s) {
    const std::size_t from = subscriber.size();
    std::optional<rdtf::status_t> result;
    subscriber.wait_for(
        [&](const std::vector<Message>& all) {
          std::vector<rdtf::status_t> seen;
          for (std::size_t i = from; i < all.size(); ++i) {
            if (all[i].kind() == "STATUS") seen.push_back(all[i].as<rdtf::status_t>());
          }
          int run = 0;
          for (std::size_t i = 0; i < seen.size(); ++i) {
            const auto& s = seen[i];
            const bool same = i > 0 && s.conversions == seen[i - 1].conversions &&
                              s.rejections == seen[i - 1].rejections &&
                              s.skipped_unchanged == seen[i - 1].skipped_unchanged &&
                              s.rescans == seen[i - 1].rescans;
            run = s.pending == 0 ? (same ? run + 1 : 1) : 0;
            if (run >= quiet) {
              result = s;
              return true;
            }
          }
          return false;
        },
        timeout);
    return result;
  }

  // Waits until an lcm-logger started on `log` records: a probe published on ITEST_PROBE until
  // the file has bytes (the logger subscribes a moment after it starts).
  bool wait_logger_recording(const fs::path& log, Clock::duration timeout = 5s) {
    rdtf::request_t probe;
    probe.utime = 0;
    probe.model_id = "";
    probe.requester = "probe";
    return wait_until(
        [&] {
          subscriber.publish("ITEST_PROBE", probe);
          std::error_code ec;
          return fs::exists(log) && fs::file_size(log, ec) > 0;
        },
        timeout);
  }

  void request(const std::string& model_id = "", const std::string& requester = "itest") {
    rdtf::request_t request;
    request.utime = 0;
    request.model_id = model_id;
    request.requester = requester;
    subscriber.publish(prefix + "/REQUEST", request);
  }
};

}  // namespace rdtf::itest
