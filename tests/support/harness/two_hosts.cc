#include "support/harness/two_hosts.h"

#include <unistd.h>

#include <stdexcept>

namespace rdtf::itest {
namespace {

void run(const std::string& command) {
  const auto result = testing::run_command(command);
  if (result.exit_code != 0) throw std::runtime_error("two hosts: '" + command + "' failed: " + result.err);
}

}  // namespace

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

TwoHosts::TwoHosts() : name_("rdtfmh" + std::to_string(::getpid())) {
  run("mkdir -p /run/netns && mount -t tmpfs rdtf-netns /run/netns");
  run("ip netns add " + name_);
  run("ip link add mhA type veth peer name mhB netns " + name_);
  run("ip addr add 10.213.0.1/24 dev mhA && ip link set mhA up multicast on");
  run("ip route replace 224.0.0.0/4 dev mhA");
  run("ip -n " + name_ + " link set lo up");
  run("ip -n " + name_ + " addr add 10.213.0.2/24 dev mhB && ip -n " + name_ + " link set mhB up multicast on");
  run("ip -n " + name_ + " route add 224.0.0.0/4 dev mhB");
}

TwoHosts::~TwoHosts() { testing::run_command("ip netns del " + name_); }

testing::CommandResult TwoHosts::on_b(const std::vector<std::string>& args, const std::vector<fs::path>& hidden) const {
  std::string script;
  for (const auto& folder : hidden) {
    script += "mount -t tmpfs hidden " + shell_quote(folder.string()) + " || exit 98; ";
    script += "[ -z \"$(ls -A " + shell_quote(folder.string()) + ")\" ] || exit 99; ";
  }
  script += "exec \"$@\"";
  std::string command = "ip netns exec " + name_ + " unshare -m --propagation private sh -c " + shell_quote(script) + " sh";
  for (const auto& arg : args) command += " " + shell_quote(arg);
  return testing::run_command(command);
}

void TwoHosts::shape_a_to_b(const std::string& rate, const std::string& burst, const std::string& latency) {
  run("tc qdisc add dev mhA root tbf rate " + rate + " burst " + burst + " latency " + latency);
}

}  // namespace rdtf::itest
