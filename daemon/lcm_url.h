// The LCM URL of a config, checked before anything is opened with it.
#pragma once

#include <string>

namespace rdtf::daemon {

// True when `url` ("" = LCM's default) is one LCM can use as the user meant it. LCM 1.3 itself
// refuses an unknown provider or an unusable address, but only warns on stderr, and carries on
// with a default, for a misspelt or invalid option: "udpm://239.255.76.67:7667?tll=1" (or
// "ttl=one") ran with TTL 0, and no controller on another host ever heard rdtfd. So for udpm the
// group must be an IPv4 multicast address, the port 1..65535, and each option one LCM reads
// (ttl 0..255, recv_buf_size a positive byte count). Other providers (memq, file, tcpq, mpudpm)
// are passed to LCM as they are. On false, `error` says which part is wrong and why.
bool check_lcm_url(const std::string& url, std::string& error);

}  // namespace rdtf::daemon
