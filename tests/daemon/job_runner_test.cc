// ThreadJobRunner (daemon/ports.h): the worker threads the daemon hands conversions to, with real
// conversions; the loop is woken through the runner's descriptor, outcomes come back whole.
#include <poll.h>

#include <atomic>
#include <future>
#include <set>
#include <thread>

#include <gtest/gtest.h>

#include "ports.h"
#include "result_cache.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;

class JobRunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    fs::create_directories(tmp_ / "watch");
    root_ = fs::canonical(tmp_ / "watch");
  }
  ConversionJob job(const std::string& name) {
    rdtf::testing::write_file(root_ / name,
                              rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / "arm3.glb"));
    ConversionJob job;
    job.model_id = name;
    job.root = root_;
    job.source = root_ / name;
    job.output_dir = tmp_.path() / "out" / name;
    return job;
  }
  // Waits (on the descriptor, as the loop does) until `count` outcomes came back.
  std::vector<ConversionOutcome> collect(ThreadJobRunner& runner, std::size_t count) {
    std::vector<ConversionOutcome> all;
    while (all.size() < count) {
      pollfd fd{runner.fd(), POLLIN, 0};
      if (::poll(&fd, 1, 60000) <= 0) break;  // A minute: far beyond three small conversions.
      // One at a time: the rest stay for the next turn, and the descriptor says so.
      bool more = false;
      auto taken = runner.take(1, more);
      EXPECT_LE(taken.size(), 1u);
      for (auto& outcome : taken) all.push_back(std::move(outcome));
    }
    return all;
  }

  rdtf::testing::TempDir tmp_;
  fs::path root_;
};

TEST_F(JobRunnerTest, EveryJobComesBackConvertedAndWakesTheLoop) {
  ThreadJobRunner runner(2);
  ASSERT_GE(runner.fd(), 0);
  for (const char* name : {"a.glb", "b.glb", "c.glb"}) runner.submit(job(name));
  const auto outcomes = collect(runner, 3);
  ASSERT_EQ(outcomes.size(), 3u);
  std::set<std::string> ids;
  for (const auto& outcome : outcomes) {
    EXPECT_EQ(outcome.kind, ConversionOutcome::Kind::kConverted) << outcome.model_id;
    ids.insert(outcome.model_id);
  }
  EXPECT_EQ(ids, (std::set<std::string>{"a.glb", "b.glb", "c.glb"}));
}

// Two large conversions hold both workers (here: blocked reading their .bin): a small model's save
// still converts at once, on the express worker, and a large job is never taken by it.
TEST_F(JobRunnerTest, ASmallJobIsNotHeldBehindLargeOnesThatHoldEveryWorker) {
  std::atomic<int> reading{0};
  ThreadJobRunner runner(2);
  // Declared after the runner, so gone before it: a failed assertion still lets its workers finish.
  struct Release {
    std::promise<void> promise;
    bool done = false;
    void now() {
      if (!done) promise.set_value();
      done = true;
    }
    ~Release() { now(); }
  } release;
  const std::shared_future<void> released = release.promise.get_future().share();
  for (const char* name : {"big1.gltf", "big2.gltf", "big3.gltf"}) {
    rdtf::testing::write_file(root_ / name, rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / "arm3.gltf"));
    rdtf::testing::write_file(root_ / "arm3.bin", rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / "arm3.bin"));
    ConversionJob big;
    big.model_id = name;
    big.root = root_;
    big.source = root_ / name;
    big.output_dir = tmp_.path() / "out" / name;
    big.read_file = [&reading, released](const fs::path&, const fs::path& path, std::uint64_t, SourceFile& file) {
      ++reading;
      released.wait();
      const std::string bytes = rdtf::testing::read_file(path);
      file.bytes.assign(bytes.begin(), bytes.end());
      file.size = bytes.size();
    };
    runner.submit(std::move(big));
  }
  for (int i = 0; i < 6000 && reading < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ASSERT_EQ(reading, 2) << "both workers should hold a large job, the third waiting";
  ConversionJob small = job("small.glb");
  small.express = true;
  runner.submit(std::move(small));
  const auto first = collect(runner, 1);
  ASSERT_EQ(first.size(), 1u);
  EXPECT_EQ(first[0].model_id, "small.glb");
  EXPECT_EQ(first[0].kind, ConversionOutcome::Kind::kConverted);
  EXPECT_EQ(reading, 2) << "the express worker took a large job";
  release.now();
  const auto rest = collect(runner, 3);
  ASSERT_EQ(rest.size(), 3u);
  for (const auto& outcome : rest) EXPECT_EQ(outcome.kind, ConversionOutcome::Kind::kConverted) << outcome.model_id;
}

// The cache entry is work for after the hand-over: the outcome reaches the loop without it, and
// the worker writes it (every one of them by the time stop() returns).
TEST_F(JobRunnerTest, TheWorkerStoresTheResultInTheCacheAfterHandingTheOutcomeOver) {
  auto cache = std::make_shared<ResultCache>(ResultCache::folder_for(tmp_.path() / "out"), 10);
  ThreadJobRunner runner(2);
  for (const char* name : {"a.glb", "b.glb", "c.glb"}) {
    ConversionJob with_cache = job(name);
    with_cache.cache = cache;
    with_cache.cache_key = "key";
    runner.submit(std::move(with_cache));
  }
  const auto outcomes = collect(runner, 3);
  ASSERT_EQ(outcomes.size(), 3u);
  for (const auto& outcome : outcomes) {
    EXPECT_EQ(outcome.kind, ConversionOutcome::Kind::kConverted) << outcome.model_id;
    EXPECT_FALSE(static_cast<bool>(outcome.after_handover)) << outcome.model_id;
  }
  runner.stop();
  EXPECT_EQ(cache->entries(), 3u);
  // What was stored is what a second conversion of the same content finds.
  ThreadJobRunner again(1);
  ConversionJob second = job("a.glb");
  second.cache = cache;
  second.cache_key = "key";
  again.submit(std::move(second));
  const auto hit = collect(again, 1);
  ASSERT_EQ(hit.size(), 1u);
  EXPECT_TRUE(hit[0].from_cache);
  EXPECT_EQ(hit[0].cache_note, "");
}

TEST_F(JobRunnerTest, StopDropsTheJobsNotStartedAndWaitsForTheRunningOnes) {
  ThreadJobRunner runner(1);
  for (const char* name : {"a.glb", "b.glb", "c.glb"}) runner.submit(job(name));
  runner.stop();  // Whatever had started is finished; nothing runs any more.
  bool more = true;
  const auto outcomes = runner.take(10, more);
  EXPECT_FALSE(more);
  EXPECT_LE(outcomes.size(), 3u);
  for (const auto& outcome : outcomes) EXPECT_EQ(outcome.kind, ConversionOutcome::Kind::kConverted) << outcome.model_id;
}

TEST_F(JobRunnerTest, ACommitRunsBeforeTheConversionsQueuedAheadOfIt) {
  // A prepared conversion (converting while settling), its outputs staged.
  ConversionJob prepare = job("c.glb");
  prepare.prepare = true;
  ConversionOutcome prepared = run_conversion(prepare);
  ASSERT_TRUE(prepared.staged);

  // The only worker is held inside a conversion that reads a .bin, until the test lets it go.
  rdtf::testing::write_file(root_ / "held.gltf", rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / "arm3.gltf"));
  rdtf::testing::write_file(root_ / "arm3.bin", rdtf::testing::read_file(rdtf::testing::data_dir() / "blender" / "arm3.bin"));
  ConversionJob held;
  held.model_id = "held.gltf";
  held.root = root_;
  held.source = root_ / "held.gltf";
  held.output_dir = tmp_.path() / "out" / "held.gltf";
  std::promise<void> entered;
  std::atomic<bool> once{false};
  std::promise<void> release;
  std::shared_future<void> released = release.get_future().share();
  held.read_file = [&entered, &once, released](const fs::path&, const fs::path& path, std::uint64_t, SourceFile& file) {
    if (!once.exchange(true)) entered.set_value();
    released.wait();
    const std::string bytes = rdtf::testing::read_file(path);
    file.bytes.assign(bytes.begin(), bytes.end());
    file.size = bytes.size();
  };
  ThreadJobRunner runner(1);
  runner.submit(std::move(held));
  entered.get_future().wait();
  runner.submit(job("n.glb"));  // Queued first...
  ConversionJob commit = job("c.glb");
  commit.commit = std::make_shared<ConversionOutcome>(std::move(prepared));
  runner.submit(std::move(commit));  // ...but the commit goes first.
  release.set_value();
  const auto outcomes = collect(runner, 3);
  ASSERT_EQ(outcomes.size(), 3u);
  std::vector<std::string> order;
  for (const auto& outcome : outcomes) order.push_back(outcome.model_id);
  EXPECT_EQ(order, (std::vector<std::string>{"held.gltf", "c.glb", "n.glb"}));
  EXPECT_TRUE(outcomes[1].while_settling);
  ASSERT_TRUE(outcomes[1].converted);
  EXPECT_TRUE(outcomes[1].converted->written);
  EXPECT_TRUE(fs::exists(tmp_.path() / "out" / "c.glb" / "c.rdtf.gltf"));
}

TEST_F(JobRunnerTest, AModelGoneBeforeItsJobRunsComesBackVanished) {
  ThreadJobRunner runner(1);
  ConversionJob gone = job("gone.glb");
  fs::remove(gone.source);
  runner.submit(std::move(gone));
  const auto outcomes = collect(runner, 1);
  ASSERT_EQ(outcomes.size(), 1u);
  EXPECT_EQ(outcomes[0].kind, ConversionOutcome::Kind::kVanished);
}

}  // namespace
}  // namespace rdtf::daemon
