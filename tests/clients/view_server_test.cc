// rdtf-view's server (clients/view/server.h) in process, on a loopback port: what it does when the
// process runs out of descriptors.
#include <gtest/gtest.h>

#include <cerrno>
#include <chrono>
#include <iostream>
#include <memory>
#include <string>
#include <vector>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core/error.hpp>

#include "model_hub.h"
#include "server.h"
#include "support/test_support.h"

namespace rdtf::view {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
using tcp = asio::ip::tcp;
using namespace std::chrono_literals;

// A browser tab (or a script) that opens connections past the open-file limit leaves them in the
// listen backlog, where accept fails at once with EMFILE for as long as no descriptor frees:
// accepting again at once held a core. The server waits kAcceptRetry after each such failure, so
// in `elapsed` it can fail at most 1 + elapsed / kAcceptRetry times (a loaded machine only makes
// it fewer); and once descriptors are free again, the waiting connections are served.
// Under the sanitizers, UBSan's vptr check opens a pipe at the first call through a (vtable, type)
// it has not met, and with no descriptor free reports a false "invalid vptr"
// (docs/notes/ubsan-descriptors.md): the calls the starved accept makes through such types (its
// message on std::cerr, the error's category and text, the retry timer) are made once first.
TEST(ViewServer, RunningOutOfDescriptorsRetriesTheAcceptInsteadOfSpinning) {
  {
    const beast::error_code shortage(EMFILE, beast::system_category());
    std::cerr.flush();  // A member call: the check is made at such a call, on (std::cerr's vtable, basic_ostream).
    EXPECT_FALSE(shortage.message().empty());
    EXPECT_TRUE(shortage.category() == beast::system_category());
    asio::io_context warm_io;
    asio::steady_timer timer(warm_io);
    timer.expires_after(1ms);
    timer.async_wait([](beast::error_code) {});
    warm_io.run();
  }
  testing::TempDir web;
  asio::io_context io;
  ModelHub hub(GainRule{}, [](std::shared_ptr<const std::string>) {}, [](const std::string&, rdtf::joint_command_t&) {});
  ServerOptions options;
  options.web_dir = web.path();
  Server server(io, tcp::endpoint(asio::ip::address_v4::loopback(), 0), options, hub);
  const tcp::endpoint address(asio::ip::address_v4::loopback(), server.port());
  // The clients' sockets are made first: connecting one needs no further descriptor.
  std::vector<tcp::socket> clients;
  for (int i = 0; i < 3; ++i) {
    clients.emplace_back(io);
    clients.back().open(tcp::v4());
  }
  std::chrono::steady_clock::duration elapsed{};
  {
    const testing::DescriptorHeadroom none(0);
    ASSERT_TRUE(none.ok());
    // A blocking connect completes against the listen backlog, before any accept.
    for (auto& client : clients) client.connect(address);
    const auto start = std::chrono::steady_clock::now();
    io.run_for(500ms);
    elapsed = std::chrono::steady_clock::now() - start;
  }
  const std::uint64_t failures = server.stats().accept_failures;
  EXPECT_GE(failures, 1u);
  EXPECT_LE(failures, 1 + static_cast<std::uint64_t>(elapsed / kAcceptRetry))
      << "in " << std::chrono::duration<double>(elapsed).count() << " s";
  EXPECT_EQ(server.stats().connections_accepted, 0u);

  io.restart();
  const auto deadline = std::chrono::steady_clock::now() + 10s;
  while (server.stats().connections_accepted < clients.size() && std::chrono::steady_clock::now() < deadline) {
    io.run_for(10ms);
  }
  EXPECT_EQ(server.stats().connections_accepted, clients.size());
}

}  // namespace
}  // namespace rdtf::view
