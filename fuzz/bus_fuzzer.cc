// libFuzzer target `bus`: one datagram's payload from a hostile LCM bus, fed to every handler that
// rdtfd and the rdtf clients register, decode and dispatch: byte 0 picks the handler, the rest is
// the payload (what liblcm hands a subscriber after the LCM header).
//
//   0  rdtfd <prefix>/REQUEST:        BusInput -> RequestThrottle, the requester escaped for the log
//   1  rdtfd <model>/JOINT_COMMAND:   BusInput -> joint_commands_of -> Simulation::set_command, one step
//   2  rdtf-pd-controller JOINT_STATE: decode -> PdController::on_state, the command it would send
//   3  rdtf-pd-controller DESCRIPTION and ERROR
//   4  rdtf-echo (any channel):       the schema check, then message_to_json
//
// Besides a crash, leak, sanitizer report or hang, a target stops on a broken contract: a log line
// or ERROR text with a byte outside printable ASCII, a published joint state with a non-finite
// value or an effort beyond its bound, a command the controller would send that does not survive
// the schema check, or a message the schema check accepts that lcm-gen's decoder then refuses.
#include <cmath>
#include <cstdint>
#include <string>

#include <rdtf/description_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/model_error_t.hpp>

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
                                nullptr, check_logged});
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
       check_logged});
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

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return -1;
  const std::uint8_t* payload = data + 1;
  const std::size_t n = size - 1;
  switch (data[0] % 5) {
    case 0: daemon_request(payload, n); break;
    case 1: daemon_command(payload, n); break;
    case 2: controller_state(payload, n); break;
    case 3: controller_other(payload, n); break;
    default: echo(payload, n); break;
  }
  return 0;
}
