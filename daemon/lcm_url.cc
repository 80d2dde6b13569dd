#include "lcm_url.h"

#include <arpa/inet.h>

#include <charconv>
#include <string_view>

#include "safe_decode.h"

namespace rdtf::daemon {
namespace {

// A whole decimal number in [min, max], nothing else. LCM reads these with strtol(..., 0), so a
// leading 0 is octal and 0x hexadecimal: ":07667" joined port 4023. Such a spelling is refused
// rather than read another way than it looks (review s90rev R2).
bool whole_number(std::string_view text, long long min, long long max) {
  if (text.size() > 1 && text[0] == '0') return false;
  long long value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size() && value >= min && value <= max;
}

bool check_udpm(const std::string& url, const char* setting, std::string_view network, std::string_view options,
                std::string& error) {
  const auto fail = [&](const std::string& why) {
    error = std::string(setting) + " \"" + lcm_safe::printable(url, 120) + "\": " + why;
    return false;
  };
  // An empty network is LCM's default group and port (udpm:// and udpm://?ttl=1 are LCM's own
  // spellings of it: s90rev R3).
  if (!network.empty()) {
    const std::size_t colon = network.find(':');
    const std::string address(network.substr(0, colon));
    in_addr group{};
    if (::inet_pton(AF_INET, address.c_str(), &group) != 1) {
      return fail("\"" + lcm_safe::printable(address, 60) +
                  "\" is not an IPv4 address (udpm://GROUP:PORT, e.g. udpm://239.255.76.67:7667)");
    }
    if (!IN_MULTICAST(ntohl(group.s_addr))) {
      return fail(address + " is not a multicast group (224.0.0.0 to 239.255.255.255; LCM's default is 239.255.76.67)");
    }
    // A group without a port is port 0 to LCM, on which every send fails (s90rev R1).
    if (colon == std::string_view::npos) return fail("no port: give the group's port (udpm://" + address + ":7667)");
    if (!whole_number(network.substr(colon + 1), 1, 65535)) {
      return fail("port \"" + lcm_safe::printable(network.substr(colon + 1), 40) +
                  "\" is not a decimal number from 1 to 65535");
    }
  }
  while (!options.empty()) {
    const std::size_t amp = options.find('&');
    const std::string_view option = options.substr(0, amp);
    options = amp == std::string_view::npos ? std::string_view() : options.substr(amp + 1);
    const std::size_t eq = option.find('=');
    const std::string name(option.substr(0, eq));
    const std::string_view value = eq == std::string_view::npos ? std::string_view() : option.substr(eq + 1);
    const std::string shown = "\"" + lcm_safe::printable(option, 60) + "\"";
    if (name == "ttl") {
      if (!whole_number(value, 0, 255)) {
        return fail("option " + shown + ": ttl is a decimal whole number from 0 to 255 (0: this host only)");
      }
    } else if (name == "recv_buf_size") {
      if (!whole_number(value, 1, 0x7fffffff)) {
        return fail("option " + shown + ": recv_buf_size is a decimal byte count from 1 to 2147483647");
      }
    } else {
      // LCM would warn on stderr and ignore it: a misspelt ttl leaves the datagrams on this host.
      return fail("option " + shown + " is not one LCM's udpm provider reads (ttl, recv_buf_size)");
    }
  }
  return true;
}

}  // namespace

bool check_lcm_url(const std::string& url, std::string& error, const char* setting) {
  if (url.empty()) return true;  // LCM's default, udpm://239.255.76.67:7667?ttl=0.
  const std::size_t scheme_end = url.find("://");
  if (scheme_end == std::string::npos) {
    error = std::string(setting) + " \"" + lcm_safe::printable(url, 120) +
            "\" is not an LCM URL (PROVIDER://NETWORK?OPTIONS, e.g. udpm://239.255.76.67:7667?ttl=1)";
    return false;
  }
  const std::string provider = url.substr(0, scheme_end);
  const std::string_view rest = std::string_view(url).substr(scheme_end + 3);
  const std::size_t question = rest.find('?');
  const std::string_view network = rest.substr(0, question);
  const std::string_view options = question == std::string_view::npos ? std::string_view() : rest.substr(question + 1);
  if (provider == "udpm") return check_udpm(url, setting, network, options, error);
  if (provider == "memq" || provider == "file" || provider == "tcpq" || provider == "mpudpm") return true;
  error = std::string(setting) + " \"" + lcm_safe::printable(url, 120) + "\": LCM has no provider \"" +
          lcm_safe::printable(provider, 40) + "\" (udpm for UDP multicast; also memq, file, tcpq, mpudpm)";
  return false;
}

}  // namespace rdtf::daemon
