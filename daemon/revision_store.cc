#include "revision_store.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>

#include <nlohmann/json.hpp>

#include "../core/gltf/confined_files.h"
#include "json_bytes.h"
#include "rdtf/atomic_file.h"
#include "rdtf/shortage.h"

namespace rdtf::daemon {
namespace {

using Json = nlohmann::json;

constexpr const char* kFormat = "rdtfd-revisions 1";
constexpr std::size_t kMaxStateBytes = std::size_t{64} << 20;
// Revision numbers stay exact in a double (JSON readers, lcm-spy): below 2^53.
constexpr std::int64_t kMaxRevision = std::int64_t{1} << 53;

// Every refusal is one of these, caught at the top of state_from_json with its text.
struct Refused {
  std::string why;
};

const Json& field(const Json& object, const char* key, Json::value_t type, const std::string& where) {
  if (!object.is_object() || !object.contains(key)) throw Refused{where + ": no '" + key + "'"};
  const Json& value = object[key];
  const bool number = type == Json::value_t::number_float;
  const bool integer = type == Json::value_t::number_integer;
  const bool ok = number    ? value.is_number()
                  : integer ? (value.is_number_integer())
                            : value.type() == type;
  if (!ok) throw Refused{where + ": '" + key + "' has the wrong type"};
  return value;
}

std::string text(const Json& object, const char* key, const std::string& where) {
  return field(object, key, Json::value_t::string, where).get<std::string>();
}

double finite(const Json& value, const std::string& where) {
  if (!value.is_number()) throw Refused{where + " is not a number"};
  const double d = value.get<double>();
  if (!std::isfinite(d)) throw Refused{where + " is not finite"};
  return d;
}

template <std::size_t N>
void numbers(const Json& object, const char* key, double (&out)[N], const std::string& where) {
  const Json& array = field(object, key, Json::value_t::array, where);
  if (array.size() != N) throw Refused{where + ": '" + key + "' needs " + std::to_string(N) + " numbers"};
  for (std::size_t i = 0; i < N; ++i) out[i] = finite(array[i], where + "/" + key);
}

std::int64_t revision_number(const Json& object, const char* key, std::int64_t low, const std::string& where) {
  const Json& value = field(object, key, Json::value_t::number_integer, where);
  const auto n = value.is_number_unsigned() && value.get<std::uint64_t>() > static_cast<std::uint64_t>(kMaxRevision)
                     ? kMaxRevision + 1
                     : value.get<std::int64_t>();
  if (n < low || n > kMaxRevision) throw Refused{where + ": '" + key + "' " + std::to_string(n) + " is out of range"};
  return n;
}

Json to_json(const LinkFacts& l) {
  return {{"name", l.name}, {"urdf_name", l.urdf_name}, {"parent_joint", l.parent_joint}, {"mass", l.mass},
          {"volume", l.volume}, {"center_of_mass", l.center_of_mass}, {"inertia", l.inertia},
          {"authored", l.authored}, {"geometry", l.geometry}};
}

Json to_json(const JointFacts& j) {
  return {{"name", j.name}, {"urdf_name", j.urdf_name}, {"type", j.type}, {"parent", j.parent},
          {"child", j.child}, {"origin", j.origin}, {"axis", j.axis}, {"has_limits", j.has_limits},
          {"has_range", j.has_range}, {"limits", j.limits}, {"dynamics", j.dynamics}};
}

LinkFacts link_from(const Json& j, const std::string& where) {
  LinkFacts l;
  l.name = text(j, "name", where);
  l.urdf_name = text(j, "urdf_name", where);
  l.parent_joint = text(j, "parent_joint", where);
  l.mass = finite(field(j, "mass", Json::value_t::number_float, where), where + "/mass");
  l.volume = finite(field(j, "volume", Json::value_t::number_float, where), where + "/volume");
  numbers(j, "center_of_mass", l.center_of_mass, where);
  numbers(j, "inertia", l.inertia, where);
  l.authored = field(j, "authored", Json::value_t::boolean, where).get<bool>();
  l.geometry = text(j, "geometry", where);
  return l;
}

JointFacts joint_from(const Json& j, const std::string& where) {
  JointFacts f;
  f.name = text(j, "name", where);
  f.urdf_name = text(j, "urdf_name", where);
  f.type = text(j, "type", where);
  f.parent = text(j, "parent", where);
  f.child = text(j, "child", where);
  numbers(j, "origin", f.origin, where);
  numbers(j, "axis", f.axis, where);
  f.has_limits = field(j, "has_limits", Json::value_t::boolean, where).get<bool>();
  // Files written before limits could come without a range have no has_range: theirs had one.
  f.has_range = j.contains("has_range") ? field(j, "has_range", Json::value_t::boolean, where).get<bool>() : f.has_limits;
  numbers(j, "limits", f.limits, where);
  numbers(j, "dynamics", f.dynamics, where);
  return f;
}

std::string hex_of_id(const std::string& model_id) { return sha256_hex(model_id).substr(0, 32); }

}  // namespace

Json facts_to_json(const RobotFacts& facts) {
  Json links = Json::array();
  for (const LinkFacts& l : facts.links) links.push_back(to_json(l));
  Json joints = Json::array();
  for (const JointFacts& f : facts.joints) joints.push_back(to_json(f));
  return {{"links", links}, {"joints", joints}};
}

std::optional<RobotFacts> facts_from_json(const Json& json, std::string& why) {
  try {
    RobotFacts facts;
    const Json& links = field(json, "links", Json::value_t::array, "");
    for (std::size_t i = 0; i < links.size(); ++i) facts.links.push_back(link_from(links[i], "/links/" + std::to_string(i)));
    const Json& joints = field(json, "joints", Json::value_t::array, "");
    for (std::size_t i = 0; i < joints.size(); ++i) {
      facts.joints.push_back(joint_from(joints[i], "/joints/" + std::to_string(i)));
    }
    return facts;
  } catch (const Refused& refused) {
    why = refused.why;
  } catch (const std::exception& error) {
    why = error.what();
  }
  return std::nullopt;
}

std::string result_digest(const ConvertedModel& m) {
  const std::string flags = std::string(m.written ? "w" : "-") + (m.validation ? "v" : "-") +
                            (m.validation && m.validation->passed ? "p" : "-");
  // Each part with its length first, as the content hash does, so that no two results collide by
  // moving bytes from one part to the next.
  std::string all;
  for (const std::string& part : {flags, m.output_path, m.rdtf_json, m.urdf_path, m.urdf}) {
    all += std::to_string(part.size()) + ":" + part;
  }
  return sha256_hex(all);
}

std::string state_to_json(const ModelState& state) {
  Json j = {{"format", kFormat},
            {"model_id", state.model_id},
            {"source", bytes_to_json(state.source)},
            {"numbered", state.numbered},
            {"reserved", std::max(state.reserved, state.numbered)}};
  if (state.live) {
    Json links = Json::array();
    for (const LinkFacts& l : state.live->facts.links) links.push_back(to_json(l));
    Json joints = Json::array();
    for (const JointFacts& f : state.live->facts.joints) joints.push_back(to_json(f));
    j["live"] = {{"revision", state.live->revision}, {"content_hash", state.live->content_hash},
                 {"result", state.live->result_digest}, {"links", links}, {"joints", joints}};
  } else {
    j["live"] = nullptr;
  }
  // The source path is written byte for byte (json_bytes.h). Other text with invalid UTF-8 (a
  // glTF name is checked) is written replaced, not refused: a replaced name only makes a delta say
  // more.
  return j.dump(1, ' ', false, Json::error_handler_t::replace) + "\n";
}

std::optional<ModelState> state_from_json(std::string_view text_in, std::string& why) {
  try {
    const Json j = Json::parse(text_in.begin(), text_in.end());
    if (!j.is_object()) throw Refused{"not a JSON object"};
    if (text(j, "format", "/") != kFormat) throw Refused{"/format is not '" + std::string(kFormat) + "'"};
    ModelState state;
    state.model_id = text(j, "model_id", "/");
    if (!j.contains("source")) throw Refused{"/: no 'source'"};
    const auto source = bytes_from_json(j["source"]);
    if (!source) throw Refused{"/: 'source' is neither text nor {\"hex\": ...}"};
    state.source = *source;
    state.numbered = revision_number(j, "numbered", 0, "/");
    state.reserved = j.contains("reserved") ? revision_number(j, "reserved", 0, "/") : state.numbered;
    if (state.reserved < state.numbered) {
      throw Refused{"/reserved " + std::to_string(state.reserved) + " is below /numbered " + std::to_string(state.numbered)};
    }
    if (!j.contains("live")) throw Refused{"/: no 'live'"};
    const Json& live = j["live"];
    if (!live.is_null()) {
      StoredRevision r;
      r.revision = revision_number(live, "revision", 1, "/live");
      if (r.revision > state.numbered) {
        throw Refused{"/live/revision " + std::to_string(r.revision) + " is above /numbered " +
                      std::to_string(state.numbered)};
      }
      r.content_hash = text(live, "content_hash", "/live");
      r.result_digest = text(live, "result", "/live");
      const Json& links = field(live, "links", Json::value_t::array, "/live");
      for (std::size_t i = 0; i < links.size(); ++i) {
        r.facts.links.push_back(link_from(links[i], "/live/links/" + std::to_string(i)));
      }
      const Json& joints = field(live, "joints", Json::value_t::array, "/live");
      for (std::size_t i = 0; i < joints.size(); ++i) {
        r.facts.joints.push_back(joint_from(joints[i], "/live/joints/" + std::to_string(i)));
      }
      state.live = std::move(r);
    }
    return state;
  } catch (const Refused& refused) {
    why = refused.why;
  } catch (const Json::parse_error& error) {
    // Where, not what: the parser's message would quote the file's bytes into the log.
    why = "not valid JSON (at byte " + std::to_string(error.byte) + ")";
  } catch (const std::exception& error) {
    why = std::string("not valid JSON: ") + error.what();
  }
  return std::nullopt;
}

std::int64_t revision_floor_now() {
  const auto micros = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::system_clock::now().time_since_epoch())
                          .count();
  return std::clamp<std::int64_t>(micros, 1, kMaxRevision / 2);
}

std::filesystem::path RevisionStore::folder_for(const std::filesystem::path& output_root) {
  return output_root / ".rdtfd-state";
}

std::filesystem::path RevisionStore::file_for(const std::filesystem::path& output_root, const std::string& model_id) {
  // Named by a hash: a model id may hold '/' and any length, and no content-addressed name (which
  // the start-up cleaning removes when unreferenced) looks like "m-<32 hex>.json".
  return folder_for(output_root) / ("m-" + hex_of_id(model_id) + ".json");
}

RevisionStore::LoadResult RevisionStore::load(const std::filesystem::path& output_root, const std::string& model_id,
                                              ModelState& state, std::string& why) {
  const auto path = file_for(output_root, model_id);
  // No symlink followed, no FIFO or device read: only a regular file of ours.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    const int error = errno;
    if (error == ENOENT) return LoadResult::kAbsent;
    why = path.string() + ": cannot open: " + std::strerror(error);
    return is_shortage(error) ? LoadResult::kUnavailable : LoadResult::kRefused;
  }
  struct stat info {};
  std::string bytes;
  bool ok = ::fstat(fd, &info) == 0;
  bool for_now = false;
  if (!ok) {
    const int error = errno;
    for_now = is_shortage(error);
    why = path.string() + ": cannot stat: " + std::strerror(error);
  } else if (!S_ISREG(info.st_mode)) {
    ok = false;
    why = path.string() + ": not a regular file";
  } else if (static_cast<std::uint64_t>(info.st_size) > kMaxStateBytes) {
    ok = false;
    why = path.string() + ": " + std::to_string(info.st_size) + " bytes, over the limit of " +
          std::to_string(kMaxStateBytes);
  } else {
    bytes.resize(static_cast<std::size_t>(info.st_size));
    std::size_t done = 0;
    while (done < bytes.size()) {
      const auto n = ::read(fd, bytes.data() + done, bytes.size() - done);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) for_now = is_shortage(errno);
      if (n <= 0) break;
      done += static_cast<std::size_t>(n);
    }
    if (done != bytes.size()) {
      ok = false;
      why = path.string() + ": read " + std::to_string(done) + " of " + std::to_string(bytes.size()) + " bytes";
    }
  }
  ::close(fd);
  if (!ok) return for_now ? LoadResult::kUnavailable : LoadResult::kRefused;
  std::string parse_why;
  auto parsed = state_from_json(bytes, parse_why);
  if (!parsed) {
    why = path.string() + ": " + parse_why;
    return LoadResult::kRefused;
  }
  if (parsed->model_id != model_id) {
    why = path.string() + ": is the state of model '" + parsed->model_id + "', not of '" + model_id + "'";
    return LoadResult::kRefused;
  }
  state = std::move(*parsed);
  return LoadResult::kLoaded;
}

bool RevisionStore::number_from_reserves(const std::filesystem::path& output_root, int& raised, std::string& why) {
  raised = 0;
  const auto folder = folder_for(output_root);
  std::error_code error;
  if (!std::filesystem::is_directory(folder, error)) return true;  // Nothing numbered yet.
  for (std::filesystem::directory_iterator it(folder, error), end; !error && it != end; it.increment(error)) {
    const std::string name = it->path().filename().string();
    std::error_code type_error;
    if (name.rfind("m-", 0) != 0 || it->path().extension() != ".json" ||
        !std::filesystem::is_regular_file(it->symlink_status(type_error))) {
      continue;
    }
    std::vector<std::uint8_t> bytes;
    std::string read_why;
    if (!internal::read_regular_file(it->path(), kMaxStateBytes, bytes, read_why)) continue;
    auto state = state_from_json(std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()), read_why);
    if (!state || file_for(output_root, state->model_id) != it->path() || state->numbered >= state->reserved) continue;
    state->numbered = state->reserved;
    if (!save(output_root, *state, /*durable=*/false, why)) return false;
    ++raised;
  }
  if (error) {
    why = "cannot list " + folder.string() + ": " + error.message();
    return false;
  }
  const int fd = ::open(folder.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  const bool synced = fd >= 0 && ::syncfs(fd) == 0;
  if (!synced) why = "cannot sync " + folder.string() + ": " + std::strerror(errno);
  if (fd >= 0) ::close(fd);
  return synced;
}

bool RevisionStore::save(const std::filesystem::path& output_root, const ModelState& state, bool durable,
                         std::string& why) {
  const auto folder = folder_for(output_root);
  std::error_code ec;
  std::filesystem::create_directories(folder, ec);
  if (ec) {
    why = "cannot make " + folder.string() + ": " + ec.message();
    return false;
  }
  const auto file = file_for(output_root, state.model_id);
  const std::string text = state_to_json(state);
  return write_file_atomically(file, text, why, durable ? Durability::kDurable : Durability::kAtomic);
}

}  // namespace rdtf::daemon
