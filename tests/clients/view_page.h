// The browser side of rdtf-view's tests (tests/clients/view_itest.cc): rdtf-view run as a child
// process, and Debian's headless chromium driven by puppeteer-core through
// tools/view-test/page_driver.mjs (JSON lines on its stdin and stdout). Both run inside the
// test case's network namespace (tests/daemon/harness.h): the page talks to rdtf-view on
// 127.0.0.1, rdtf-view and rdtfd to each other over LCM multicast on the namespace's loopback.
#pragma once

#include <poll.h>
#include <signal.h>
#include <spawn.h>

#include "daemon/harness.h"

namespace rdtf::itest {

inline fs::path view_artifacts() {
  const fs::path folder = RDTF_VIEW_ARTIFACTS_DIR;
  fs::create_directories(folder);
  return folder;
}

// rdtf-view on a free port; url() once it printed it.
class ViewProcess {
 public:
  explicit ViewProcess(const fs::path& folder, std::vector<std::string> extra = {})
      : log_(folder / "rdtf-view.log"), process_(args(std::move(extra)), log_) {
    const bool up = wait_until([&] { return testing::read_file(log_).find("rdtf-view: http://") != std::string::npos; }, 10s);
    if (!up) throw std::runtime_error("rdtf-view printed no URL; log:\n" + log());
    const std::string text = log();
    const auto at = text.find("http://");
    url_ = text.substr(at, text.find('\n', at) - at);
  }
  const std::string& url() const { return url_; }
  std::string log() const { return testing::read_file(log_); }
  ChildProcess& process() { return process_; }

 private:
  static std::vector<std::string> args(std::vector<std::string> extra) {
    std::vector<std::string> out = {RDTF_VIEW_PATH};
    if (std::find(extra.begin(), extra.end(), "--port") == extra.end()) out.insert(out.end(), {"--port", "0"});
    out.insert(out.end(), extra.begin(), extra.end());
    return out;
  }
  fs::path log_;
  ChildProcess process_;
  std::string url_;
};

// Chromium with the page, through page_driver.mjs.
class Page {
 public:
  Page(const std::string& url, const fs::path& log) : log_(log) {
    ::signal(SIGPIPE, SIG_IGN);  // a driver that died is reported by its answers, not by a signal
    int to_driver[2], from_driver[2];
    if (::pipe2(to_driver, O_CLOEXEC) != 0 || ::pipe2(from_driver, O_CLOEXEC) != 0) throw std::runtime_error("pipe");
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, to_driver[0], 0);
    posix_spawn_file_actions_adddup2(&actions, from_driver[1], 1);
    posix_spawn_file_actions_addopen(&actions, 2, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<std::string> args = {"node", RDTF_VIEW_DRIVER};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    const int error = posix_spawnp(&pid_, "node", &actions, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&actions);
    ::close(to_driver[0]);
    ::close(from_driver[1]);
    to_ = to_driver[1];
    from_ = from_driver[0];
    if (error != 0) throw std::runtime_error(std::string("cannot start node: ") + std::strerror(error));
    // Starting Chromium comes first: on a loaded machine it has taken over 30 s.
    const Json opened = request({{"open", url}}, 150s);
    if (!opened.value("ok", false)) throw std::runtime_error("the page did not open: " + opened.dump() + "\n" + driver_log());
  }
  ~Page() {
    ::close(to_);  // the driver quits at the end of its input
    int status = 0;
    if (!wait_until([&] { return ::waitpid(pid_, &status, WNOHANG) == pid_; }, 5s)) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
    }
    ::close(from_);
  }
  Page(const Page&) = delete;
  Page& operator=(const Page&) = delete;

  std::string driver_log() const { return testing::read_file(log_); }

  // One request, its answer (throws when the driver answers nothing within the timeout).
  Json request(const Json& r, Clock::duration timeout = 30s) {
    const std::string line = r.dump() + "\n";
    if (::write(to_, line.data(), line.size()) != static_cast<ssize_t>(line.size())) {
      throw std::runtime_error("the page driver is gone; its log:\n" + driver_log());
    }
    const auto deadline = Clock::now() + timeout * RDTF_TEST_DEADLINE_SCALE;
    for (;;) {
      if (const auto end = buffer_.find('\n'); end != std::string::npos) {
        const std::string answer = buffer_.substr(0, end);
        buffer_.erase(0, end + 1);
        return Json::parse(answer);
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
      if (left <= 0) {
        throw std::runtime_error("no answer from the page driver to " + r.dump().substr(0, 200) + "; its log:\n" +
                                 driver_log());
      }
      pollfd p{from_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(std::min<long long>(left, 1000))) > 0) {
        char chunk[65536];
        const ssize_t n = ::read(from_, chunk, sizeof chunk);
        if (n <= 0) throw std::runtime_error("the page driver closed; its log:\n" + driver_log());
        buffer_.append(chunk, static_cast<std::size_t>(n));
      }
    }
  }
  // A JavaScript expression's value (awaited when it is a promise).
  Json eval(const std::string& js) {
    const Json answer = request({{"eval", js}});
    if (!answer.value("ok", false)) throw std::runtime_error("eval failed: " + answer.dump() + "\n" + driver_log());
    return answer["value"];
  }
  Json state() { return eval("window.rdtfView.state()"); }
  // Polls the page's state until `predicate` holds; the last state seen in `last`.
  bool wait_state(const std::function<bool(const Json&)>& predicate, Clock::duration timeout = 10s, Json* last = nullptr) {
    Json seen;
    const bool ok = wait_until([&] {
      seen = state();
      return predicate(seen);
    }, timeout);
    if (last) *last = seen;
    return ok;
  }
  void screenshot(const std::string& name) {
    const Json answer = request({{"screenshot", (view_artifacts() / name).string()}});
    if (!answer.value("ok", false)) throw std::runtime_error("screenshot failed: " + answer.dump());
  }

 private:
  fs::path log_;
  pid_t pid_ = -1;
  int to_ = -1, from_ = -1;
  std::string buffer_;
};

// The model `id` in a page state, or null.
inline Json model_in(const Json& state, const std::string& id) {
  for (const auto& m : state["models"]) {
    if (m["id"] == id) return m;
  }
  return nullptr;
}

}  // namespace rdtf::itest
