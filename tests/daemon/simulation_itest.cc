// rdtfd's live simulation over real LCM (one network namespace per case; see harness.h): joint
// states stamped with the live revision at the configured rate, commands checked against the
// live revision, content hash and joints before anything is applied, torque commands that move
// a joint, and hot reloads that keep joint positions by name.
//
// The model is the arm3 fixture under the default gravity (-Y): its joint axes (+Y) run along the
// arm and every centre of mass lies on them (live_arm.h), so gravity never loads a joint and a
// joint moves only when a command moves it. "Not applied" is therefore sharp: the joints stay at 0
// but for the drift of centres of mass that lie on the axis only to rounding (about 1e-18 m off
// it; drift seen: 3e-30 rad), while the 0.5 N m the rejected commands ask for would turn the
// shoulder (about 0.01 kg m^2 about its axis) by more than a radian in half a second.
#include <cmath>
#include <set>

#include "clients/live_arm.h"

namespace rdtf::itest {
namespace {

constexpr double kAtRest = 1e-9;  // rad

// These tests send a command once and watch what it does for seconds: the commands' lifetime is
// the longest there is (its release is tested in tests/dynamics/command_lifetime_test.cc).
DaemonOptions simulating(double state_rate_hz = 100) {
  return DaemonOptions().with("simulate", true).with("state_rate_hz", state_rate_hz).with("joint_command_timeout_s", 60);
}

// Starts rdtfd on arm3 and waits for its first joint state. Returns the content hash.
std::string start_arm(Session& s, double state_rate_hz = 100) {
  copy_fixture(s.watch, "arm3");
  s.start(simulating(state_rate_hz));
  const std::string hash = fixture_hash("arm3");
  if (!s.wait_revision(kArm, 1, hash)) throw std::runtime_error("arm3 revision 1 not published");
  if (!s.wait_for([](const auto& all) { return last_state(all, 1).has_value(); }, 5s)) {
    throw std::runtime_error("no JOINT_STATE for arm3 revision 1");
  }
  return hash;
}

// Waits for `count` more states of `revision` than there are now.
bool wait_states(Session& s, std::int64_t revision, std::size_t count) {
  std::size_t now = 0;
  for (const auto& r : joint_states(s.messages())) now += r.state.revision == revision;
  return s.wait_for(
      [&](const auto& all) {
        std::size_t seen = 0;
        for (const auto& r : joint_states(all)) seen += r.state.revision == revision;
        return seen >= now + count;
      },
      5s);
}

// The largest |position| of any joint in the states of `revision`.
double largest_excursion(const std::vector<Message>& all, std::int64_t revision) {
  double worst = 0;
  for (const auto& r : joint_states(all)) {
    if (r.state.revision != revision) continue;
    for (double q : r.state.position) worst = std::max(worst, std::abs(q));
  }
  return worst;
}

TEST(Simulation, JointStatesCarryTheLiveRevisionAtTheConfiguredRate) {
  Session s;
  const double rate = 50;
  const std::string hash = start_arm(s, rate);
  // Count the states that arrive in a window of the subscriber's own clock.
  const auto window = 2s;
  const auto begin = Clock::now();
  s.wait_for([&](const auto&) { return Clock::now() - begin >= window * RDTF_TEST_DEADLINE_SCALE; }, 2 * window);
  const auto end = Clock::now();
  const auto states = joint_states(s.messages());
  std::size_t in_window = 0;
  for (const auto& r : states) in_window += r.received >= begin && r.received < end;
  const double seconds = std::chrono::duration<double>(end - begin).count();
  std::printf("%zu joint states in %.3f s: %.1f per second (configured %.0f)\n", in_window, seconds,
              in_window / seconds, rate);
  // Broad: the rate is paced by the daemon's clock; only a gross error (none, or unpaced) fails.
  EXPECT_GE(in_window / seconds, 0.5 * rate);
  EXPECT_LE(in_window / seconds, 1.5 * rate);
  for (const auto& r : states) {
    EXPECT_EQ(r.state.model_id, kArm);
    EXPECT_EQ(r.state.revision, 1);
    EXPECT_EQ(r.state.content_hash, hash);
    EXPECT_EQ(r.state.name, (std::vector<std::string>{"shoulder", "elbow"}));
    EXPECT_EQ(r.state.num_joints, 2);
    EXPECT_EQ(r.state.position.size(), 2u);
  }
  // Simulated time advances with the states.
  EXPECT_GT(states.back().state.sim_time, states.front().state.sim_time);
}

TEST(Simulation, CommandForAnotherRevisionOrContentHashIsRejectedAndNotApplied) {
  Session s;
  const std::string hash = start_arm(s);
  const std::vector<JointOrder> push{{"shoulder", rdtf::joint_command_t::TORQUE, 0.5}};
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND", make_command(kArm, 2, hash, push));
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND", make_command(kArm, 1, std::string(64, '0'), push));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return rejections(all).size() >= 2; }, 5s));
  const auto errors = decoded<rdtf::model_error_t>(s.messages(), "ERROR", kArm);
  ASSERT_EQ(errors.size(), 2u);
  EXPECT_EQ(errors[0].live_revision, 1);
  EXPECT_EQ(errors[0].diagnostics.at(0).severity, rdtf::diagnostic_t::ERROR);
  EXPECT_EQ(errors[0].diagnostics.at(0).message, "command for revision 2 but revision 1 is live");
  // The live revision's hash: the command's own is in the text (escaped, cut at 80 bytes).
  EXPECT_EQ(errors[1].content_hash, hash);
  EXPECT_EQ(errors[1].diagnostics.at(0).message,
            "command for content hash '" + std::string(64, '0') + "' but revision 1 has content hash '" + hash + "'");
  // Half a second of states after the rejections: nothing moved.
  ASSERT_TRUE(wait_states(s, 1, 50));
  EXPECT_LT(largest_excursion(s.messages(), 1), kAtRest);

  // A stale revision: after a hot reload, revision 1's stamp is refused.
  Json document = Json::parse(read(s.watch / kArm));
  document["asset"]["generator"] = "rdtf itest, second save";
  const std::string second = document.dump(1);
  write_in_place(s.watch / kArm, second);
  const std::string hash2 = content_hash(second, {read(s.watch / "arm3.bin")});
  ASSERT_TRUE(s.wait_revision(kArm, 2, hash2));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return last_state(all, 2).has_value(); }, 5s));
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND", make_command(kArm, 1, hash, push));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return rejections(all).size() >= 3; }, 5s));
  EXPECT_EQ(rejections(s.messages()).back(), "command for revision 1 but revision 2 is live");
  ASSERT_TRUE(wait_states(s, 2, 50));
  EXPECT_LT(largest_excursion(s.messages(), 2), kAtRest);
}

TEST(Simulation, CommandNamingAnUnknownJointIsRejectedAsAWhole) {
  Session s;
  const std::string hash = start_arm(s);
  // A valid order for the shoulder beside one for a joint arm3 does not have: nothing applies.
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash,
                                    {{"shoulder", rdtf::joint_command_t::TORQUE, 0.5},
                                     {"wrist", rdtf::joint_command_t::TORQUE, 0.5}}));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !rejections(all).empty(); }, 5s));
  EXPECT_EQ(rejections(s.messages()),
            (std::vector<std::string>{"unknown joint 'wrist' (neither a joint's URDF name nor its glTF name)"}));
  ASSERT_TRUE(wait_states(s, 1, 50));
  EXPECT_LT(largest_excursion(s.messages(), 1), kAtRest);
}

// A torque on the elbow alone. Both joints turn about the same line (the arm's Y axis, on which
// every centre of mass lies) and the shoulder is free, so the arm's angular momentum about it is
// conserved: I_u w_s + I_f (w_s + w_e) = 0 with I_u, I_f the upper arm's and forearm's moments
// about Y. The elbow's relative speed settles where the torque meets the elbow's damping
// (rdtf_damping 0.4 N m s/rad): w_e = tau / d, within a few milliseconds (time constant
// I_u I_f / ((I_u + I_f) d)). Closed form for both speeds.
TEST(Simulation, TorqueCommandMovesTheJointItNames) {
  Session s;
  const std::string hash = start_arm(s);
  const Json inspected = inspect(s.watch / kArm);
  std::map<std::string, double> I_yy;  // inspect: [ixx, ixy, ixz, iyy, iyz, izz], link frames unrotated
  for (const auto& link : inspected["links"]) I_yy[link["name"].get<std::string>()] = link["inertia"][3].get<double>();
  double damping = 0;
  for (const auto& joint : inspected["joints"]) {
    if (joint["name"] == "elbow") damping = joint["damping"].get<double>();
  }
  ASSERT_EQ(damping, 0.4);
  const double tau = 0.1;
  const double w_e = tau / damping;
  const double w_s = -I_yy.at("forearm") / (I_yy.at("upper_arm") + I_yy.at("forearm")) * w_e;

  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash, {{"elbow", rdtf::joint_command_t::TORQUE, tau}}));
  ASSERT_TRUE(s.wait_for(
      [](const auto& all) {
        const auto last = last_state(all, 1);
        return last && *position_of(*last, "elbow") > 0.05;
      },
      5s))
      << "the elbow did not turn";
  ASSERT_TRUE(wait_states(s, 1, 10));
  const auto last = *last_state(s.messages(), 1);
  std::printf("torque %.3f N m on the elbow: elbow %.4f rad at %.9f rad/s (closed form %.9f), shoulder %.4f rad at "
              "%.9f rad/s (closed form %.9f), effort %.4f N m\n",
              tau, *position_of(last, "elbow"), *velocity_of(last, "elbow"), w_e, *position_of(last, "shoulder"),
              *velocity_of(last, "shoulder"), w_s, last.effort.at(1));
  EXPECT_NEAR(*velocity_of(last, "elbow"), w_e, 1e-6 * w_e);
  EXPECT_NEAR(*velocity_of(last, "shoulder"), w_s, 1e-6 * std::abs(w_s));
  EXPECT_EQ(last.effort.at(1), tau);  // The torque applied is the one commanded.
  EXPECT_EQ(last.effort.at(0), 0.0);
  EXPECT_TRUE(rejections(s.messages()).empty());
}

TEST(Simulation, HotReloadKeepsPositionsByNameAndNeverMixesRevisions) {
  Session s;
  const std::string hash = start_arm(s);
  // Drive both joints to a pose and hold it there (position mode, daemon-side PD).
  const double shoulder = 0.4, elbow = -0.3;
  s.subscriber.publish("RDTF/arm3.gltf/JOINT_COMMAND",
                       make_command(kArm, 1, hash,
                                    {{"shoulder", rdtf::joint_command_t::POSITION, shoulder, 2.0, 0.2},
                                     {"elbow", rdtf::joint_command_t::POSITION, elbow, 2.0, 0.2}}));
  ASSERT_TRUE(s.wait_for(
      [&](const auto& all) {
        const auto last = last_state(all, 1);
        return last && std::abs(*position_of(*last, "shoulder") - shoulder) < 1e-6 &&
               std::abs(*position_of(*last, "elbow") - elbow) < 1e-6 && std::abs(*velocity_of(*last, "shoulder")) < 1e-6;
      },
      10s))
      << "the pose was not reached";

  // Rename the elbow: the shoulder keeps its position, "wrist" starts at its rest position.
  Json document = Json::parse(read(s.watch / kArm));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "elbow") node["name"] = "wrist";
  }
  const std::string renamed = document.dump(1);
  write_in_place(s.watch / kArm, renamed);
  const std::string hash2 = content_hash(renamed, {read(s.watch / "arm3.bin")});
  ASSERT_TRUE(s.wait_revision(kArm, 2, hash2));
  ASSERT_TRUE(wait_states(s, 2, 20));

  const auto states = joint_states(s.messages());
  bool switched = false;
  std::optional<rdtf::joint_state_t> first_of_2;
  for (const auto& r : states) {
    const auto& st = r.state;
    if (st.revision == 2) {
      if (!first_of_2) first_of_2 = st;
      switched = true;
      EXPECT_EQ(st.content_hash, hash2);
      EXPECT_EQ(st.name, (std::vector<std::string>{"shoulder", "wrist"}));
    } else {
      EXPECT_FALSE(switched) << "a revision 1 state after revision 2's";
      EXPECT_EQ(st.revision, 1);
      EXPECT_EQ(st.content_hash, hash);
      EXPECT_EQ(st.name, (std::vector<std::string>{"shoulder", "elbow"}));
    }
  }
  ASSERT_TRUE(first_of_2);
  // No gravity torque and no command in revision 2 (commands belong to a revision): the shoulder
  // rests where revision 1 held it; only the elbow's damping and the wrist's reaction could move
  // it, and the wrist starts at rest.
  std::printf("first state of revision 2: shoulder %.9f (held at %.3f), wrist %.9f\n",
              *position_of(*first_of_2, "shoulder"), shoulder, *position_of(*first_of_2, "wrist"));
  EXPECT_NEAR(*position_of(*first_of_2, "shoulder"), shoulder, 1e-5);
  EXPECT_NEAR(*position_of(*first_of_2, "wrist"), 0.0, 1e-5);
  EXPECT_TRUE(rejections(s.messages()).empty());
}

}  // namespace
}  // namespace rdtf::itest
