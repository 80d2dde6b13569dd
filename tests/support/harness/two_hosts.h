// Two hosts on one machine for the multi-host tests (multihost_itest.cc): the test's own network
// namespace (made by tests/support/in_netns.sh) is host A, where rdtfd runs; host B is a second
// network namespace joined to A by a veth pair, 10.213.0.1/24 (A) and 10.213.0.2/24 (B), with
// the multicast route 224.0.0.0/4 over the link on both sides. LCM runs with ttl=1 (ttl=0 would
// never leave A). Commands run on B inside a mount namespace of their own where the folders given
// as `hidden` are covered by an empty tmpfs: B sees none of the daemon's files.
//
// `ip netns add` keeps its handle under /run/netns; a tmpfs mounted there first keeps that in
// the test's private mount namespace (nothing is left on the machine). Make a TwoHosts before any
// LCM socket of the test opens (before the Session): group memberships follow the route that
// is current when a socket joins.
#pragma once

#include <string>
#include <vector>

#include "support/harness/basics.h"

namespace rdtf::itest {

std::string shell_quote(const std::string& text);

class TwoHosts {
 public:
  static constexpr const char* kUrl = "udpm://239.255.76.67:7667?ttl=1";

  TwoHosts();
  ~TwoHosts();
  TwoHosts(const TwoHosts&) = delete;
  TwoHosts& operator=(const TwoHosts&) = delete;

  // `args` on host B, each folder of `hidden` covered by an empty tmpfs first (the command fails
  // with exit code 99 when one is still visible).
  testing::CommandResult on_b(const std::vector<std::string>& args, const std::vector<fs::path>& hidden) const;

  // Limits what A sends to B to `rate` (tc's token bucket filter on A's end of the link: a bucket
  // of `burst`, a queue of `latency`): packets sent faster are dropped before they reach B.
  static void shape_a_to_b(const std::string& rate, const std::string& burst, const std::string& latency);

 private:
  std::string name_;
};

}  // namespace rdtf::itest
