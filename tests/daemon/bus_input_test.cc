// The pieces of rdtfd's bus input without a network: the schema check of every rdtf type (parsed
// from lcmtypes/*.lcm), the escaping of bus strings for the log, the request throttle, the
// publisher's byte bound and urgent queue, the live simulations' CPU budget, and the clamp of
// commanded efforts.
#include <algorithm>
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/joint_command_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "bus_input.h"
#include "publisher.h"
#include "safe_decode.h"
#include "simulation_host.h"

namespace rdtf::daemon {
namespace {

using namespace std::chrono_literals;

template <typename T>
std::vector<std::uint8_t> encode(const T& message) {
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

rdtf::joint_command_t two_joint_command() {
  rdtf::joint_command_t c;
  c.model_id = "arm3.gltf";
  c.revision = 1;
  c.content_hash = "abc";
  c.num_joints = 2;
  c.name = {"shoulder", "elbow"};
  c.mode = {0, 1};
  c.value = {0.5, 1.0};
  c.kp = {0, 10};
  c.kd = {0, 1};
  return c;
}

TEST(SafeDecode, EveryRdtfTypeRoundTripsThroughTheSchemaCheck) {
  // Non-empty arrays of nested types, multi-dimensional arrays and strings.
  rdtf::model_error_t error;
  error.model_id = "m";
  error.diagnostics.resize(2);
  error.diagnostics[1].message = "second";
  error.num_diagnostics = 2;
  rdtf::inertia_table_t table;
  table.links.resize(3);
  table.num_links = 3;
  rdtf::link_state_t links;
  links.num_links = 2;
  links.name = {"a", "b"};
  links.gltf_name = {"a", "b"};
  links.position = {{1, 2, 3}, {4, 5, 6}};
  links.orientation = {{1, 0, 0, 0}, {1, 0, 0, 0}};
  links.linear_velocity = links.position;
  links.angular_velocity = links.position;
  rdtf::status_t status;
  status.model_ids = {"x", "y"};
  status.num_model_ids = 2;
  const std::vector<std::pair<std::string, std::vector<std::uint8_t>>> cases = {
      {"model_error_t", encode(error)},         {"inertia_table_t", encode(table)},
      {"link_state_t", encode(links)},          {"status_t", encode(status)},
      {"joint_command_t", encode(two_joint_command())}, {"description_t", encode(rdtf::description_t{})},
      {"validation_report_t", encode(rdtf::validation_report_t{})}, {"request_t", encode(rdtf::request_t{})}};
  for (const auto& [type, bytes] : cases) {
    EXPECT_EQ(lcm_safe::type_of(bytes.data(), bytes.size()), type);
    EXPECT_EQ(lcm_safe::check_known(bytes.data(), bytes.size()), "") << type;
    // One byte short, or one too many: refused.
    EXPECT_NE(lcm_safe::check_known(bytes.data(), bytes.size() - 1), "") << type;
    auto longer = bytes;
    longer.push_back(0);
    EXPECT_NE(lcm_safe::check_known(longer.data(), longer.size()), "") << type;
  }
  std::string why;
  const auto bytes = encode(two_joint_command());
  const auto decoded = lcm_safe::decode<rdtf::joint_command_t>(bytes.data(), bytes.size(), why);
  ASSERT_TRUE(decoded) << why;
  EXPECT_EQ(decoded->name, two_joint_command().name);
  EXPECT_EQ(decoded->kp, two_joint_command().kp);
}

// The bytes of `message` with the 4 bytes at `offset` replaced by `value` (big endian).
template <typename T>
std::vector<std::uint8_t> with_int32(const T& message, std::size_t offset, std::int32_t value) {
  auto bytes = encode(message);
  for (int k = 0; k < 4; ++k) bytes[offset + k] = static_cast<std::uint8_t>(static_cast<std::uint32_t>(value) >> (24 - 8 * k));
  return bytes;
}

TEST(SafeDecode, LengthsThatDoNotFitTheBytesLeftAreRefusedBeforeDecoding) {
  // joint_command_t: hash 8, utime 8, model_id 4+10, revision 8, content_hash 4+4, num_joints at 46.
  const auto command = two_joint_command();
  const std::size_t num_joints_at = 8 + 8 + 4 + 10 + 8 + 4 + 4;
  for (std::int32_t n : {-1, 3, 1000, 100000000, std::numeric_limits<std::int32_t>::max(),
                         std::numeric_limits<std::int32_t>::min()}) {
    const auto bytes = with_int32(command, num_joints_at, n);
    std::string why;
    EXPECT_FALSE(lcm_safe::decode<rdtf::joint_command_t>(bytes.data(), bytes.size(), why)) << n;
    EXPECT_NE(why.find("name"), std::string::npos) << why;
  }
  // request_t: model_id's length at 16: 0 (lcm-gen's assign(p, -1)), negative, past the end.
  rdtf::request_t request;
  request.model_id = "abc";
  for (std::int32_t n : {0, -1, -2147483647 - 1, 10, 1 << 30}) {
    const auto bytes = with_int32(request, 16, n);
    std::string why;
    EXPECT_FALSE(lcm_safe::decode<rdtf::request_t>(bytes.data(), bytes.size(), why)) << n;
    EXPECT_NE(why.find("model_id: string length"), std::string::npos) << why;
  }
  // A string without its NUL; another type's fingerprint; too short for one.
  auto bytes = encode(request);
  bytes[16 + 4 + 3] = 'x';
  std::string why;
  EXPECT_FALSE(lcm_safe::decode<rdtf::request_t>(bytes.data(), bytes.size(), why));
  EXPECT_NE(why.find("NUL"), std::string::npos) << why;
  // A NUL inside a string: lcm-gen keeps it, its encoder cuts there (a controller that sent such a
  // joint name back sent a message whose lengths do not match; found by the bus fuzz target).
  rdtf::request_t inner;
  inner.model_id = std::string("ab\0c", 4);
  bytes = encode(inner);
  EXPECT_FALSE(lcm_safe::decode<rdtf::request_t>(bytes.data(), bytes.size(), why));
  const auto status = encode(rdtf::status_t{});
  EXPECT_FALSE(lcm_safe::decode<rdtf::request_t>(status.data(), status.size(), why));
  EXPECT_FALSE(lcm_safe::decode<rdtf::request_t>(status.data(), 7, why));
}

TEST(SafeDecode, BusStringsArePrintableAndBoundedInTheLog) {
  EXPECT_EQ(lcm_safe::printable("plain text 1.0"), "plain text 1.0");
  EXPECT_EQ(lcm_safe::printable(std::string("a\nb\\c\x1b\0", 7)), "a\\x0ab\\\\c\\x1b\\x00");
  EXPECT_EQ(lcm_safe::printable(std::string(300, 'x'), 4), "xxxx...(300 bytes)");
}

TEST(SafeDecode, DropsAreLoggedAtMostOnceAPeriodWithTheirCount) {
  lcm_safe::DropCounter drops(1s);
  const auto t0 = std::chrono::steady_clock::now();
  ASSERT_TRUE(drops.drop("RDTF/REQUEST", "why", t0));
  for (int k = 0; k < 100; ++k) EXPECT_FALSE(drops.drop("RDTF/REQUEST", "why", t0 + 10ms));
  const auto line = drops.drop("RDTF/X\n", "again", t0 + 1s);
  ASSERT_TRUE(line);
  EXPECT_NE(line->find("dropped 101 messages from the bus (102 since start)"), std::string::npos) << *line;
  EXPECT_NE(line->find("RDTF/X\\x0a"), std::string::npos) << *line;
  EXPECT_EQ(drops.total(), 102u);
  // The reason holds bus text printable() made already (a blob requester's bytes): its
  // backslashes stay single, so a requester's byte 0xff reads "\\xff" in the log, not
  // "\\\\xff"; a raw byte in it is still escaped, and the line stays printable ASCII.
  lcm_safe::DropCounter again(1s);
  const auto kept = again.drop("RDTF/BLOB_REQUEST",
                               "blob request from '" + lcm_safe::printable("\xff\xfe") + "': raw \x1b" + std::string(300, 'x'), t0);
  ASSERT_TRUE(kept);
  EXPECT_NE(kept->find("latest on RDTF/BLOB_REQUEST: blob request from '\\xff\\xfe': raw \\x1bxxx"), std::string::npos) << *kept;
  EXPECT_NE(kept->find("...(335 bytes)"), std::string::npos) << *kept;
  EXPECT_TRUE(std::all_of(kept->begin(), kept->end(), [](char c) { return c >= 0x20 && c < 0x7f; })) << *kept;
}

// A burst that ends within its period is logged once the period is over, not only when the next
// drop comes (which may be never): flush() gives its line, with the latest drop's channel and reason.
TEST(SafeDecode, TheEndOfABurstIsLoggedOnceItsPeriodIsOver) {
  lcm_safe::DropCounter drops(1s);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_FALSE(drops.flush(t0));  // nothing dropped
  ASSERT_TRUE(drops.drop("RDTF/REQUEST", "first", t0));
  EXPECT_FALSE(drops.flush(t0 + 2s));  // the first drop was logged at once: nothing left
  const auto at_once = drops.drop("RDTF/REQUEST", "burst", t0 + 2s);  // a new period: logged at once
  ASSERT_TRUE(at_once);
  EXPECT_NE(at_once->find("dropped 1 message from the bus (2 since start)"), std::string::npos) << *at_once;
  for (int k = 0; k < 40; ++k) EXPECT_FALSE(drops.drop("RDTF/REQUEST", "burst", t0 + 2s + 5ms));
  for (int k = 0; k < 7; ++k) EXPECT_FALSE(drops.drop("RDTF/x.gltf/JOINT_COMMAND", "end\\xff", t0 + 2s + 10ms));
  EXPECT_FALSE(drops.flush(t0 + 2s + 999ms));  // its period is not over
  const auto end = drops.flush(t0 + 3s);
  ASSERT_TRUE(end);
  EXPECT_EQ(*end, "dropped 47 messages from the bus (49 since start); latest on RDTF/x.gltf/JOINT_COMMAND: end\\xff");
  EXPECT_FALSE(drops.flush(t0 + 5s));  // said once
  EXPECT_EQ(drops.total(), 49u);
}

TEST(BusInput, MalformedDatagramsNeverReachTheHandlers) {
  int requests = 0, commands = 0;
  std::vector<std::string> lines;
  BusInput input({[&](const rdtf::request_t&) { ++requests; }, [&](const rdtf::joint_command_t&) {
                    ++commands;
                    return std::string();
                  },
                  [&](const std::string& line) { lines.push_back(line); }, nullptr});
  const auto good = encode(two_joint_command());
  input.command_datagram("RDTF/arm3.gltf/JOINT_COMMAND", good.data(), good.size());
  EXPECT_EQ(commands, 1);
  // Another model's channel: dropped.
  input.command_datagram("RDTF/other.gltf/JOINT_COMMAND", good.data(), good.size());
  const auto bad = with_int32(two_joint_command(), 46, -1);
  input.command_datagram("RDTF/arm3.gltf/JOINT_COMMAND", bad.data(), bad.size());
  input.request_datagram("RDTF/REQUEST", good.data(), good.size());  // Not a request_t.
  EXPECT_EQ(commands, 1);
  EXPECT_EQ(requests, 0);
  EXPECT_EQ(input.dropped(), 3u);
  EXPECT_EQ(lines.size(), 1u);  // The first drop; the others within the second.
}

TEST(BusInput, DatagramsAboveOneUdpDatagramAndCommandsTheHostRefusesAreDroppedAndCounted) {
  int commands = 0;
  std::vector<std::string> lines;
  std::string refusal;
  BusInput input({nullptr,
                  [&](const rdtf::joint_command_t&) {
                    ++commands;
                    return refusal;
                  },
                  [&](const std::string& line) { lines.push_back(line); }, nullptr});
  auto big = two_joint_command();
  big.content_hash = std::string(BusInput::kMaxInputBytes, 'h');
  const auto bytes = encode(big);
  ASSERT_GT(bytes.size(), BusInput::kMaxInputBytes);
  ASSERT_EQ(lcm_safe::check_known(bytes.data(), bytes.size()), "");  // Well-formed, only too big.
  input.command_datagram("RDTF/arm3.gltf/JOINT_COMMAND", bytes.data(), bytes.size());
  EXPECT_EQ(commands, 0);
  EXPECT_EQ(input.dropped(), 1u);
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NE(lines[0].find("above rdtfd's input limit of 65536"), std::string::npos) << lines[0];
  // The handler's refusal (a full queue, too many joints) is a drop too.
  const auto good = encode(two_joint_command());
  input.command_datagram("RDTF/arm3.gltf/JOINT_COMMAND", good.data(), good.size());
  EXPECT_EQ(input.dropped(), 1u);
  refusal = "too many joints";
  input.command_datagram("RDTF/arm3.gltf/JOINT_COMMAND", good.data(), good.size());
  EXPECT_EQ(commands, 2);
  EXPECT_EQ(input.dropped(), 2u);
}

TEST(BusInput, AHandlerThatThrowsIsACountedDropNeverAnExceptionIntoLiblcm) {
  std::vector<std::string> lines;
  BusInput input({[](const rdtf::request_t&) { throw std::runtime_error("request handler broke"); },
                  [](const rdtf::joint_command_t&) -> std::string { throw 42; },
                  [&](const std::string& line) { lines.push_back(line); }, nullptr});
  const auto request = encode(rdtf::request_t{});
  const auto command = encode(two_joint_command());
  EXPECT_NO_THROW(input.request_datagram("RDTF/REQUEST", request.data(), request.size()));
  EXPECT_NO_THROW(input.command_datagram("RDTF/arm3.gltf/JOINT_COMMAND", command.data(), command.size()));
  EXPECT_EQ(input.dropped(), 2u);
  ASSERT_EQ(lines.size(), 1u);  // The first drop; the second within the second.
  EXPECT_NE(lines[0].find("handler failed: request handler broke"), std::string::npos) << lines[0];
}

TEST(RequestThrottle, RepeatedRequestsGetOneDeferredAnswerPerPeriod) {
  RequestThrottle throttle(1s);
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_TRUE(throttle.admit("", t0));
  for (int k = 0; k < 1000; ++k) EXPECT_FALSE(throttle.admit("", t0 + 1ms * k / 10));
  EXPECT_TRUE(throttle.admit("arm", t0));  // Another model: its own period.
  EXPECT_EQ(throttle.coalesced(), 1000u);
  EXPECT_TRUE(throttle.take_due(t0 + 999ms).empty());
  ASSERT_EQ(throttle.next_due(), t0 + 1s);
  EXPECT_EQ(throttle.take_due(t0 + 1s), std::vector<std::string>{""});
  // The deferred answer started a new period; a quiet one forgets the id.
  EXPECT_FALSE(throttle.admit("", t0 + 1500ms));
  EXPECT_EQ(throttle.take_due(t0 + 2s), std::vector<std::string>{""});
  EXPECT_TRUE(throttle.take_due(t0 + 3s).empty());
  EXPECT_TRUE(throttle.admit("", t0 + 3s));
}

TEST(Publisher, QueueIsBoundedInBytesAndUrgentMessagesGoFirst) {
  std::vector<std::string> sent;
  bool refuse = true;
  Publisher publisher(
      [&](const std::string& channel, const std::uint8_t*, unsigned int) {
        if (refuse) return -1;
        sent.push_back(channel);
        return 0;
      },
      1e12, 1 << 30);
  std::vector<PublisherEvent> events;
  publisher.on_event([&](const PublisherEvent& e) { events.push_back(e); });
  // An injected clock: the drop reports' pacing must not depend on how fast this machine is.
  auto now = std::chrono::steady_clock::time_point{} + 1000s;
  publisher.set_clock([&] { return now; });
  const auto drop_reports = [&] {
    std::size_t n = 0;
    for (const auto& e : events) n += e.kind == PublisherEvent::Kind::kDropped;
    return n;
  };
  rdtf::description_t big;
  big.rdtf_json.assign(1 << 20, 'x');  // 1 MiB each
  for (int k = 0; k < 100; ++k) publisher.publish("BIG", big);
  EXPECT_LE(publisher.queued_bytes(), Publisher::kMaxQueuedBytes);
  EXPECT_GT(publisher.dropped(), 30u);
  EXPECT_EQ(drop_reports(), 1u);  // Once a second, not once a message.
  now += 999ms;
  publisher.publish("BIG", big);
  EXPECT_EQ(drop_reports(), 1u);
  now += 1ms;
  publisher.publish("BIG", big);
  EXPECT_EQ(drop_reports(), 2u);  // A second after the first report.
  // Every drop since the first report, which reported one.
  EXPECT_NE(events.back().text.find("dropped " + std::to_string(publisher.dropped() - 1) + " oldest message(s) (" +
                                    std::to_string(publisher.dropped()) + " since start)"),
            std::string::npos)
      << events.back().text;
  publisher.publish("STATUS", rdtf::status_t{}, Publisher::Priority::kUrgent);
  refuse = false;
  publisher.drain(now + 1s);
  ASSERT_FALSE(sent.empty());
  EXPECT_EQ(sent.front(), "STATUS");
  EXPECT_EQ(publisher.queued_bytes(), 0u);
}

TEST(ReportLimiter, AtMostNAWindowAndTheNextReportCountsTheLeftOut) {
  ReportLimiter limiter(2, "failures");
  const Clock::time_point t0 = Clock::now();
  EXPECT_EQ(limiter.admit("a", t0), "a");
  EXPECT_EQ(limiter.admit("b", t0 + 100ms), "b");
  EXPECT_FALSE(limiter.admit("c", t0 + 200ms).has_value());
  EXPECT_FALSE(limiter.admit("d", t0 + 999ms).has_value());
  EXPECT_EQ(limiter.admit("e", t0 + 1000ms), "e (and 2 earlier failures not reported: over 2 a second)");
  EXPECT_EQ(limiter.admit("f", t0 + 1500ms), "f");
}

TEST(RestartDelay, DoublesFromTheFirstDelayUpToTheMaximum) {
  EXPECT_EQ(restart_delay(1), kFirstRestartDelay);
  EXPECT_EQ(restart_delay(2), 2 * kFirstRestartDelay);
  EXPECT_EQ(restart_delay(5), 16 * kFirstRestartDelay);
  EXPECT_EQ(restart_delay(9), 256 * kFirstRestartDelay);  // 25.6 s
  EXPECT_EQ(restart_delay(10), Clock::duration(kMaxRestartDelay));
  EXPECT_EQ(restart_delay(1000), Clock::duration(kMaxRestartDelay));
}

// Up to three models that fall behind in one window are logged a line each; more at once (a
// starved thread: every model together) in one line with the count and the range of factors.
TEST(LiveTiming, ManyModelsFallingBehindAtOnceAreOneLine) {
  std::vector<TimingChange> changes;
  for (int i = 0; i < 3; ++i) changes.push_back({"m" + std::to_string(i) + ".gltf", 0.5 + 0.1 * i, "line " + std::to_string(i)});
  EXPECT_EQ(timing_change_lines(changes, "are behind", 1.0), (std::vector<std::string>{"line 0", "line 1", "line 2"}));
  changes.push_back({"m3.gltf", 0.166, "line 3"});
  changes.push_back({"m4.gltf", 0.8, "line 4"});
  EXPECT_EQ(timing_change_lines(changes, "are behind", 1.0),
            (std::vector<std::string>{"live simulations of 5 models are behind (m0.gltf, m1.gltf, m2.gltf and 2 more): "
                                      "0.166 to 0.8 simulated s per wall s of 1 wanted (all at once: the machine's "
                                      "load, not one model's cost)"}));
  EXPECT_TRUE(timing_change_lines({}, "keep time again", 1.0).empty());
}

TEST(LiveBudget, ModelsCheaperThanTheirShareRunFullyAndTheCostlyOneTakesTheRest) {
  // Budget 1 ms per step; costs 0.1, 0.2 and 5 ms: the two cheap ones at full rate, the costly one
  // gets what is left (0.7 ms of 5).
  const auto rates = budget_step_rates({0.1e-3, 5e-3, 0.2e-3}, 1e-3);
  EXPECT_DOUBLE_EQ(rates[0], 1);
  EXPECT_DOUBLE_EQ(rates[2], 1);
  EXPECT_NEAR(rates[1], 0.7 / 5, 1e-12);
  // Everything fits: all at full rate. Two equal costly ones: half the budget each.
  EXPECT_EQ(budget_step_rates({1e-4, 1e-4}, 1e-3), (std::vector<double>{1, 1}));
  const auto equal = budget_step_rates({4e-3, 4e-3}, 1e-3);
  EXPECT_NEAR(equal[0], 0.125, 1e-12);
  EXPECT_NEAR(equal[1], 0.125, 1e-12);
}

}  // namespace
}  // namespace rdtf::daemon
