// rdtfd and the rdtf clients against a hostile bus (docs/security.md): datagrams crafted byte by
// byte and sent over a plain UDP socket to LCM's multicast group, inside the test's own network
// namespace (harness.h). Malformed messages (lengths of 0, negative, or far beyond the datagram)
// are dropped, counted in STATUS and logged once a second; liblcm's fragment reassembly refuses a
// fragment whose offset wraps 32 bits; the requester field reaches the log escaped; a request flood
// is answered once per second and model; a huge but finite joint command never makes the live
// simulation publish a non-finite value or stop; a live simulation that cannot keep real time says
// so in STATUS and the log.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cmath>
#include <limits>

#include <rdtf/link_state_t.hpp>

#include "clients/live_arm.h"

namespace rdtf::itest {
namespace {

// Big-endian fields as LCM encodes them.
struct Bytes {
  std::vector<std::uint8_t> data;
  Bytes& u(std::uint64_t value, int width) {
    for (int k = width - 1; k >= 0; --k) data.push_back(static_cast<std::uint8_t>(value >> (8 * k)));
    return *this;
  }
  Bytes& i64(std::int64_t v) { return u(static_cast<std::uint64_t>(v), 8); }
  Bytes& i32(std::int32_t v) { return u(static_cast<std::uint32_t>(v), 4); }
  Bytes& f64(double v) {
    std::uint64_t bits;
    std::memcpy(&bits, &v, 8);
    return u(bits, 8);
  }
  // An LCM string: its length with the NUL, the bytes, the NUL.
  Bytes& str(const std::string& s) {
    i32(static_cast<std::int32_t>(s.size() + 1));
    data.insert(data.end(), s.begin(), s.end());
    data.push_back(0);
    return *this;
  }
  Bytes& raw(const std::string& s) {
    data.insert(data.end(), s.begin(), s.end());
    return *this;
  }
};

// A UDP socket sending to LCM's default group (udpm://239.255.76.67:7667), multicast looped back.
class RawSender {
 public:
  RawSender() {
    fd_ = ::socket(AF_INET, SOCK_DGRAM, 0);
    if (fd_ < 0) throw std::runtime_error("socket failed");
    const unsigned char ttl = 0, loop = 1;
    ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_TTL, &ttl, sizeof(ttl));
    ::setsockopt(fd_, IPPROTO_IP, IP_MULTICAST_LOOP, &loop, sizeof(loop));
    to_.sin_family = AF_INET;
    to_.sin_port = htons(7667);
    ::inet_pton(AF_INET, "239.255.76.67", &to_.sin_addr);
  }
  ~RawSender() { ::close(fd_); }
  void send(const std::vector<std::uint8_t>& datagram) const {
    if (::sendto(fd_, datagram.data(), datagram.size(), 0, reinterpret_cast<const sockaddr*>(&to_), sizeof(to_)) !=
        static_cast<ssize_t>(datagram.size())) {
      throw std::runtime_error("sendto failed");
    }
  }
  // One LCM datagram with the short header: magic "LC02", sequence number, channel, payload.
  std::vector<std::uint8_t> short_message(const std::string& channel, const Bytes& payload) {
    Bytes d;
    d.u(0x4c433032, 4).u(sequence_++, 4).raw(channel).u(0, 1);
    d.data.insert(d.data.end(), payload.data.begin(), payload.data.end());
    return d.data;
  }
  // One fragment with the long header: magic "LC03", sequence, message size, fragment offset,
  // fragment number and count; fragment 0 carries the channel.
  static std::vector<std::uint8_t> fragment(std::uint32_t sequence, std::uint32_t message_size, std::uint32_t offset,
                                            std::uint16_t number, std::uint16_t count, const std::string& channel,
                                            std::size_t data_bytes) {
    Bytes d;
    d.u(0x4c433033, 4).u(sequence, 4).u(message_size, 4).u(offset, 4).u(number, 2).u(count, 2);
    if (number == 0) d.raw(channel).u(0, 1);
    d.data.insert(d.data.end(), data_bytes, 0x41);
    return d.data;
  }

 private:
  int fd_ = -1;
  sockaddr_in to_{};
  std::uint32_t sequence_ = 1;
};

Bytes request_head() { return Bytes().i64(rdtf::request_t::getHash()).i64(0); }
Bytes command_head(const std::string& hash) {
  return Bytes().i64(rdtf::joint_command_t::getHash()).i64(0).str(kArm).i64(1).str(hash);
}

std::int64_t dropped(const std::vector<Message>& all) {
  const auto s = statuses(all);
  return s.empty() ? 0 : s.back().dropped_messages;
}

// The daemon's own uptime in its newest STATUS: how long it has run, by its clock.
double uptime(const std::vector<Message>& all) {
  const auto s = statuses(all);
  return s.empty() ? 0 : s.back().uptime;
}

std::size_t count_lines(const std::string& log, const std::string& text) {
  std::size_t n = 0;
  for (std::size_t at = log.find(text); at != std::string::npos; at = log.find(text, at + 1)) ++n;
  return n;
}

// A request answered: a DESCRIPTION of arm3 after `from` messages.
bool answered(Session& s, std::size_t from) {
  return s.wait_for([&](const auto& all) {
    for (std::size_t i = from; i < all.size(); ++i) {
      if (all[i].kind() == "DESCRIPTION" && all[i].model_id() == kArm) return true;
    }
    return false;
  });
}

void request_all(Session& s, const std::string& requester) {
  rdtf::request_t request;
  request.requester = requester;
  s.subscriber.publish("RDTF/REQUEST", request);
}

TEST(HostileBus, MalformedDatagramsAreDroppedCountedAndLoggedNotFatal) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start();
  ASSERT_TRUE(s.wait_revision(kArm, 1, fixture_hash("arm3")));
  RawSender sender;
  const std::string hash = fixture_hash("arm3");
  std::vector<std::vector<std::uint8_t>> datagrams;
  // request_t: model_id of length 0 (lcm-gen: assign(p, -1)), negative, and a requester of 0.
  datagrams.push_back(sender.short_message("RDTF/REQUEST", request_head().i32(0).str("x")));
  datagrams.push_back(sender.short_message("RDTF/REQUEST", request_head().i32(-5).str("x")));
  datagrams.push_back(sender.short_message("RDTF/REQUEST", request_head().str("").i32(0)));
  // joint_command_t: num_joints -1 and 2^31-1 (resize before any check), a name of length 0.
  const std::string channel = "RDTF/arm3.gltf/JOINT_COMMAND";
  datagrams.push_back(sender.short_message(channel, command_head(hash).i32(-1)));
  datagrams.push_back(sender.short_message(channel, command_head(hash).i32(std::numeric_limits<std::int32_t>::max())));
  datagrams.push_back(sender.short_message(channel, command_head(hash).i32(1).i32(0)));
  // num_joints 100,000,000 in a 111-byte datagram (3.1 GB and a 7 s stall before).
  Bytes padded = Bytes().i64(rdtf::joint_command_t::getHash()).i64(0).str(kArm).i64(1);
  const std::size_t header = 8 + channel.size() + 1;
  padded.str(std::string(111 - header - padded.data.size() - 4 - 1 - 4, 'h')).i32(100000000);
  datagrams.push_back(sender.short_message(channel, padded));
  ASSERT_EQ(datagrams.back().size(), 111u);
  for (const auto& d : datagrams) sender.send(d);

  const auto sent = static_cast<std::int64_t>(datagrams.size());
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return dropped(all) >= sent; }))
      << "STATUS counts " << dropped(s.messages()) << " dropped of " << sent;
  EXPECT_EQ(dropped(s.messages()), sent);
  ASSERT_TRUE(s.daemon->running());
  const std::string log = s.daemon->log();
  EXPECT_NE(log.find(" from the bus ("), std::string::npos) << log;
  EXPECT_NE(log.find("request_t: model_id: string length 0"), std::string::npos) << log;
  // Still serving: a valid request is answered.
  const std::size_t from = s.messages().size();
  request_all(s, "itest");
  EXPECT_TRUE(answered(s, from));
}

TEST(HostileBus, FloodOfMalformedDatagramsIsLoggedOnceASecond) {
  Session s;
  s.start();
  RawSender sender;
  const int kCount = 3000;
  for (int k = 0; k < kCount; ++k) sender.send(sender.short_message("RDTF/REQUEST", request_head().i32(0)));
  // Not every datagram need arrive (the socket buffer, LCM's queue of 30 per subscription); every
  // one that did is counted. A request right after the flood may meet a full queue: sent again
  // until the daemon answers.
  ASSERT_TRUE(wait_until(
      [&] {
        request_all(s, "after the flood");
        return s.daemon->wait_log("on request of 'after the flood'", 200ms);
      },
      20s));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return dropped(all) > 0; }));
  const auto all = s.messages();
  const std::string log = s.daemon->log();
  const std::size_t lines = count_lines(log, " from the bus (");
  std::printf("%lld of %d malformed datagrams counted; %zu log lines over %.2f s of the daemon's uptime\n",
              static_cast<long long>(dropped(all)), kCount, lines, uptime(all));
  EXPECT_LE(dropped(all), kCount);
  EXPECT_GE(lines, 1u) << log;
  // One line for the first drop, then at most one per second of the daemon's run.
  EXPECT_LE(static_cast<double>(lines), 1 + std::ceil(uptime(all)));
}

TEST(HostileBus, FragmentWhoseOffsetWraps32BitsIsRefusedByLiblcm) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start();
  ASSERT_TRUE(s.wait_revision(kArm, 1, fixture_hash("arm3")));
  ChildProcess echo({RDTF_ECHO_PATH, "--omit-documents"}, s.root / "echo.out");
  // rdtf-echo listens once it prints the heartbeat.
  ASSERT_TRUE(wait_until([&] { return echo.output().find("RDTF/STATUS") != std::string::npos; }, 10s));
  RawSender sender;
  // Fragment 0 of a 1000-byte message on a subscribed channel, then one at offset 0xfffffff0:
  // 0xfffffff0 + 100 wraps to 84 < 1000 in liblcm 1.3.1's check, and its memcpy wrote 100 bytes
  // at fbuf->data + 0xfffffff0 (pointer arithmetic on a 64-bit host: about 4 GiB past the buffer,
  // SIGSEGV). Both processes: rdtfd and rdtf-echo subscribe to RDTF/REQUEST.
  for (int round = 0; round < 3; ++round) {
    const auto seq = static_cast<std::uint32_t>(100 + round);
    sender.send(RawSender::fragment(seq, 1000, 0, 0, 2, "RDTF/REQUEST", 100));
    sender.send(RawSender::fragment(seq, 1000, 0xfffffff0u, 1, 2, "", 100));
    // Shorter than the long header; a fragment count of 0.
    sender.send({0x4c, 0x43, 0x30, 0x33, 0, 0, 0, 1, 0, 0});
    sender.send(RawSender::fragment(seq + 10, 1000, 0, 0, 0, "RDTF/REQUEST", 10));
    // A channel longer than the datagram: fragment 0 ends inside its channel name, whose NUL
    // liblcm's strlen finds in the stale zeros a bad-magic datagram left in the receive buffer.
    sender.send(std::vector<std::uint8_t>(64, 0));
    auto cut = RawSender::fragment(seq + 20, 1000, 0, 0, 2, "RDTF/REQUEST", 0);
    cut.pop_back();  // the NUL
    sender.send(cut);
  }
  // rdtfd still answers; rdtf-echo still prints.
  const std::size_t from = s.messages().size();
  request_all(s, "after the fragments");
  EXPECT_TRUE(answered(s, from)) << [&] {
    std::string kinds;
    const auto all = s.messages();
    for (std::size_t i = from; i < all.size(); ++i) kinds += all[i].channel + " ";
    return kinds;
  }();
  EXPECT_TRUE(s.daemon->running());
  EXPECT_TRUE(wait_until([&] { return echo.output().find("after the fragments") != std::string::npos; }, 5s))
      << echo.output();
  EXPECT_FALSE(echo.wait_exit(0s).has_value()) << "rdtf-echo exited:\n" << echo.output();
}

// liblcm 1.3.1 takes the subscriber's queue slot (lcm_try_enqueue_message) before the patched
// check that the channel name ends inside the datagram: a return after it leaked the slot, and
// 31 such datagrams left RDTF/REQUEST's queue (30) full for good, every later request dropped.
// Each one: a bad-magic datagram with a zero at byte 20, then the 20 bytes "LC02", sequence,
// "RDTF/REQUEST" with no NUL (liblcm reuses the buffer after bad magic; strlen finds the zero).
TEST(HostileBus, ChannelNamesPastTheDatagramNeverLeaveTheDaemonDeaf) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start();
  ASSERT_TRUE(s.wait_revision(kArm, 1, fixture_hash("arm3")));
  RawSender sender;
  const int kPairs = 100;
  for (int k = 0; k < kPairs; ++k) {
    sender.send(std::vector<std::uint8_t>(32, 0));
    auto cut = sender.short_message("RDTF/REQUEST", Bytes());
    cut.pop_back();  // the channel's NUL
    ASSERT_EQ(cut.size(), 20u);
    sender.send(cut);
  }
  // A request sent after them is answered. Resent until answered (UDP may drop one), but a deaf
  // subscription drops every one: the deadline ends the test.
  const std::size_t from = s.messages().size();
  ASSERT_TRUE(wait_until(
      [&] {
        request_all(s, "after the cut channels");
        return s.daemon->wait_log("on request of 'after the cut channels'", 500ms);
      },
      10s))
      << s.daemon->log();
  EXPECT_TRUE(answered(s, from));
  EXPECT_TRUE(s.daemon->running());
}

TEST(HostileBus, RequesterIsEscapedInTheLog) {
  Session s;
  s.start();
  request_all(s, "mallory\n2030-01-01T00:00:00.000Z rdtfd stopped\x1b[2J");
  ASSERT_TRUE(s.daemon->wait_log("on request of 'mallory"));
  const std::string log = s.daemon->log();
  EXPECT_NE(log.find("on request of 'mallory\\n2030-01-01T00:00:00.000Z rdtfd stopped\\x1b[2J'"), std::string::npos)
      << log;
  EXPECT_EQ(log.find("\n2030-01-01"), std::string::npos) << log;
}

TEST(HostileBus, RequestFloodIsAnsweredOncePerSecondWithStatusOnTime) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start();
  ASSERT_TRUE(s.wait_revision(kArm, 1, fixture_hash("arm3")));
  const std::size_t from = s.messages().size();
  const int kRequests = 5000;
  for (int k = 0; k < kRequests; ++k) request_all(s, "flood");
  // Every request is either answered or answered together with others (coalesced).
  ASSERT_TRUE(s.wait_for(
      [&](const auto& all) {
        const auto st = statuses(all);
        return !st.empty() && st.back().coalesced_requests > 0 && st.back().pending == 0;
      },
      20s));
  ASSERT_TRUE(s.wait_idle());
  const auto all = s.messages();
  std::size_t descriptions = 0;
  std::size_t statuses_during = 0;
  std::int64_t most_queued = 0;
  for (std::size_t i = from; i < all.size(); ++i) {
    if (all[i].kind() == "DESCRIPTION") ++descriptions;
    if (all[i].kind() == "STATUS") {
      ++statuses_during;
      most_queued = std::max(most_queued, all[i].as<rdtf::status_t>().send_queue_bytes);
    }
  }
  const auto last = statuses(all).back();
  std::printf("%d requests: %zu descriptions, %lld coalesced, %zu STATUS, most queued %lld bytes\n", kRequests,
              descriptions, static_cast<long long>(last.coalesced_requests), statuses_during,
              static_cast<long long>(most_queued));
  // Answers: one per second of the daemon's clock (STATUS every 100 ms: ten per answer), plus the
  // first and the one deferred to the end of its period.
  EXPECT_LE(static_cast<double>(descriptions), 2 + static_cast<double>(statuses_during) / 10.0);
  EXPECT_GE(last.coalesced_requests, 1);
  // The queue never held more than a few descriptions (each well under 64 KiB here).
  EXPECT_LT(most_queued, 1 << 20);
}

// Waits until model revision 1's JOINT_STATE reports a simulated time past `t` (s).
bool wait_sim_time_past(Session& s, double t) {
  return s.wait_for(
      [&](const auto& all) {
        const auto last = last_state(all, 1);
        return last && last->sim_time > t;
      },
      20s);
}

DaemonOptions simulating() { return DaemonOptions().with("simulate", true).with("state_rate_hz", 100); }

bool all_finite(const rdtf::joint_state_t& s) {
  for (const auto* v : {&s.position, &s.velocity, &s.effort}) {
    for (double x : *v) {
      if (!std::isfinite(x)) return false;
    }
  }
  return std::isfinite(s.sim_time);
}

TEST(HostileBus, HugeFiniteCommandsNeverStopTheSimulationNorPublishNonFiniteValues) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating());
  const std::string hash = fixture_hash("arm3");
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return last_state(all, 1).has_value(); }));
  const std::vector<JointOrder> huge_torque{{"shoulder", rdtf::joint_command_t::TORQUE, 1e300},
                                            {"elbow", rdtf::joint_command_t::TORQUE, -1e300}};
  const std::vector<JointOrder> huge_position{{"shoulder", rdtf::joint_command_t::POSITION, 1e308, 1e308, 1e308},
                                              {"elbow", rdtf::joint_command_t::POSITION, -1e308, 1e308, 0}};
  for (const auto& orders : {huge_torque, huge_position}) {
    const std::size_t from = s.messages().size();
    s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND", make_command(kArm, 1, hash, orders));
    // Two seconds of simulated time after the command.
    const double t0 = last_state(s.messages(), 1)->sim_time;
    ASSERT_TRUE(wait_sim_time_past(s, t0 + 2.0)) << "simulated time stopped";
    const auto all = s.messages();
    double previous = -1;
    for (std::size_t i = from; i < all.size(); ++i) {
      if (all[i].kind() == "JOINT_STATE") {
        const auto state = all[i].as<rdtf::joint_state_t>();
        EXPECT_TRUE(all_finite(state)) << "non-finite JOINT_STATE at t = " << state.sim_time;
        EXPECT_GT(state.sim_time, previous);
        previous = state.sim_time;
        for (double e : state.effort) EXPECT_LE(std::abs(e), rdtf::kDefaultEffortLimit);
      }
      if (all[i].kind() == "LINK_STATE") {
        const auto links = all[i].as<rdtf::link_state_t>();
        for (const auto* rows : {&links.position, &links.linear_velocity, &links.angular_velocity}) {
          for (const auto& row : *rows) {
            for (double x : row) EXPECT_TRUE(std::isfinite(x));
          }
        }
      }
    }
  }
  // Whether ODE failed under the clamped effort or not, the daemon reported every failure it had
  // and kept stepping: each failure is on ERROR, in the log and counted in STATUS.
  const auto failures_on_error = [](const std::vector<Message>& all) {
    std::int64_t failures = 0;
    for (const auto& e : decoded<rdtf::model_error_t>(all, "ERROR", kArm)) {
      failures += !e.diagnostics.empty() && e.diagnostics[0].code == "SIMULATION_FAILED";
    }
    return failures;
  };
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    const auto st = statuses(all);
    return !st.empty() && st.back().simulations_failed == failures_on_error(all);
  })) << "STATUS counts " << statuses(s.messages()).back().simulations_failed << " failures, ERROR "
      << failures_on_error(s.messages());
  const std::int64_t failures = failures_on_error(s.messages());
  std::printf("simulation failures reported: %lld\n", static_cast<long long>(failures));
  EXPECT_EQ(count_lines(s.daemon->log(), "restarted from the rest pose") > 0, failures > 0);
}

// A command is queued for the simulation thread only when it fits one datagram (64 KiB) and has
// at most twice the model's joints plus 16: the queue's bound by count then bounds its bytes. One
// with more is rejected on ERROR all the same, not dropped in silence; one within the bound that
// names a joint twice is rejected naming it, whatever its count (s90ctrl D6). A rejection's ERROR carries the bus's text escaped and cut, and the live
// model's content hash.
TEST(HostileBus, OversizedCommandsAreDroppedAndRejectionsCarryNoBusBytes) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating());
  const std::string hash = fixture_hash("arm3");
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return last_state(all, 1).has_value(); }));
  const std::int64_t dropped_before = dropped(s.messages());
  // 70,000 bytes of content hash (LCM sends it in fragments); four joints for arm3's three.
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, std::string(70000, 'h'), {{"shoulder", rdtf::joint_command_t::TORQUE, 1}}));
  std::vector<JointOrder> many;
  for (int i = 0; i < 40; ++i) many.push_back({"j" + std::to_string(i), rdtf::joint_command_t::TORQUE, 1});
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND", make_command(kArm, 1, hash, many));
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash,
                                    {{"shoulder", rdtf::joint_command_t::TORQUE, 1},
                                     {"elbow", rdtf::joint_command_t::TORQUE, 1},
                                     {"shoulder", rdtf::joint_command_t::TORQUE, 1}}));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return dropped(all) >= dropped_before + 1; }))
      << "STATUS counts " << dropped(s.messages()) - dropped_before << " dropped of 1";
  ASSERT_TRUE(s.daemon->wait_log("above rdtfd's input limit of 65536")) << s.daemon->log();
  const auto over_count = [](const std::vector<Message>& all) {
    for (const auto& e : decoded<rdtf::model_error_t>(all, "ERROR", kArm)) {
      if (!e.diagnostics.empty() && e.diagnostics[0].code == "COMMAND_REJECTED" &&
          e.diagnostics[0].message.find("command names 40 joints, but the model has ") != std::string::npos) {
        return true;
      }
    }
    return false;
  };
  ASSERT_TRUE(s.wait_for(over_count)) << "no COMMAND_REJECTED for the command with 40 joints";
  const auto named_twice = [](const std::vector<Message>& all) {
    for (const auto& e : decoded<rdtf::model_error_t>(all, "ERROR", kArm)) {
      if (!e.diagnostics.empty() &&
          e.diagnostics[0].message.find("joint 'shoulder' is named twice in one command (entries 0 'shoulder' and 2)") !=
              std::string::npos) {
        return true;
      }
    }
    return false;
  };
  ASSERT_TRUE(s.wait_for(named_twice)) << "no COMMAND_REJECTED naming the joint named twice in three entries";
  // 30,000 bytes of hash with control bytes, in one datagram: rejected, the text escaped and cut.
  std::string bad_hash(30000, 'x');
  bad_hash[10] = '\n';
  bad_hash[11] = '\x1b';
  const std::size_t from = s.messages().size();
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, bad_hash, {{"shoulder", rdtf::joint_command_t::TORQUE, 1}}));
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    return !rejections(std::vector<Message>(all.begin() + static_cast<std::ptrdiff_t>(from), all.end())).empty();
  }));
  const auto all = s.messages();
  const auto errors = decoded<rdtf::model_error_t>(std::vector<Message>(all.begin() + static_cast<std::ptrdiff_t>(from), all.end()),
                                                   "ERROR", kArm);
  ASSERT_FALSE(errors.empty());
  const auto& error = errors.front();
  EXPECT_EQ(error.content_hash, hash);
  ASSERT_EQ(error.diagnostics.size(), 1u);
  const std::string& text = error.diagnostics[0].message;
  EXPECT_LT(text.size(), 400u) << text;
  EXPECT_EQ(text.find('\n'), std::string::npos) << text;
  EXPECT_EQ(text.find('\x1b'), std::string::npos) << text;
  EXPECT_NE(text.find("xx\\x0a\\x1bxx"), std::string::npos) << text;
  EXPECT_TRUE(s.daemon->running());
}

// arm3 whose two joints have an authored effort limit of 1e120: a torque command of 1e120 gets
// through the clamp and blows the simulation up (1e117 rad/s after one step, beyond the 1e100 ODE
// may step), so a restart is certain, not left to chance.
TEST(HostileBus, ABlownUpLiveSimulationIsReportedAndRestartedAfterItsBackOff) {
  Session s;
  copy_fixture(s.watch, "arm3");
  Json document = Json::parse(read(s.watch / "arm3.gltf"));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "shoulder" || node.value("name", "") == "elbow") node["extras"]["rdtf_effort"] = 1e120;
  }
  const std::string gltf = document.dump(1);
  write_in_place(s.watch / "arm3.gltf", gltf);
  const std::string hash = content_hash(gltf, {read(s.watch / "arm3.bin")});
  s.start(simulating());
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return last_state(all, 1).has_value(); }));
  const auto failures_on_error = [](const std::vector<Message>& all) {
    std::int64_t failures = 0;
    for (const auto& e : decoded<rdtf::model_error_t>(all, "ERROR", kArm)) {
      failures += !e.diagnostics.empty() && e.diagnostics[0].code == "SIMULATION_FAILED";
    }
    return failures;
  };
  const std::size_t from = s.messages().size();
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash, {{"shoulder", rdtf::joint_command_t::TORQUE, 1e120}}));
  ASSERT_TRUE(s.wait_for([&](const auto& all) { return failures_on_error(all) >= 1; })) << s.daemon->log();
  ASSERT_TRUE(s.daemon->wait_log("restarts from the rest pose in 100 ms (failure 1 in a row)")) << s.daemon->log();
  // STATUS counts what ERROR reported (commands are cleared on restart: this one failure).
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    const auto st = statuses(all);
    return !st.empty() && st.back().simulations_failed == failures_on_error(all);
  }));
  EXPECT_EQ(failures_on_error(s.messages()), 1);
  // After the restart simulated time goes on, and every state published since the command is
  // finite and within what may be stepped: the exploded step went out in neither message.
  const double t_failed = last_state(s.messages(), 1)->sim_time;
  ASSERT_TRUE(wait_sim_time_past(s, t_failed + 0.5)) << "simulated time stopped after the failure";
  const auto all = s.messages();
  for (std::size_t i = from; i < all.size(); ++i) {
    if (all[i].kind() == "JOINT_STATE") {
      const auto state = all[i].as<rdtf::joint_state_t>();
      for (const auto* values : {&state.position, &state.velocity, &state.effort}) {
        for (double x : *values) EXPECT_TRUE(std::isfinite(x) && std::abs(x) <= 1e100) << x << " at t = " << state.sim_time;
      }
    }
    if (all[i].kind() == "LINK_STATE") {
      const auto links = all[i].as<rdtf::link_state_t>();
      for (const auto* rows : {&links.position, &links.linear_velocity, &links.angular_velocity}) {
        for (const auto& row : *rows) {
          for (double x : row) EXPECT_TRUE(std::isfinite(x) && std::abs(x) <= 1e100) << x;
        }
      }
    }
  }
  EXPECT_TRUE(s.daemon->running());
}

TEST(HostileBus, LiveSimulationThatCannotKeepRealTimeSaysSo) {
  Session s;
  copy_fixture(s.watch, "arm3");
  // 100 simulated seconds per wall second (the highest real_time_factor allowed) at 0.1 ms steps
  // (the smallest time_step allowed): a million steps a second, about five times what one core
  // steps arm3 at.
  s.start(simulating().with("real_time_factor", 100.0).with("time_step", 1e-4).with("state_rate_hz", 100));
  ASSERT_TRUE(s.wait_revision(kArm, 1, fixture_hash("arm3")));
  ASSERT_TRUE(s.wait_for(
      [](const auto& all) {
        const auto st = statuses(all);
        return !st.empty() && st.back().simulations_behind == 1;
      },
      10s));
  const auto st = statuses(s.messages()).back();
  EXPECT_GT(st.live_real_time_factor, 0);
  EXPECT_LT(st.live_real_time_factor, 0.9 * 100);
  EXPECT_TRUE(s.daemon->wait_log("live simulation of arm3.gltf is behind")) << s.daemon->log();
}

}  // namespace
}  // namespace rdtf::itest
