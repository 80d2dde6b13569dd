// The LCM URL of a config, checked before anything is opened with it.
#pragma once

#include <string>

namespace rdtf::daemon {

// True when `url` ("" = LCM's default) is one LCM can use as the user meant it. LCM 1.3 itself
// refuses an unknown provider or an unusable address, but only warns on stderr, and carries on
// with a default, for a misspelt or invalid option: "udpm://239.255.76.67:7667?tll=1" (or
// "ttl=one") ran with TTL 0, and no controller on another host ever heard rdtfd. So for udpm the
// network must be empty (LCM's default group and port) or an IPv4 multicast group with a port
// 1..65535, and each option one LCM reads (ttl 0..255, recv_buf_size a positive byte count), all
// numbers in decimal without a leading 0 (LCM reads 0... as octal, 0x... as hexadecimal). Other providers (memq, file, tcpq, mpudpm)
// are passed to LCM as they are. On false, `error` says which part is wrong and why.
// `setting` names where the URL came from in `error` (the config's lcm_url, or LCM_DEFAULT_URL).
bool check_lcm_url(const std::string& url, std::string& error, const char* setting = "lcm_url");

}  // namespace rdtf::daemon
