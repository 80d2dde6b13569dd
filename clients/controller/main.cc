// rdtf-pd-controller: holds one model of rdtfd's live simulation at a target pose.
//
// The model comes from the bus (rdtf_client: a request at start, the revision reassembled and
// checked); without it after --wait seconds the controller exits 2 naming the models it saw.
// The loop: every JOINT_STATE of the model's current revision (rdtfd publishes them at
// state_rate_hz) is answered at once by one JOINT_COMMAND for all its joints, stamped with that
// state's revision and content hash (PdController in pd_controller.h). States of any other
// revision are never handed over by the client; after a hot reload the first state of the new
// revision re-stamps the commands. Commands rejected by rdtfd (ERROR, code COMMAND_REJECTED) are
// printed. Runs until SIGINT/SIGTERM or --duration.
//
//   rdtf-pd-controller --model arm3.gltf --target shoulder=0.3 --target elbow=-0.5 --kp 400 --kd 20
//
// docs/controller.md: gains, modes, and how to write your own controller.
#include <CLI/CLI.hpp>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include <rdtf/model_error_t.hpp>

#include "../cli_numbers.h"
#include "pd_controller.h"
#include "rdtf/client.h"
#include "lcm_ready.h"
#include "safe_decode.h"
#include "rdtf/version.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

std::int64_t now_utime() {
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

// "joint=value" into targets; an error message for anything else.
std::string parse_target(const std::string& text, std::map<std::string, double>& targets) {
  const auto equals = text.rfind('=');
  if (equals == std::string::npos || equals == 0) return "expected joint=value, got '" + text + "'";
  try {
    std::size_t used = 0;
    const double value = std::stod(text.substr(equals + 1), &used);
    if (used != text.size() - equals - 1 || !std::isfinite(value)) throw std::invalid_argument(text);
    targets[text.substr(0, equals)] = value;
  } catch (const std::exception&) {
    return "not a number in '" + text + "'";
  }
  return "";
}

class ControllerNode {
 public:
  ControllerNode(lcm::LCM& lcm, std::string prefix, rdtf::controller::PdOptions options)
      : lcm_(lcm), model_id_(options.model_id), controller_(std::move(options)) {
    command_channel_ = prefix + "/" + model_id_ + "/JOINT_COMMAND";
    // rdtf_client: the model's revisions from the bus (a request at start, every part checked)
    // and only the states of the revision it holds; no blobs.
    rdtf::client::Options client_options;
    client_options.prefix = std::move(prefix);
    client_options.model = model_id_;
    client_options.blobs = rdtf::client::Blobs::kNone;
    rdtf::client::Callbacks callbacks;
    callbacks.on_revision = [this](std::shared_ptr<const rdtf::client::Snapshot> s) {
      controller_.on_description(s->revision());
    };
    callbacks.on_joint_state = [this](const rdtf::client::Snapshot&, const rdtf::joint_state_t& state) {
      on_state(state);
    };
    callbacks.on_error = [this](const rdtf::model_error_t& error) { on_error(error); };
    callbacks.on_removed = [this](const rdtf::model_removed_t&) {
      std::cerr << "rdtf-pd-controller: " << model_id_ << " was removed\n";
    };
    client_ = std::make_unique<rdtf::client::Client>(lcm, client_options, callbacks);
  }

  void tick() { client_->tick(); }
  bool has_model() const { return client_->snapshot(model_id_) != nullptr; }
  std::set<std::string> models_seen() const { return client_->models_seen(); }

 private:
  void on_state(const rdtf::joint_state_t& state) {
    const std::int64_t followed = controller_.revision();
    auto command = controller_.on_state(state);
    if (!command) return;
    if (controller_.revision() != followed) report_revision();
    command->utime = now_utime();
    lcm_.publish(command_channel_, &*command);
  }

  void on_error(const rdtf::model_error_t& error) {
    for (const auto& d : error.diagnostics) {
      if (d.code == "COMMAND_REJECTED") {
        std::cerr << "rdtf-pd-controller: command rejected: " << rdtf::lcm_safe::printable(d.message) << "\n";
      }
    }
  }

  void report_revision() const {
    std::cerr << "rdtf-pd-controller: following " << model_id_ << " revision " << controller_.revision()
              << ", targets:";
    for (const auto& [joint, value] : controller_.targets()) std::cerr << " " << joint << "=" << value;
    std::cerr << "\n";
    for (const auto& [joint, value] : controller_.unknown_targets()) {
      std::cerr << "rdtf-pd-controller: revision " << controller_.revision() << " has no joint '" << joint
                << "': target ignored\n";
    }
  }

  lcm::LCM& lcm_;
  std::string model_id_;
  std::string command_channel_;
  rdtf::controller::PdController controller_;
  std::unique_ptr<rdtf::client::Client> client_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rdtf-pd-controller: holds a model of rdtfd's live simulation at a target pose (PD)"};
  app.set_version_flag("--version", rdtf::version_line("rdtf-pd-controller"));
  rdtf::controller::PdOptions options;
  std::string url;
  std::string prefix = "RDTF";
  std::string mode = "position";
  std::vector<std::string> targets;
  double duration = 0;
  double wait = 10;
  app.add_option("--model", options.model_id, "Model id (its channel name, e.g. arm3.gltf)")->required();
  app.add_option("--target", targets,
                 "joint=value in rad or m (repeatable); joints without one hold their first state");
  app.add_option("--kp", options.gains.kp, "Position gain, N m/rad (N/m)")->capture_default_str()
      ->check(rdtf::cli_numbers::kNonNegative);
  app.add_option("--kd", options.gains.kd, "Velocity gain, N m s/rad (N s/m)")->capture_default_str()
      ->check(rdtf::cli_numbers::kNonNegative);
  app.add_option("--mode", mode, "position: rdtfd applies the PD law every step; torque: computed here")
      ->capture_default_str()->check(CLI::IsMember({"position", "torque"}));
  app.add_option("--lcm-url", url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--channel-prefix", prefix, "rdtfd's channel prefix")->capture_default_str();
  app.add_option("--duration", duration, "Stop after this many seconds (0: run until SIGINT/SIGTERM)")
      ->check(rdtf::cli_numbers::kNonNegative);
  app.add_option("--wait", wait, "Seconds to wait for the model on the bus before giving up (exit 2)")
      ->capture_default_str()->check(CLI::Range(0.0, 86400.0));
  CLI11_PARSE(app, argc, argv);
  for (const auto& target : targets) {
    if (const std::string error = parse_target(target, options.targets); !error.empty()) {
      std::cerr << "rdtf-pd-controller: --target: " << error << "\n";
      return 2;
    }
  }
  options.mode = mode == "torque" ? rdtf::controller::Mode::kTorque : rdtf::controller::Mode::kPosition;
  // The default gains are for position mode, where rdtfd applies the law at every physics step. In
  // torque mode the loop closes over LCM one state period late, and kd 10 spun arm3's elbow to 35
  // rad within a second (docs/controller.md, "Position or torque mode").
  if (options.mode == rdtf::controller::Mode::kTorque && app.count("--kp") == 0 && app.count("--kd") == 0) {
    std::cerr << "rdtf-pd-controller: --mode torque with the default gains (kp " << options.gains.kp << ", kd "
              << options.gains.kd << "), which are for position mode: the loop closes over LCM a state period T "
              << "late and is stable only for soft gains (kd T / I < 1 for a joint moving an inertia I; "
                 "docs/controller.md). Give --kp and --kd\n";
  }

  lcm::LCM lcm(url);
  if (const std::string problem = rdtf::lcm_safe::lcm_receive_problem(lcm, url); !problem.empty()) {
    std::cerr << "rdtf-pd-controller: " << problem << "\n";
    return 1;
  }
  ControllerNode node(lcm, prefix, options);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  const auto start = std::chrono::steady_clock::now();
  const auto out_of_time = [&] {
    return duration > 0 && std::chrono::steady_clock::now() - start >= std::chrono::duration<double>(duration);
  };
  const auto wait_until = start + std::chrono::duration<double>(wait);
  while (!g_stop && !out_of_time()) {
    if (lcm.handleTimeout(50) < 0) {
      // The wait that SIGINT or SIGTERM cut short ends the loop; that is no failure.
      if (g_stop || errno == EINTR) continue;
      std::cerr << "rdtf-pd-controller: LCM failed: " << std::strerror(errno) << "\n";
      return 1;
    }
    node.tick();
    if (!node.has_model() && std::chrono::steady_clock::now() >= wait_until) {
      std::string seen;
      for (const auto& id : node.models_seen()) seen += (seen.empty() ? "" : ", ") + id;
      std::cerr << "rdtf-pd-controller: no model '" << options.model_id << "' on the bus within " << wait
                << " s; models seen: " << (seen.empty() ? "none (no rdtfd heard)" : seen) << "\n";
      return 2;
    }
  }
  return 0;
}
