// rdtf-view: every model on the bus in a browser, live (docs/view.md).
//
//   rdtf-view [--port 8765] [--bind 127.0.0.1] [--lcm-url URL]
//
// One thread: a Boost.Asio io_context runs the HTTP/WebSocket server (server.h), waits on LCM's
// socket and ticks the client library after each batch of datagrams (so blob requests leave at
// once) and every 20 ms (it asks for at least every 100 ms); the timer also flushes the newest joint and link states to the pages (at most 50 messages a second per model
// however fast rdtfd publishes).
#include <CLI/CLI.hpp>

#include <chrono>
#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <string>

#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <lcm/lcm-cpp.hpp>

#include "../cli_numbers.h"
#include "lcm_ready.h"
#include "model_hub.h"
#include "rdtf/client.h"
#include "server.h"
#include "rdtf/version.h"

#ifndef RDTF_VIEW_WEB_DIR
#define RDTF_VIEW_WEB_DIR ""
#endif

namespace {

namespace asio = boost::asio;
using namespace std::chrono_literals;

// LCM's socket in the io_context: when it is readable, dispatch what is there.
class LcmPump {
 public:
  // `after_batch` runs after each batch dispatched.
  LcmPump(asio::io_context& io, lcm::LCM& lcm, std::function<void()> after_batch)
      : lcm_(lcm), descriptor_(io, lcm.getFileno()), after_batch_(std::move(after_batch)) {
    wait();
  }
  ~LcmPump() {
    descriptor_.cancel();
    descriptor_.release();  // LCM owns the descriptor
  }
  bool failed() const { return failed_; }

 private:
  void wait() {
    descriptor_.async_wait(asio::posix::stream_descriptor::wait_read, [this](boost::system::error_code ec) {
      if (ec) return;
      // Readable: handle what is queued without blocking (at most a bounded batch per turn, so
      // HTTP and WebSocket traffic is served between batches).
      for (int i = 0; i < 256; ++i) {
        const int handled = lcm_.handleTimeout(0);
        if (handled < 0) {
          failed_ = true;
          return;
        }
        if (handled == 0) break;
      }
      after_batch_();
      wait();
    });
  }
  lcm::LCM& lcm_;
  asio::posix::stream_descriptor descriptor_;
  std::function<void()> after_batch_;
  bool failed_ = false;
};

void release_free_memory() {
#ifdef __GLIBC__
  malloc_trim(0);
#endif
}

// The page rdtf-view serves unless --web-dir says: the installed one beside the program
// (<bindir>/../share/rdtf/view, clients/view/CMakeLists.txt) when there is one, else the source
// tree's web/ of the build it came from.
std::string default_web_dir() {
  std::error_code ec;
  const auto program = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) {
    const auto installed = (program.parent_path() / RDTF_VIEW_INSTALLED_WEB_DIR).lexically_normal();
    if (std::filesystem::is_regular_file(installed / "index.html", ec)) return installed.string();
  }
  return RDTF_VIEW_WEB_DIR;
}

}  // namespace

static int run_view(int argc, char** argv) {
  CLI::App app{"rdtf-view: every rdtf model on the bus in a browser, live"};
  app.set_version_flag("--version", rdtf::version_line("rdtf-view"));
  std::string bind = "127.0.0.1";
  int port = 8765;
  std::string url;
  std::string prefix = "RDTF";
  std::string web_dir = default_web_dir();
  rdtf::view::GainRule gains;
  double kp = -1, kd = -1;
  app.add_option("--port", port, "TCP port of the page (0: any free port)")->capture_default_str()->check(CLI::Range(0, 65535));
  app.add_option("--bind", bind, "Address to listen on (loopback unless you mean others to command joints)")
      ->capture_default_str();
  app.add_option("--lcm-url", url, "LCM URL (default: LCM_DEFAULT_URL, else LCM's default)");
  app.add_option("--channel-prefix", prefix, "rdtfd's channel prefix")->capture_default_str();
  app.add_option("--web-dir", web_dir, "Folder of the page (index.html, *.js, node_modules/three)")->capture_default_str();
  app.add_option("--gain-hz", gains.frequency_hz,
                 "Natural frequency of each joint's slider response: kp = M w^2, kd = 2 M w for the inertia M it moves")
      ->capture_default_str()->check(CLI::Range(0.01, 100.0));
  app.add_option("--kp", kp, "The same position gain for every joint instead, N m/rad (N/m)")
      ->check(rdtf::cli_numbers::kNonNegative);
  app.add_option("--kd", kd, "The same velocity gain for every joint instead, N m s/rad (N s/m)")
      ->check(rdtf::cli_numbers::kNonNegative);
  CLI11_PARSE(app, argc, argv);
  if (kp >= 0) gains.kp = kp;
  if (kd >= 0) gains.kd = kd;

  boost::system::error_code ec;
  const auto address = asio::ip::make_address(bind, ec);
  if (ec) {
    std::cerr << "rdtf-view: --bind " << bind << ": not an IP address\n";
    return 2;
  }
  if (!std::filesystem::is_regular_file(std::filesystem::path(web_dir) / "index.html") ||
      !std::filesystem::is_regular_file(std::filesystem::path(web_dir) / "node_modules/three/build/three.module.js")) {
    std::cerr << "rdtf-view: --web-dir '" << web_dir
              << "' lacks index.html or node_modules/three (run scripts/install-deps.sh)\n";
    return 2;
  }
  if (!address.is_loopback()) {
    std::cerr << "rdtf-view: WARNING: listening on " << bind
              << ", not loopback: anyone who reaches this address can see every model and command its joints "
                 "in the live simulation\n";
  }

  lcm::LCM lcm(url);
  if (const std::string problem = rdtf::lcm_safe::lcm_receive_problem(lcm, url); !problem.empty()) {
    std::cerr << "rdtf-view: " << problem << "\n";
    return 1;
  }

  asio::io_context io;
  std::unique_ptr<rdtf::view::Server> server;
  rdtf::view::ModelHub hub(
      gains, [&](std::shared_ptr<const std::string> json) { if (server) server->broadcast(json); },
      [&](const std::string& model_id, rdtf::joint_command_t& command) {
        lcm.publish(prefix + "/" + model_id + "/JOINT_COMMAND", &command);
      },
      [&](const std::string& model_id, std::shared_ptr<const std::string> json) {
        if (server) server->broadcast_state(model_id, json);
      });
  try {
    rdtf::view::ServerOptions options;
    options.web_dir = web_dir;
    options.loopback_only = address.is_loopback();
    server = std::make_unique<rdtf::view::Server>(io, asio::ip::tcp::endpoint(address, static_cast<std::uint16_t>(port)),
                                                  options, hub);
  } catch (const std::exception& e) {
    std::cerr << "rdtf-view: cannot listen on " << bind << ":" << port << ": " << e.what() << "\n";
    return 1;
  }

  rdtf::client::Options client_options;
  client_options.prefix = prefix;
  client_options.blobs = rdtf::client::Blobs::kAll;
  // The page draws the glTF: its buffers and images, never the URDF's meshes (a 1M-triangle
  // link's STL is 50 MB, new with every revision).
  client_options.blob_roles = {"rdtf", "buffer", "image"};
  // Blobs are held while a revision the hub keeps (the live one and the one before) uses them,
  // no longer: memory follows those two revisions, not how many came before (docs/view.md).
  client_options.limits.max_store_bytes = 0;
  client_options.requester = "rdtf-view";
  rdtf::client::Callbacks callbacks;
  bool trim_due = false;
  callbacks.on_revision = [&](std::shared_ptr<const rdtf::client::Snapshot> s) {
    hub.on_revision(std::move(s));
    trim_due = true;
  };
  callbacks.on_error = [&](const rdtf::model_error_t& e) { hub.on_error(e); };
  callbacks.on_saving = [&](const rdtf::model_saving_t& saving) { hub.on_saving(saving); };
  callbacks.on_removed = [&](const rdtf::model_removed_t& r) {
    hub.on_removed(r);
    trim_due = true;
  };
  callbacks.on_joint_state = [&](const rdtf::client::Snapshot& s, const rdtf::joint_state_t& q) { hub.on_joint_state(s, q); };
  callbacks.on_link_state = [&](const rdtf::client::Snapshot& s, const rdtf::link_state_t& x) { hub.on_link_state(s, x); };
  callbacks.on_problem = [](const std::string& model_id, const std::string& problem) {
    std::cerr << "rdtf-view: " << model_id << ": " << problem << "\n";
  };
  rdtf::client::Client client(lcm, client_options, callbacks);

  const std::string host = address.is_v6() ? "[" + bind + "]" : bind;
  std::cout << "rdtf-view: http://" << host << ":" << server->port() << "/" << std::endl;

  // The client is ticked after every batch, not only by the timer: a MANIFEST's blob requests
  // leave at once instead of up to a timer period later (a tick that has nothing due is cheap).
  LcmPump pump(io, lcm, [&] {
    client.tick();  // also evicts the blobs of the revision the hub just let go
    if (trim_due) {
      trim_due = false;
      // glibc keeps freed memory for reuse, and a big blob freed in the middle of the heap is
      // never handed back: return it to the system once a revision's blobs are gone.
      release_free_memory();
    }
  });
  asio::steady_timer timer(io);
  std::function<void()> tick = [&] {
    timer.expires_after(20ms);
    timer.async_wait([&](boost::system::error_code e) {
      if (e) return;
      if (pump.failed()) {
        std::cerr << "rdtf-view: LCM failed\n";
        io.stop();
        return;
      }
      client.tick();
      hub.on_models_seen(client.models_seen());
      hub.flush_states();
      tick();
    });
  };
  tick();
  asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](boost::system::error_code, int) { io.stop(); });
  io.run();
  server.reset();
  return pump.failed() ? 1 : 0;
}

// What asio throws where the system runs out (signal_set's pipe, a descriptor for LCM's socket)
// ends rdtf-view with the reason, never std::terminate's abort.
int main(int argc, char** argv) {
  try {
    return run_view(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "rdtf-view: " << e.what() << "\n";
    return 1;
  }
}
