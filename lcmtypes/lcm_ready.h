// Whether an lcm::LCM can receive. lcm::LCM::good() says only that LCM was made: udpm makes its
// receive socket and thread at the first subscribe, and when that fails (the process is out of
// descriptors) LCM's C++ subscribe still hands back a Subscription with no C subscription behind
// it. A program then ran deaf (rdtfd answered no request and took no joint command) or crashed on
// it (rdtf-view's setQueueCapacity on a null subscription). Every rdtf program that subscribes
// asks this first and refuses to start with the reason.
#pragma once

#include <string>

namespace lcm {
class LCM;
}

namespace rdtf::lcm_safe {

// Empty when `lcm` is open and can receive; else what is wrong, naming `url` ("" is LCM's default
// URL); the system's reason is on stderr already, from LCM. Makes and drops one subscription: the receive side it sets up
// stays for the program's own subscribes.
std::string lcm_receive_problem(lcm::LCM& lcm, const std::string& url);

}  // namespace rdtf::lcm_safe
