// rdtfd's shutdown does not wait for a dynamics check (docs/dynamics.md, SIM_CANCELLED): a model
// whose check would run for minutes (300 links, 60 s of simulated time, the most that
// validation_seconds allows, and no CPU budget) is being checked when SIGTERM arrives; rdtfd
// exits 0 at once, and the revision it never judged is neither published nor logged as rejected.
#include <signal.h>

#include <rdtf/status_t.hpp>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

TEST(DaemonLife, SigtermDoesNotWaitForADynamicsCheck) {
  Session s;
  const auto big = box_model("big_base", 0.02, 300);
  write_model(s.watch, "big.gltf", big);
  auto& daemon = s.start(DaemonOptions()
                             .with("validate", true)
                             .with("urdf", false)
                             .with("validation_seconds", 60)
                             .with("validation_cpu_budget_s", 0)
                             .with("simulate", false)
                             .with("status_period_ms", 200));
  // A STATUS three seconds after the start with the model still pending: it settled (50 ms) and
  // was converted (about a second here) before, so its check is running.
  ASSERT_TRUE(s.wait_for(
      [](const auto& all) {
        for (const auto& m : all) {
          if (m.kind() != "STATUS") continue;
          const auto status = m.template as<rdtf::status_t>();
          if (status.uptime >= 3.0 && status.pending == 1) return true;
        }
        return false;
      },
      10s))
      << daemon.log();
  daemon.signal(SIGTERM);
  EXPECT_EQ(daemon.wait_exit(10s), std::optional<int>(0)) << daemon.log();
  EXPECT_NE(daemon.log().find("rdtfd stopped"), std::string::npos) << daemon.log();
  EXPECT_EQ(daemon.log().find("rejected big"), std::string::npos) << daemon.log();
  EXPECT_EQ(daemon.log().find("converted big"), std::string::npos) << daemon.log();
  EXPECT_TRUE(on_kind(s.messages(), "DESCRIPTION").empty());
}

}  // namespace
}  // namespace rdtf::itest
