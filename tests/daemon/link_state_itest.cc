// rdtfd's LINK_STATE stream over real LCM (one network namespace per case; see harness.h): every
// link with the live revision and content hash, paired with the JOINT_STATE of the same step; a
// root held by the world at its glTF scene pose; arm3's poses those of a core Simulation stepped
// alike and, at rest, those of the forward kinematics of the joint positions; a floating box
// falling as ODE's integrator says it must.
#include <cfloat>
#include <cmath>
#include <set>

#include <rdtf/link_state_t.hpp>

#include "clients/live_arm.h"
#include "rdtf/convert.h"

namespace rdtf::itest {
namespace {

constexpr double kDt = 1e-3;  // s: the daemon's step (SimulationOptions::time_step).
// A unit quaternion from Eigen's matrix conversion, renormalised: a few ulps off 1 at most.
constexpr double kUnitTolerance = 4 * DBL_EPSILON;

struct ReceivedLinks {
  rdtf::link_state_t state;
  Json json;  // The same message as rdtf-echo prints it (message_json).
};

std::vector<ReceivedLinks> link_states(const std::vector<Message>& all, const std::string& model_id) {
  std::vector<ReceivedLinks> out;
  for (const auto& m : on_kind(all, "LINK_STATE", model_id)) out.push_back({m.as<rdtf::link_state_t>(), m.json()});
  return out;
}

bool wait_link_states(Session& s, const std::string& model_id, std::size_t count) {
  return s.wait_for([&](const auto& all) { return on_kind(all, "LINK_STATE", model_id).size() >= count; }, 10s);
}

Eigen::Quaterniond orientation(const rdtf::link_state_t& m, std::size_t i) {
  const auto& q = m.orientation.at(i);
  return {q.at(0), q.at(1), q.at(2), q.at(3)};
}

Eigen::Vector3d vec3(const std::vector<double>& v) { return {v.at(0), v.at(1), v.at(2)}; }

// The step a state belongs to; sim_time is that many steps of kDt (to rounding).
std::uint64_t step_of(double sim_time) { return static_cast<std::uint64_t>(std::llround(sim_time / kDt)); }

// Shape, stamps and unit quaternions of every LINK_STATE of a model, its JSON as rdtf-echo prints
// it, and the JOINT_STATE of the same step (same utime and sim_time) beside each.
void expect_well_formed(const std::vector<Message>& all, const std::string& model_id, std::int64_t revision,
                        const std::string& hash, const std::vector<std::string>& links) {
  const auto states = link_states(all, model_id);
  ASSERT_FALSE(states.empty());
  std::map<std::int64_t, double> joint_state_times;  // utime -> sim_time
  for (const auto& m : on_kind(all, "JOINT_STATE", model_id)) {
    const auto js = m.as<rdtf::joint_state_t>();
    joint_state_times[js.utime] = js.sim_time;
  }
  for (const auto& [m, json] : states) {
    SCOPED_TRACE("LINK_STATE at sim_time " + std::to_string(m.sim_time));
    EXPECT_EQ(m.model_id, model_id);
    EXPECT_EQ(m.revision, revision);
    EXPECT_EQ(m.content_hash, hash);
    EXPECT_EQ(m.name, links);
    ASSERT_EQ(m.num_links, static_cast<std::int32_t>(links.size()));
    for (std::size_t i = 0; i < links.size(); ++i) {
      EXPECT_NEAR(orientation(m, i).norm(), 1.0, kUnitTolerance) << links[i];
      for (double x : m.position[i]) EXPECT_TRUE(std::isfinite(x));
    }
    const auto paired = joint_state_times.find(m.utime);
    ASSERT_NE(paired, joint_state_times.end()) << "no JOINT_STATE with the same utime";
    EXPECT_EQ(paired->second, m.sim_time);
    ASSERT_TRUE(json.is_object()) << "message_json does not decode link_state_t";
    EXPECT_EQ(json["type"], "rdtf.link_state_t");
    EXPECT_EQ(json["revision"], m.revision);
    EXPECT_EQ(json["content_hash"], m.content_hash);
    EXPECT_EQ(json["sim_time"].get<double>(), m.sim_time);
    EXPECT_EQ(json["name"].get<std::vector<std::string>>(), m.name);
    EXPECT_EQ(json["position"].get<std::vector<std::vector<double>>>(), m.position);
    EXPECT_EQ(json["orientation"].get<std::vector<std::vector<double>>>(), m.orientation);
    EXPECT_EQ(json["linear_velocity"].get<std::vector<std::vector<double>>>(), m.linear_velocity);
    EXPECT_EQ(json["angular_velocity"].get<std::vector<std::vector<double>>>(), m.angular_velocity);
  }
}

std::vector<std::string> link_names(const Json& inspected) {
  std::vector<std::string> names;
  for (const auto& link : inspected["links"]) names.push_back(link["name"].get<std::string>());
  return names;
}

// A chain of three boxes whose root node is moved and turned in the scene, so that "the root
// stays at its scene pose" is not "the root stays at the origin". With `massless_root` the root
// node has no mesh: the world carries that link itself (no body), else it is a body of its own.
struct PlacedChain {
  std::string gltf;
  Eigen::Vector3d translation{0.3, 1.25, -0.7};
  Eigen::Quaterniond rotation = Eigen::Quaterniond(Eigen::AngleAxisd(0.6, Eigen::Vector3d(1, 2, 3).normalized()));
  double mass = 0;  // kg, of the bodies
  explicit PlacedChain(bool massless_root) {
    const GeneratedModel model = box_model("base", 0.05, 3);
    Json document = Json::parse(model.gltf);
    document["nodes"][0]["translation"] = {translation.x(), translation.y(), translation.z()};
    document["nodes"][0]["rotation"] = {rotation.x(), rotation.y(), rotation.z(), rotation.w()};
    if (massless_root) {
      document["nodes"][0].erase("mesh");
      document["nodes"][0]["extras"]["rdtf_type"] = "link";  // A bare root would not be one.
    }
    gltf = document.dump(1);
    mass = model.link_mass * (massless_root ? 2 : 3);
  }
};

// The two ways a fixed root is held. A root link without mass (and none fixed to it) is carried
// by the world itself: its pose is the node's, exactly (the rotation to the rounding of the
// matrix-to-quaternion conversion), and it has no velocity. A root with mass is a body that an
// ODE fixed joint holds to the world, and ODE's constraints are soft: ERP = h k / (h k + c) and
// CFM = 1 / (h k + c) for a spring k and damper c, so with c = 0, k = ERP / (h CFM) (ODE manual, "Soft constraint and constraint force mixing"),
// 0.2 / (1e-3 x 1e-10) = 2e12 N/m (N m/rad for the rotation). So the root yields by F / k under
// the joint's load F; the toppling chain's reaction stays within ten times its weight (its links'
// accelerations stay under 9 g: they fall from rest through less than half a metre), so the bound
// is 10 m g / k, and 10 m g r / k in rotation (r the chain's length). Velocities: ODE moves a body
// by v h each step (x' = x + v' h), so |v| <= 2 bound / h.
TEST(LinkState, EveryLinkWithTheLiveRevisionAndAFixedRootAtItsScenePose) {
  Session s;
  const PlacedChain carried(true), held(false);
  write_in_place(s.watch / "carried.gltf", carried.gltf);
  write_in_place(s.watch / "held.gltf", held.gltf);
  s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100));
  ASSERT_TRUE(s.wait_revision("carried.gltf", 1, content_hash(carried.gltf)));
  ASSERT_TRUE(s.wait_revision("held.gltf", 1, content_hash(held.gltf)));
  ASSERT_TRUE(wait_link_states(s, "carried.gltf", 30));
  ASSERT_TRUE(wait_link_states(s, "held.gltf", 30));
  const auto all = s.messages();
  const auto names = link_names(inspect(s.watch / "held.gltf"));
  ASSERT_EQ(names.size(), 3u);
  EXPECT_EQ(link_names(inspect(s.watch / "carried.gltf")), names);
  expect_well_formed(all, "carried.gltf", 1, content_hash(carried.gltf), names);
  expect_well_formed(all, "held.gltf", 1, content_hash(held.gltf), names);

  const Eigen::Matrix3d R_node = carried.rotation.toRotationMatrix();
  bool links_moved = false;
  for (const auto& [m, json] : link_states(all, "carried.gltf")) {
    EXPECT_EQ(vec3(m.position[0]), carried.translation);
    EXPECT_LE((orientation(m, 0).toRotationMatrix() - R_node).cwiseAbs().maxCoeff(), 4 * DBL_EPSILON);
    EXPECT_EQ(vec3(m.linear_velocity[0]), Eigen::Vector3d::Zero());
    EXPECT_EQ(vec3(m.angular_velocity[0]), Eigen::Vector3d::Zero());
    links_moved |= vec3(m.angular_velocity[1]).norm() > 1e-3;
  }
  // The tilted chain topples under gravity: the other links' poses are live, not the rest pose.
  EXPECT_TRUE(links_moved);

  const double k = 0.2 / (kDt * 1e-10);  // SimulationOptions' erp and cfm
  const double length = 3 * (2 * 0.05 + 0.01);
  const double position_bound = 10 * held.mass * kStandardGravity / k;
  const double rotation_bound = position_bound * length;
  double worst_position = 0, worst_rotation = 0, worst_v = 0, worst_w = 0;
  for (const auto& [m, json] : link_states(all, "held.gltf")) {
    worst_position = std::max(worst_position, (vec3(m.position[0]) - held.translation).norm());
    // Small rotations: the largest matrix element's change is at most the angle.
    worst_rotation = std::max(worst_rotation, (orientation(m, 0).toRotationMatrix() - R_node).cwiseAbs().maxCoeff());
    worst_v = std::max(worst_v, vec3(m.linear_velocity[0]).norm());
    worst_w = std::max(worst_w, vec3(m.angular_velocity[0]).norm());
  }
  std::printf("root held by a fixed joint: moved %.3g m (bound %.3g), turned %.3g rad (bound %.3g), "
              "%.3g m/s (bound %.3g), %.3g rad/s (bound %.3g)\n",
              worst_position, position_bound, worst_rotation, rotation_bound, worst_v, 2 * position_bound / kDt,
              worst_w, 2 * rotation_bound / kDt);
  EXPECT_LE(worst_position, position_bound);
  EXPECT_LE(worst_rotation, rotation_bound);
  EXPECT_LE(worst_v, 2 * position_bound / kDt);
  EXPECT_LE(worst_w, 2 * rotation_bound / kDt);
}

// The daemon's arm3 against a core Simulation of the same file, stepped with the same steps: the
// same code on the same inputs, so the poses agree to rounding at every state (1e-9 relative is
// far above it), and joint and link states of one step agree with each other.
void expect_like_core_simulation(const fs::path& model, const std::vector<Message>& all,
                                 const Eigen::Vector3d& gravity) {
  Diagnostics diag;
  const auto conversion = convert_file(model, ConvertOptions{}, diag);
  ASSERT_TRUE(conversion) << "cannot convert " << model;
  SimulationOptions options;
  options.gravity = gravity;
  auto local = Simulation::create(conversion->robot, options, {}, diag);
  ASSERT_TRUE(local);
  std::map<double, rdtf::joint_state_t> joint_states_by_time;
  for (const auto& r : joint_states(all)) joint_states_by_time[r.state.sim_time] = r.state;

  const auto states = link_states(all, kArm);
  double reach = 0;  // m: the scale of positions, for relative tolerances
  for (const auto& pose : local->link_poses()) reach = std::max(reach, pose.X_SL.translation().norm());
  double worst_position = 0, worst_rotation = 0, worst_velocity = 0, fastest = 0;
  for (const auto& [m, json] : states) {
    const std::uint64_t n = step_of(m.sim_time);
    ASSERT_GE(n, local->steps()) << "LINK_STATEs out of order";
    while (local->steps() < n) local->step(kDt);
    ASSERT_EQ(local->time(), m.sim_time);
    const auto poses = local->link_poses();
    ASSERT_EQ(poses.size(), m.name.size());
    for (std::size_t i = 0; i < poses.size(); ++i) {
      EXPECT_EQ(m.name[i], poses[i].name);
      worst_position = std::max(worst_position, (vec3(m.position[i]) - poses[i].X_SL.translation()).norm());
      worst_rotation = std::max(
          worst_rotation, (orientation(m, i).toRotationMatrix() - poses[i].X_SL.linear()).cwiseAbs().maxCoeff());
      worst_velocity = std::max({worst_velocity, (vec3(m.linear_velocity[i]) - poses[i].v_SLo_S).norm(),
                                 (vec3(m.angular_velocity[i]) - poses[i].w_SL_S).norm()});
      fastest = std::max({fastest, poses[i].v_SLo_S.norm(), poses[i].w_SL_S.norm()});
    }
    const auto paired = joint_states_by_time.find(m.sim_time);
    ASSERT_NE(paired, joint_states_by_time.end());
    const auto joints = local->joint_states();
    ASSERT_EQ(paired->second.name.size(), joints.size());
    for (std::size_t j = 0; j < joints.size(); ++j) {
      EXPECT_NEAR(paired->second.position[j], joints[j].position, 1e-9 * std::max(1.0, std::abs(joints[j].position)));
    }
  }
  std::printf("%zu LINK_STATEs to t = %.3f s against a core Simulation: worst position %.3g m (reach %.3f m), "
              "rotation %.3g, velocity %.3g (fastest %.3g)\n",
              states.size(), states.back().state.sim_time, worst_position, reach, worst_rotation, worst_velocity,
              fastest);
  EXPECT_LE(worst_position, 1e-9 * reach);
  EXPECT_LE(worst_rotation, 1e-9);
  EXPECT_LE(worst_velocity, 1e-9 * std::max(fastest, 1e-12));
}

// Forward kinematics of a chain from `rdtf inspect --json`: a child link's frame is its joint's
// frame, turned by the joint's position about its axis (in the child frame) from the rest pose.
std::map<std::string, Eigen::Isometry3d> forward_kinematics(const Json& inspected,
                                                           const std::map<std::string, double>& q) {
  std::map<std::string, Eigen::Isometry3d> rest, out;
  for (const auto& link : inspected["links"]) {
    const auto& t = link["pose"]["translation"];
    const auto& r = link["pose"]["rotation"];  // x, y, z, w
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translate(Eigen::Vector3d(t[0].get<double>(), t[1].get<double>(), t[2].get<double>()));
    X.rotate(Eigen::Quaterniond(r[3].get<double>(), r[0].get<double>(), r[1].get<double>(), r[2].get<double>()));
    rest[link["name"].get<std::string>()] = X;
  }
  out = rest;  // Roots (and any link without a parent joint) stay at rest: fixed root.
  // Joints are listed parents first (robot order), so each parent is placed before its child.
  for (const auto& joint : inspected["joints"]) {
    const std::string parent = joint["parent"], child = joint["child"];
    const auto& a = joint["axis"];
    const Eigen::Vector3d axis(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
    const auto angle = q.find(joint["name"].get<std::string>());
    out[child] = out[parent] * (rest[parent].inverse() * rest[child]) *
                 Eigen::AngleAxisd(angle == q.end() ? 0.0 : angle->second, axis.normalized());
  }
  return out;
}

// arm3 as drawn, no commands: its joints stay where they start (gravity along both axes, see
// live_arm.h), and each state's link poses are the forward kinematics of the joint positions of
// the JOINT_STATE of the same step, but for the give of ODE's soft constraints. Every constraint
// row is a spring k = ERP / (h CFM) = 2e12 N/m (see the fixed-root test above); gravity along the
// arm loads the fixed joint that holds the base with the whole arm's weight, the shoulder with
// that of the upper arm and forearm, the elbow with the forearm's, each along the arm and without
// torque (every centre of mass lies on the line of the axes). So a link's origin sits below its
// forward-kinematics place by the sum, over the constraints between it and the world, of the
// weight each carries over k (8.8e-11 m for the forearm), and no more than twice that while the
// springs settle (a spring loaded from rest overshoots its static deflection at most by itself).
// Rotations carry no load: rounding only.
TEST(LinkState, Arm3AtRestIsTheForwardKinematicsOfItsJointStateAndACoreSimulation) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100));
  const std::string hash = fixture_hash("arm3");
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(wait_link_states(s, kArm, 50));
  const Json inspected = inspect(s.watch / kArm);
  const auto all = s.messages();
  expect_well_formed(all, kArm, 1, hash, link_names(inspected));
  expect_like_core_simulation(s.watch / kArm, all, {0, -kStandardGravity, 0});

  // The yield bound of each link: the chain base_link -> upper_arm -> forearm, in link order.
  const double k = 0.2 / (kDt * 1e-10);  // SimulationOptions' erp and cfm
  std::vector<double> masses;
  for (const auto& link : inspected["links"]) masses.push_back(link["mass"].get<double>());
  ASSERT_EQ(masses.size(), 3u);
  std::map<std::string, double> bound;
  double yield = 0;
  for (std::size_t i = 0; i < masses.size(); ++i) {
    double carried = 0;  // kg: the links from i to the arm's end hang on constraint i
    for (std::size_t j = i; j < masses.size(); ++j) carried += masses[j];
    yield += carried * kStandardGravity / k;
    bound[inspected["links"][i]["name"].get<std::string>()] = 2 * yield;
  }

  std::map<double, rdtf::joint_state_t> by_time;
  for (const auto& r : joint_states(all)) by_time[r.state.sim_time] = r.state;
  double worst_position = 0, worst_ratio = 0, worst_rotation = 0;
  for (const auto& [m, json] : link_states(all, kArm)) {
    const auto& js = by_time.at(m.sim_time);
    std::map<std::string, double> q;
    for (std::size_t j = 0; j < js.name.size(); ++j) q[js.name[j]] = js.position[j];
    const auto X = forward_kinematics(inspected, q);
    for (std::size_t i = 0; i < m.name.size(); ++i) {
      const Eigen::Isometry3d& fk = X.at(m.name[i]);
      const double off = (vec3(m.position[i]) - fk.translation()).norm();
      worst_position = std::max(worst_position, off);
      worst_ratio = std::max(worst_ratio, off / bound.at(m.name[i]));
      worst_rotation =
          std::max(worst_rotation, (orientation(m, i).toRotationMatrix() - fk.linear()).cwiseAbs().maxCoeff());
    }
  }
  std::printf("forward kinematics of the JOINT_STATEs against the LINK_STATEs: worst position %.3g m "
              "(%.3f of its bound, forearm's %.3g m), worst rotation element %.3g\n",
              worst_position, worst_ratio, bound.at("forearm"), worst_rotation);
  EXPECT_LE(worst_ratio, 1.0);
  EXPECT_LE(worst_rotation, 4 * DBL_EPSILON);
}

// arm3 with its axes across gravity swings on its own: poses that change every state, still the
// core Simulation's.
TEST(LinkState, Arm3SwingingFreelyMatchesACoreSimulationSteppedAlike) {
  Session s;
  const std::string hash = write_arm3_across_gravity(s.watch);
  const Eigen::Vector3d gravity(-kStandardGravity, 0, 0);
  s.start(DaemonOptions()
              .with("simulate", true)
              .with("state_rate_hz", 100)
              .with("gravity", Json::array({gravity.x(), gravity.y(), gravity.z()})));
  ASSERT_TRUE(s.wait_revision(kArm, 1, hash));
  ASSERT_TRUE(wait_link_states(s, kArm, 50));
  const auto all = s.messages();
  expect_well_formed(all, kArm, 1, hash, link_names(inspect(s.watch / kArm)));
  const auto last = link_states(all, kArm).back().state;
  EXPECT_GT(vec3(last.angular_velocity.back()).norm(), 0.1) << "the arm does not swing";
  expect_like_core_simulation(s.watch / kArm, all, gravity);
}

// A box with a floating root falls from rest. ODE steps it with semi-implicit Euler
// (v += g h, then x += v h), which gives exactly y_n = y0 - g h^2 n (n + 1) / 2: checked to
// rounding. Against the continuous y0 - g t^2 / 2 that is an error of exactly g h t / 2 (0.5 g t^2
// is reached only as h -> 0), so the bound of the free fall is g h t / 2, not a guessed margin;
// the velocity -g t is exact for that integrator.
TEST(LinkState, AFloatingBoxFallsAsHalfGTSquared) {
  Session s;
  Json document = Json::parse(box_model("faller", 0.1).gltf);
  const Eigen::Vector3d start(0.25, 2.0, -0.5);
  document["nodes"][0]["translation"] = {start.x(), start.y(), start.z()};
  const std::string gltf = document.dump(1);
  write_in_place(s.watch / "faller.gltf", gltf);
  s.start(DaemonOptions().with("simulate", true).with("state_rate_hz", 100).with("floating_root", true));
  ASSERT_TRUE(s.wait_revision("faller.gltf", 1, content_hash(gltf)));
  ASSERT_TRUE(wait_link_states(s, "faller.gltf", 50));
  const auto all = s.messages();
  expect_well_formed(all, "faller.gltf", 1, content_hash(gltf), {"faller"});
  const double g = kStandardGravity, h = kDt;
  double worst_discrete = 0;
  for (const auto& [m, json] : link_states(all, "faller.gltf")) {
    const double n = static_cast<double>(step_of(m.sim_time));
    const double t = n * h;
    ASSERT_NEAR(m.sim_time, t, 1e-9 * t);
    const Eigen::Vector3d p = vec3(m.position[0]);
    const double y_discrete = start.y() - g * h * h * n * (n + 1) / 2;
    const double y_continuous = start.y() - g * t * t / 2;
    worst_discrete = std::max(worst_discrete, std::abs(p.y() - y_discrete));
    EXPECT_NEAR(p.y(), y_discrete, 1e-9 * start.y()) << "t = " << t;
    // The continuous free fall, within the integrator's exact error g h t / 2 (plus rounding).
    EXPECT_LE(std::abs(p.y() - y_continuous), g * h * t / 2 + 1e-9 * start.y()) << "t = " << t;
    EXPECT_NEAR(p.x(), start.x(), 1e-12);
    EXPECT_NEAR(p.z(), start.z(), 1e-12);
    EXPECT_NEAR(m.linear_velocity[0][1], -g * t, 1e-9 * g * t);
    EXPECT_EQ(m.linear_velocity[0][0], 0.0);
    EXPECT_EQ(m.linear_velocity[0][2], 0.0);
    EXPECT_EQ(vec3(m.angular_velocity[0]), Eigen::Vector3d::Zero());
    EXPECT_NEAR(m.orientation[0][0], 1.0, kUnitTolerance);
  }
  const auto last = link_states(all, "faller.gltf").back().state;
  std::printf("fell %.6f m in %.3f s; worst difference from the exact discrete fall %.3g m\n",
              start.y() - last.position[0][1], last.sim_time, worst_discrete);
  EXPECT_GT(last.sim_time, 0.4);
}

}  // namespace
}  // namespace rdtf::itest
