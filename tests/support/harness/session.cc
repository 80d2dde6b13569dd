#include "support/harness/session.h"

#include <gtest/gtest.h>

#include <iostream>
#include <stdexcept>

#include <rdtf/request_t.hpp>

#include "support/harness/messages.h"

namespace rdtf::itest {

Session::Session(std::string channel_prefix) : prefix(std::move(channel_prefix)), subscriber(prefix + "/.*") {
  fs::create_directories(watch);
  fs::create_directories(output);
}

Session::~Session() {
  if (::testing::Test::HasFailure() && daemon) {
    std::cerr << "---- rdtfd log ----\n" << daemon->log() << "-------------------\n";
  }
}

DaemonProcess& Session::start(DaemonOptions options) {
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

bool Session::wait_revision(const std::string& id, std::int64_t revision, const std::string& hash,
                            Clock::duration timeout) {
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

std::optional<rdtf::status_t> Session::wait_idle(int quiet, Clock::duration timeout) {
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

bool Session::wait_logger_recording(const fs::path& log, Clock::duration timeout) {
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

void Session::request(const std::string& model_id, const std::string& requester) {
  rdtf::request_t request;
  request.utime = 0;
  request.model_id = model_id;
  request.requester = requester;
  subscriber.publish(prefix + "/REQUEST", request);
}

}  // namespace rdtf::itest
