// The validation's CPU budget and its cancellation (docs/dynamics.md, "Budget"): a big model with a
// tiny budget gets its verdict, SIM_BUDGET_EXCEEDED naming the budget and how far it got, long
// before its run would end; a cancelled validation stops with SIM_CANCELLED, whenever the flag
// is set.
#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "dynamics/benchmark_robots.h"
#include "dynamics/dynamics_models.h"

namespace rdtf {
namespace {

using dynamics_test::all_text;
using dynamics_test::with_code;

TEST(ValidationBudget, ABigModelWithATinyBudgetGetsItsVerdict) {
  ValidationOptions options;
  options.cpu_budget = 0.02;  // s; the 200-link tree's 3 s take seconds of CPU
  const ValidationReport report = validate_dynamics(benchmark_robots::tree_robot(200), options, nullptr, "tree.gltf");
  std::printf("tree_200, budget 0.02 s: %s\n", validation_summary_line(report).c_str());
  EXPECT_FALSE(report.passed);
  EXPECT_TRUE(report.simulated);
  EXPECT_LT(report.steps, 3000u);
  EXPECT_FALSE(report.cancelled);
  const auto exceeded = with_code(report.diagnostics, "SIM_BUDGET_EXCEEDED");
  ASSERT_EQ(exceeded.size(), 1u) << all_text(report.diagnostics);
  EXPECT_EQ(exceeded[0].severity, Severity::kError);
  EXPECT_EQ(exceeded[0].file, "tree.gltf");
  EXPECT_NE(exceeded[0].message.find("beyond its budget of 0.02 s"), std::string::npos) << exceeded[0].message;
  // 199 bodies: the root, welded to the world, is none.
  EXPECT_NE(exceeded[0].message.find(" steps of 199 bodies, dWorldQuickStep"), std::string::npos) << exceeded[0].message;
  // The run stopped at the first check past the budget: nothing else was judged.
  for (const Diagnostic& d : report.diagnostics.all()) {
    if (d.severity == Severity::kError) {
      EXPECT_EQ(d.code, "SIM_BUDGET_EXCEEDED") << format(d);
    }
  }
}

TEST(ValidationBudget, ZeroMeansNoLimit) {
  ValidationOptions options;
  options.cpu_budget = 0;
  options.duration = 0.1;
  const ValidationReport report = validate_dynamics(benchmark_robots::chain_robot(30), options);
  EXPECT_TRUE(report.passed) << all_text(report.diagnostics);
  EXPECT_EQ(report.steps, 100u);
}

TEST(ValidationBudget, ACancelledValidationStops) {
  std::atomic<bool> cancel{true};
  ValidationOptions options;
  options.cancel = &cancel;
  const ValidationReport before = validate_dynamics(benchmark_robots::chain_robot(30), options);
  EXPECT_TRUE(before.cancelled);
  EXPECT_FALSE(before.passed);
  EXPECT_EQ(before.steps, 0u);
  EXPECT_TRUE(before.diagnostics.contains("SIM_CANCELLED")) << all_text(before.diagnostics);

  // Set from another thread while a run of a simulated day (and no budget) goes on: it ends with
  // SIM_CANCELLED whenever the flag lands, before or during the run.
  cancel = false;
  options.duration = 86400;
  options.cpu_budget = 0;
  std::thread canceller([&cancel] { cancel = true; });
  const ValidationReport during = validate_dynamics(benchmark_robots::chain_robot(30), options);
  canceller.join();
  EXPECT_TRUE(during.cancelled);
  EXPECT_FALSE(during.passed);
  EXPECT_LT(during.steps, 86400000u);
  const auto cancelled = with_code(during.diagnostics, "SIM_CANCELLED");
  ASSERT_EQ(cancelled.size(), 1u) << all_text(during.diagnostics);
  EXPECT_EQ(cancelled[0].severity, Severity::kError);
}

}  // namespace
}  // namespace rdtf
