// libFuzzer target `bus`: one datagram's payload from a hostile LCM bus, fed to every handler that
// rdtfd and the rdtf clients register, decode and dispatch: byte 0 picks the handler, the rest is
// the payload (what liblcm hands a subscriber after the LCM header).
//
//   0  rdtfd <prefix>/REQUEST:        BusInput -> RequestThrottle, the requester escaped for the log
//   1  rdtfd <model>/JOINT_COMMAND:   BusInput -> joint_commands_of -> Simulation::set_command, one step
//   2  rdtf-pd-controller JOINT_STATE: decode -> PdController::on_state, the command it would send
//   3  rdtf-pd-controller DESCRIPTION and ERROR
//   4  rdtf-echo (any channel):       the schema check, then message_to_json
//   5  rdtfd <prefix>/BLOB_REQUEST:   BusInput -> BlobServer over three files (one empty, one of
//                                     several chunks), pumped and sent until nothing is left
//
// Besides a crash, leak, sanitizer report or hang, a target stops on a broken contract: a log line
// or ERROR text with a byte outside printable ASCII, a blob chunk or answer over the message size
// or failing the schema check, a chunk whose bytes are not the file's, a published joint state with a non-finite
// value or an effort beyond its bound, a command the controller would send that does not survive
// the schema check, or a message the schema check accepts that lcm-gen's decoder then refuses.
#include <cmath>
#include <cstdint>
#include <string>

#include <rdtf/description_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/model_error_t.hpp>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>

#include "blob_server.h"
#include "conversion.h"
#include "bus_input.h"
#include "message_json.h"
#include "pd_controller.h"
#include "rdtf/convert.h"
#include "rdtf/dynamics.h"
#include "safe_decode.h"
#include "simulation_host.h"

namespace {

void require(bool ok, const char* what) {
  if (ok) return;
  std::fprintf(stderr, "rdtf fuzz: %s\n", what);
  std::abort();
}

bool printable_ascii(const std::string& text) {
  for (unsigned char c : text) {
    if (c < 0x20 || c >= 0x7f) return false;
  }
  return true;
}

// arm3 (tests/data/blender), converted once: the live model commands go to.
const rdtf::Robot& arm3() {
  static const rdtf::Robot robot = [] {
    rdtf::Diagnostics diag;
    auto conversion = rdtf::convert_file(std::string(RDTF_FUZZ_DATA_DIR) + "/blender/arm3.gltf", {}, diag);
    require(conversion.has_value(), "arm3 does not convert");
    return conversion->robot;
  }();
  return robot;
}

void check_logged(const std::string& line) { require(printable_ascii(line), "a log line with unescaped bytes"); }

void daemon_request(const std::uint8_t* data, std::size_t size) {
  static rdtf::daemon::RequestThrottle throttle(std::chrono::seconds(1));
  rdtf::daemon::BusInput input({[&](const rdtf::request_t& request) {
                                  throttle.admit(request.model_id, std::chrono::steady_clock::now());
                                  check_logged(rdtf::lcm_safe::printable(request.requester, 80));
                                },
                                nullptr, check_logged, nullptr});
  input.request_datagram("RDTF/REQUEST", data, size);
}

void daemon_command(const std::uint8_t* data, std::size_t size) {
  rdtf::init_ode();
  rdtf::Diagnostics diag;
  // As the daemon runs it: under the URDF names, glTF names accepted where unambiguous.
  rdtf::daemon::LiveNames names;
  auto simulation = rdtf::Simulation::create(rdtf::daemon::with_urdf_names(arm3(), names), rdtf::SimulationOptions{}, {}, diag);
  require(simulation != nullptr, "arm3 does not simulate");
  rdtf::daemon::BusInput input(
      {nullptr,
       [&](const rdtf::joint_command_t& command) {
         std::vector<rdtf::JointCommand> commands;
         const std::string why = rdtf::daemon::joint_commands_of(command, names, *simulation, commands);
         if (!why.empty()) {
           require(printable_ascii(why), "a rejection with unescaped bytes");
           return std::string();
         }
         for (const auto& c : commands) require(simulation->set_command(c), "a checked command was refused");
         return std::string();
       },
       check_logged, nullptr});
  // The channel names the model the payload claims, as a subscriber's pattern would match it.
  std::string why;
  const auto claimed = rdtf::lcm_safe::decode<rdtf::joint_command_t>(data, size, why);
  input.command_datagram("RDTF/" + (claimed ? claimed->model_id : std::string("arm3.gltf")) + "/JOINT_COMMAND", data,
                         size);
  for (int k = 0; k < 3; ++k) simulation->step();
  for (const auto& state : simulation->joint_states()) {
    require((std::isfinite(state.position) && std::isfinite(state.velocity) && std::isfinite(state.effort)) ||
                !simulation->health().finite,
            "a non-finite joint state from a simulation that did not report failure");
    require(!(std::abs(state.effort) > rdtf::kDefaultEffortLimit), "an effort beyond the default bound (arm3 has no effort limits)");
  }
}

void controller_state(const std::uint8_t* data, std::size_t size) {
  std::string why;
  auto state = rdtf::lcm_safe::decode<rdtf::joint_state_t>(data, size, why);
  if (!state) return;
  rdtf::controller::PdOptions options;
  options.model_id = state->model_id;
  options.targets = {{"shoulder", 0.5}};
  rdtf::controller::PdController controller(options);
  controller.on_description(state->revision);
  if (auto command = controller.on_state(*state)) {
    std::vector<std::uint8_t> bytes(static_cast<std::size_t>(command->getEncodedSize()));
    command->encode(bytes.data(), 0, static_cast<int>(bytes.size()));
    require(rdtf::lcm_safe::check_known(bytes.data(), bytes.size()).empty(), "the controller's command fails the schema");
  }
}

void controller_other(const std::uint8_t* data, std::size_t size) {
  std::string why;
  if (auto d = rdtf::lcm_safe::decode<rdtf::description_t>(data, size, why)) {
    rdtf::controller::PdController controller({});
    controller.on_description(d->revision);
  }
  if (auto error = rdtf::lcm_safe::decode<rdtf::model_error_t>(data, size, why)) {
    for (const auto& d : error->diagnostics) check_logged(rdtf::lcm_safe::printable(d.message));
  }
}

void echo(const std::uint8_t* data, std::size_t size) {
  const auto type = rdtf::lcm_safe::type_of(data, size);
  if (type.empty() || !rdtf::lcm_safe::check_known(data, size).empty()) return;
  const auto json = rdtf::clients::message_to_json(data, static_cast<std::uint32_t>(size));
  require(json.has_value(), "a message that passed the schema check does not decode");
  (void)json->dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

// The files the blob server serves (written once into a temporary folder): a model "m" whose
// output holds an empty file, 3,000 bytes (several chunks of 1,024-byte messages) and 10 bytes.
struct BlobFiles {
  std::filesystem::path folder;
  std::vector<rdtf::daemon::OutputFile> files;
  std::map<std::string, std::string> bytes_of;  // sha256 -> bytes
  BlobFiles() = default;
  BlobFiles(BlobFiles&& other) noexcept
      : folder(std::move(other.folder)), files(std::move(other.files)), bytes_of(std::move(other.bytes_of)) {
    other.folder.clear();  // The folder goes with the last owner only.
  }
  ~BlobFiles() {
    std::error_code ignored;
    if (!folder.empty()) std::filesystem::remove_all(folder.parent_path(), ignored);
  }
};

const BlobFiles& blob_files() {
  static const BlobFiles files = [] {
    BlobFiles out;
    char pattern[] = "/tmp/rdtf-bus-fuzz-XXXXXX";
    require(::mkdtemp(pattern) != nullptr, "no temporary folder");
    out.folder = std::filesystem::path(pattern) / "m";
    std::filesystem::create_directories(out.folder);
    std::string big(3000, '\0');
    for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<char>(i * 7 + 3);
    for (const auto& [name, bytes] : std::map<std::string, std::string>{{"empty.bin", ""}, {"big.bin", big}, {"small.bin", "0123456789"}}) {
      std::ofstream(out.folder / name, std::ios::binary) << bytes;
      const std::string sha = rdtf::daemon::sha256_hex(bytes);
      out.files.push_back({name, sha, static_cast<std::int64_t>(bytes.size()), "buffer"});
      out.bytes_of[sha] = bytes;
    }
    return out;
  }();
  return files;
}

void daemon_blob_request(const std::uint8_t* data, std::size_t size) {
  const BlobFiles& files = blob_files();
  constexpr std::size_t kMaxMessage = 1024;
  std::set<std::string> heard;  // Blobs that got a chunk or an answer.
  rdtf::daemon::Publisher publisher(
      [&](const std::string& channel, const std::uint8_t* bytes, unsigned int n) {
        require(n <= kMaxMessage, "a blob message over max_chunk_bytes");
        require(rdtf::lcm_safe::check_known(bytes, n).empty(), "a blob message fails the schema check");
        if (channel == "RDTF/BLOB") {
          rdtf::blob_chunk_t chunk;
          require(chunk.decode(bytes, 0, static_cast<int>(n)) == static_cast<int>(n), "a chunk does not decode");
          const auto it = files.bytes_of.find(chunk.sha256);
          require(it != files.bytes_of.end(), "a chunk of a blob nobody serves");
          const std::size_t begin = static_cast<std::size_t>(chunk.index) * static_cast<std::size_t>(chunk.chunk_size);
          heard.insert(chunk.sha256);
          require(begin <= it->second.size() &&
                      it->second.compare(begin, static_cast<std::size_t>(chunk.size),
                                         std::string(chunk.data.begin(), chunk.data.end())) == 0,
                  "a chunk whose bytes are not the file's");
        } else {
          require(channel == "RDTF/BLOB_UNAVAILABLE", "a blob answer on another channel");
          rdtf::blob_unavailable_t answer;
          require(answer.decode(bytes, 0, static_cast<int>(n)) == static_cast<int>(n), "an answer does not decode");
          for (const auto& reason : answer.reason) require(printable_ascii(reason), "a reason with unescaped bytes");
          heard.insert(answer.sha256.begin(), answer.sha256.end());
          for (std::size_t i = 0; i < answer.sha256.size(); ++i) {
            // The files are intact: a blob of theirs is unavailable only for a range beyond its end.
            require(files.bytes_of.count(answer.sha256[i]) == 0 || answer.reason[i].rfind("chunk ", 0) == 0,
                    "an intact file answered unavailable");
          }
        }
        return 0;
      },
      1e12, std::size_t{1} << 30);
  rdtf::daemon::BlobServer server(check_logged);
  server.set_max_message_bytes(kMaxMessage);
  server.set_model("m", files.folder, files.files);
  std::set<std::string> asked;  // Blobs of a request that was taken.
  rdtf::daemon::BusInput input({nullptr, nullptr, check_logged, [&](const rdtf::blob_request_t& request) {
                                  const std::string why =
                                      server.request(request, std::chrono::steady_clock::now(), publisher, "RDTF");
                                  check_logged(why);
                                  if (why.empty()) asked.insert(request.sha256.begin(), request.sha256.end());
                                  return why;
                                }});
  input.blob_request_datagram("RDTF/BLOB_REQUEST", data, size);
  auto now = std::chrono::steady_clock::now();
  for (int turn = 0; turn < 1000 && (server.jobs() > 0 || publisher.queued() > 0); ++turn) {
    server.pump(publisher, "RDTF");
    now += std::chrono::milliseconds(1);
    publisher.drain(now);
  }
  require(server.jobs() == 0 && publisher.queued() == 0, "blob jobs left after 1000 turns");
  require(heard == asked, "a blob asked for got neither a chunk nor an answer (or one not asked for got one)");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return -1;
  const std::uint8_t* payload = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % 6) {
    case 0: daemon_request(payload, n); break;
    case 1: daemon_command(payload, n); break;
    case 2: controller_state(payload, n); break;
    case 3: controller_other(payload, n); break;
    case 4: echo(payload, n); break;
    default: daemon_blob_request(payload, n); break;
  }
  return 0;
}
