#include "lcm_ready.h"

#include <lcm/lcm-cpp.hpp>

namespace rdtf::lcm_safe {
namespace {

void ignore(const lcm_recv_buf_t*, const char*, void*) {}

std::string where(const std::string& url) {
  return url.empty() ? std::string("LCM's default URL") : "'" + url + "'";
}

}  // namespace

std::string lcm_receive_problem(lcm::LCM& lcm, const std::string& url) {
  // errno is not the reason here: LCM's clean-up after the failing call has replaced it. LCM
  // prints the call that failed and why on stderr just before.
  if (!lcm.good()) return "cannot open LCM at " + where(url) + " (LCM's message above says why)";
  // A channel nothing publishes on; the probe's handler is never called and is dropped at once.
  lcm_subscription_t* probe = lcm_subscribe(lcm.getUnderlyingLCM(), "rdtf-receive-probe", ignore, nullptr);
  if (probe == nullptr) {
    return "cannot receive on LCM at " + where(url) +
           ": its receive socket or thread could not be made (LCM's message above says why)";
  }
  lcm_unsubscribe(lcm.getUnderlyingLCM(), probe);
  return {};
}

}  // namespace rdtf::lcm_safe
