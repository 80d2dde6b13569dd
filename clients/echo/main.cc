// rdtf-echo: prints every rdtf LCM message as one JSON line:
//   {"channel": "...", "recv_utime": ..., "message": {"type": "rdtf.description_t", ...}}
// Messages that are not rdtf types are printed with "type": null and their size.
#include <CLI/CLI.hpp>

#include <csignal>
#include <iostream>

#include <lcm/lcm-cpp.hpp>

#include "message_json.h"
#include "safe_decode.h"

namespace {

volatile std::sig_atomic_t g_stop = 0;

void on_signal(int) { g_stop = 1; }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"rdtf-echo: prints every rdtf LCM message as one JSON line"};
  std::string url;
  std::string channels = "RDTF/.*";
  bool omit_json = false;
  std::int64_t count = 0;
  app.add_option("--lcm-url", url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("-c,--channels", channels, "Regular expression of channels to print")->capture_default_str();
  app.add_flag("--omit-documents", omit_json, "Leave out rdtf_json, urdf and chunk data (long)");
  app.add_option("-n,--count", count, "Exit after this many messages (0: never)");
  CLI11_PARSE(app, argc, argv);

  lcm::LCM lcm(url);
  if (!lcm.good()) {
    std::cerr << "rdtf-echo: cannot open LCM" << (url.empty() ? "" : " at " + url) << "\n";
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
      std::cout << line.dump() << std::endl;
      ++*printed;
    }
  } handler{omit_json, &printed};
  lcm.subscribe(channels, &Handler::handle, &handler);
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);
  while (!g_stop && (count == 0 || printed < count)) lcm.handleTimeout(200);
  return 0;
}
