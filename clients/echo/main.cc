// rdtf-echo: prints every rdtf LCM message as one JSON line:
//   {"channel": "...", "recv_utime": ..., "message": {"type": "rdtf.description_t", ...}}
// Messages that are not rdtf types are printed with "type": null and their size.
// At start it sends a request_t (rdtf_client), so a late joiner sees every live model at once;
// with --snapshots it also prints one line per complete revision the client assembled:
//   {"channel": "RDTF/arm3.gltf", "snapshot": {"model_id", "revision", "content_hash", ...}}
#include <CLI/CLI.hpp>

#include <csignal>
#include <iostream>

#include <lcm/lcm-cpp.hpp>

#include "message_json.h"
#include "rdtf/client.h"
#include "lcm_ready.h"
#include "safe_decode.h"
#include "rdtf/version.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rdtf-echo: prints every rdtf LCM message as one JSON line"};
  app.set_version_flag("--version", rdtf::version_line("rdtf-echo"));
  std::string url;
  std::string channels = "RDTF/.*";
  bool omit_json = false;
  std::int64_t count = 0;
  std::string prefix = "RDTF";
  bool no_request = false;
  bool snapshots = false;
  app.add_option("--lcm-url", url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("-c,--channels", channels, "Regular expression of channels to print")->capture_default_str();
  app.add_flag("--omit-documents", omit_json, "Leave out rdtf_json, urdf and chunk data (long)");
  app.add_option("-n,--count", count, "Exit after this many messages (0: never)");
  app.add_option("--channel-prefix", prefix, "rdtfd's channel prefix (for the request and --snapshots)")
      ->capture_default_str();
  app.add_flag("--no-request", no_request, "Do not send a request_t at start (wait for republications)");
  app.add_flag("--snapshots", snapshots, "Also print each complete revision (every part checked) as one line");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(url);
  if (const std::string problem = rdtf::lcm_safe::lcm_receive_problem(lcm, url); !problem.empty()) {
    std::cerr << "rdtf-echo: " << problem << "\n";
    return 1;
  }
  std::int64_t printed = 0;
  struct Handler {
    bool omit_json;
    std::int64_t* printed;
    void handle(const lcm::ReceiveBuffer* buffer, const std::string& channel) {
      nlohmann::ordered_json line = {{"channel", channel}, {"recv_utime", buffer->recv_utime}};
      // An rdtf type is decoded only when it passes the schema check (lcmtypes/safe_decode.h);
      // one that does not is printed as dropped, with the reason.
      const std::string_view type = rdtf::lcm_safe::type_of(buffer->data, buffer->data_size);
      const std::string invalid = type.empty() ? std::string() : rdtf::lcm_safe::check_known(buffer->data, buffer->data_size);
      if (!invalid.empty()) {
        line["message"] = {{"type", "rdtf." + std::string(type)}, {"size", buffer->data_size}, {"dropped", invalid}};
      } else if (auto message = rdtf::clients::message_to_json(buffer->data, buffer->data_size)) {
        if (omit_json) {
          for (const char* key : {"rdtf_json", "urdf", "data"}) {
            if (message->contains(key)) (*message)[key] = "(omitted)";
          }
        }
        line["message"] = std::move(*message);
      } else {
        line["message"] = {{"type", nullptr}, {"size", buffer->data_size}};
      }
      std::cout << line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << std::endl;
      ++*printed;
    }
  } handler{omit_json, &printed};
  lcm.subscribe(channels, &Handler::handle, &handler);
  // The client asks for every live model at start (and again until one answers) and, with
  // --snapshots, reassembles them; the raw lines above already show every drop.
  std::unique_ptr<rdtf::client::Client> client;
  {
    rdtf::client::Options options;
    options.prefix = prefix;
    options.states = false;
    options.send_requests = !no_request;
    rdtf::client::Callbacks callbacks;
    callbacks.on_drop = [](const std::string&, const std::string&) {};
    if (snapshots) {
      callbacks.on_revision = [&](std::shared_ptr<const rdtf::client::Snapshot> s) {
        nlohmann::ordered_json snapshot = {
            {"model_id", s->model_id()},
            {"revision", s->revision()},
            {"content_hash", s->content_hash()},
            {"num_links", s->inertia.num_links},
            {"total_mass", s->inertia.total_mass},
            {"rdtf_json_size", s->description.rdtf_json.size()},
            {"urdf_size", s->description.urdf.size()},
            {"validated", s->validation.has_value()},
            {"files", s->manifest.size()}};
        nlohmann::ordered_json line = {{"channel", prefix + "/" + s->model_id()}, {"snapshot", snapshot}};
        std::cout << line.dump(-1, ' ', false, nlohmann::ordered_json::error_handler_t::replace) << std::endl;
        ++printed;
      };
    }
    client = std::make_unique<rdtf::client::Client>(lcm, options, callbacks);
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  while (!g_stop && (count == 0 || printed < count)) {
    lcm.handleTimeout(50);
    client->tick();
    // Its reader gone (SIGPIPE ignored, as under systemd) or its disk full: lines are lost, so stop.
    if (!std::cout) {
      std::cerr << "rdtf-echo: could not write to standard output (its reader went away, or the disk is full)\n";
      return 1;
    }
  }
  return 0;
}
