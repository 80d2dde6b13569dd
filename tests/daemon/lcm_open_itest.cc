// LCM that opens only half way, as in a process out of descriptors (helper sweep s106fd D3, D7):
// lcm::LCM::good() is true once the sending side is made, but udpm makes its receive socket and
// thread at the first subscribe, and LCM's C++ subscribe hands back a subscription with nothing
// behind it when that fails. rdtfd then ran deaf to requests and commands; rdtf-view crashed
// (SIGSEGV on the subscription, or abort() on asio's signal pipe); rdtfd's live simulation, whose
// LCM failed to open, printed a line for every publish it dropped (61,732 lines in 45 s) while
// rdtfd said it had started. Each now exits 1 with the reason.
//
// strace injects the failure into the one system call that makes it: the processes' calls come in
// the order of their code (rdtfd and rdtf-view: LCM's pipe, two sockets while LCM opens, the
// receive socket at the first subscribe, the receive thread's pipe; then rdtfd's live simulation
// opens its own LCM with a third pipe, and rdtf-view's signal_set makes its own third pipe).
#include <cstdlib>

#include "daemon/harness.h"
#include "support/harness/fs_support.h"
#include "support/sanitized.h"

namespace rdtf::itest {
namespace {

// LeakSanitizer cannot run under ptrace (CI's sanitizer build): leaks are not looked for in the
// traced process alone, whatever else ASAN_OPTIONS asks.
std::vector<std::string> traced(const std::string& inject, std::vector<std::string> command) {
  const char* asan = std::getenv("ASAN_OPTIONS");
  std::vector<std::string> args = {"env",    std::string("ASAN_OPTIONS=") + (asan ? std::string(asan) + ":" : "") + "detect_leaks=0",
                                   "strace", "-f",
                                   "-qq",    "-o",
                                   "/dev/null", "-e",
                                   "trace=socket,pipe2", "-e",
                                   "inject=" + inject};
  args.insert(args.end(), command.begin(), command.end());
  return args;
}

struct Folders {
  testing::TempDir root;
  fs::path watch = root / "watch";
  fs::path output = root / "output";
  Folders() {
    fs::create_directories(watch);
    fs::create_directories(output);
  }
  std::vector<std::string> rdtfd() const {
    return {RDTFD_PATH, "--watch", watch.string(), "--output", output.string(), "--lcm-url",
            "udpm://239.255.76.67:7667?ttl=0"};
  }
};

TEST(LcmOpen, RdtfdThatCannotReceiveOnLcmRefusesToStart) {
  Folders f;
  ChildProcess daemon(traced("socket:error=EMFILE:when=3", f.rdtfd()), f.root / "rdtfd.log");
  const auto code = daemon.wait_exit(std::chrono::seconds(20 * deadline_scale()));
  ASSERT_TRUE(code.has_value()) << daemon.output();
  EXPECT_EQ(*code, 1) << daemon.output();
  EXPECT_NE(daemon.output().find("cannot receive on LCM at 'udpm://239.255.76.67:7667?ttl=0': its receive socket or thread could not be made"),
            std::string::npos)
      << daemon.output();
  EXPECT_NE(daemon.output().find("allocating LCM recv socket: Too many open files"), std::string::npos) << daemon.output();
  EXPECT_EQ(daemon.output().find("rdtfd started"), std::string::npos) << daemon.output();
}

// Not in the sanitizer build: UBSan's vptr check opens pipes of its own (one at the first call
// through each vtable it has not seen; docs/notes/ubsan-descriptors.md), so the third pipe2 is
// not the one meant, and a failed one is reported as a false "invalid vptr".
#if !RDTF_SANITIZED
TEST(LcmOpen, RdtfdWhoseLiveSimulationCannotOpenLcmRefusesToStart) {
  Folders f;
  ChildProcess daemon(traced("pipe2:error=EMFILE:when=3", f.rdtfd()), f.root / "rdtfd.log");
  const auto code = daemon.wait_exit(std::chrono::seconds(20 * deadline_scale()));
  ASSERT_TRUE(code.has_value()) << daemon.output();
  EXPECT_EQ(*code, 1) << daemon.output();
  EXPECT_NE(daemon.output().find("the live simulation: cannot open LCM at 'udpm://239.255.76.67:7667?ttl=0'"),
            std::string::npos)
      << daemon.output();
  EXPECT_EQ(daemon.output().find("Ignoring call to publish"), std::string::npos) << daemon.output();
  EXPECT_EQ(daemon.output().find("rdtfd started"), std::string::npos) << daemon.output();
}
#endif

TEST(LcmOpen, RdtfViewThatCannotReceiveOnLcmSaysSoInsteadOfCrashing) {
  testing::TempDir root;
  ChildProcess view(traced("socket:error=EMFILE:when=3",
                           {RDTF_VIEW_PATH, "--port", "0", "--lcm-url", "udpm://239.255.76.67:7667?ttl=0"}),
                    root / "view.log");
  const auto code = view.wait_exit(std::chrono::seconds(20 * deadline_scale()));
  ASSERT_TRUE(code.has_value()) << view.output();
  EXPECT_EQ(*code, 1) << view.output();
  EXPECT_NE(view.output().find("rdtf-view: cannot receive on LCM at 'udpm://239.255.76.67:7667?ttl=0': its receive socket or thread could not be made"),
            std::string::npos)
      << view.output();
}

// Not in the sanitizer build: UBSan's vptr check opens pipes of its own (one at the first call
// through each vtable it has not seen; docs/notes/ubsan-descriptors.md), so the third pipe2 is
// not the one meant, and a failed one is reported as a false "invalid vptr".
#if !RDTF_SANITIZED
TEST(LcmOpen, RdtfViewWithoutADescriptorForItsSignalsSaysSoInsteadOfAborting) {
  testing::TempDir root;
  ChildProcess view(traced("pipe2:error=EMFILE:when=3",
                           {RDTF_VIEW_PATH, "--port", "0", "--lcm-url", "udpm://239.255.76.67:7667?ttl=0"}),
                    root / "view.log");
  const auto code = view.wait_exit(std::chrono::seconds(20 * deadline_scale()));
  ASSERT_TRUE(code.has_value()) << view.output();
  EXPECT_EQ(*code, 1) << view.output();
  EXPECT_NE(view.output().find("rdtf-view: signal_set_service pipe: Too many open files"), std::string::npos)
      << view.output();
}
#endif

}  // namespace
}  // namespace rdtf::itest
