// Helpers for the integration tests of rdtfd's live simulation (tests/daemon/simulation_itest.cc)
// and of the example controller (tests/clients/controller_itest.cc). They run on the harness of
// tests/daemon/harness.h (read its header comment: one network namespace per test case, the real
// rdtfd, a Subscriber that records every RDTF message).
//
// The arm3 fixture (tests/data/blender/arm3.gltf) has two revolute joints, shoulder and elbow,
// whose axes (+Y) run along the arm, and every link's centre of mass lies on that axis: gravity
// never loads them. So a joint at rest stays exactly at rest unless a command moves it (what the
// daemon tests want), and `arm3_across_gravity` turns both axes to +Z so that gravity along -X
// (config "gravity": [-9.80665, 0, 0]) pulls the straight arm sideways with its full weight
// (what the controller test wants).
#pragma once

#include <cmath>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "rdtf/dynamics.h"

#include <rdtf/joint_command_t.hpp>
#include <rdtf/joint_state_t.hpp>

#include "daemon/harness.h"

namespace rdtf::itest {

inline constexpr const char* kArm = "arm3.gltf";

struct ReceivedState {
  rdtf::joint_state_t state;
  Clock::time_point received;
};

inline std::vector<ReceivedState> joint_states(const std::vector<Message>& all, const std::string& model_id = kArm) {
  std::vector<ReceivedState> out;
  for (const auto& m : on_kind(all, "JOINT_STATE", model_id)) out.push_back({m.as<rdtf::joint_state_t>(), m.received});
  return out;
}

inline std::optional<double> position_of(const rdtf::joint_state_t& state, const std::string& joint) {
  for (std::size_t i = 0; i < state.name.size(); ++i) {
    if (state.name[i] == joint) return state.position[i];
  }
  return std::nullopt;
}

inline std::optional<double> velocity_of(const rdtf::joint_state_t& state, const std::string& joint) {
  for (std::size_t i = 0; i < state.name.size(); ++i) {
    if (state.name[i] == joint) return state.velocity[i];
  }
  return std::nullopt;
}

// The newest state of a revision, if any arrived.
inline std::optional<rdtf::joint_state_t> last_state(const std::vector<Message>& all, std::int64_t revision,
                                                     const std::string& model_id = kArm) {
  std::optional<rdtf::joint_state_t> last;
  for (auto& s : joint_states(all, model_id)) {
    if (s.state.revision == revision) last = std::move(s.state);
  }
  return last;
}

struct JointOrder {
  std::string joint;
  std::int8_t mode = rdtf::joint_command_t::TORQUE;
  double value = 0;
  double kp = 0;
  double kd = 0;
};

inline rdtf::joint_command_t make_command(const std::string& model_id, std::int64_t revision, const std::string& hash,
                                          const std::vector<JointOrder>& orders) {
  rdtf::joint_command_t command;
  command.utime = 0;
  command.model_id = model_id;
  command.revision = revision;
  command.content_hash = hash;
  for (const auto& o : orders) {
    command.name.push_back(o.joint);
    command.mode.push_back(o.mode);
    command.value.push_back(o.value);
    command.kp.push_back(o.kp);
    command.kd.push_back(o.kd);
  }
  command.num_joints = static_cast<std::int32_t>(command.name.size());
  return command;
}

// COMMAND_REJECTED reports on the model's ERROR channel, in arrival order.
inline std::vector<std::string> rejections(const std::vector<Message>& all, const std::string& model_id = kArm) {
  std::vector<std::string> out;
  for (const auto& e : decoded<rdtf::model_error_t>(all, "ERROR", model_id)) {
    for (const auto& d : e.diagnostics) {
      if (d.code == "COMMAND_REJECTED") out.push_back(d.message);
    }
  }
  return out;
}

// arm3 with both joint axes turned from +Y (along the arm) to +Z (across it), written into
// `folder` as arm3.gltf beside the fixture's arm3.bin. Returns the daemon's content hash.
inline std::string write_arm3_across_gravity(const fs::path& folder) {
  copy_fixture(folder, "arm3");
  Json document = Json::parse(read(folder / "arm3.gltf"));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "shoulder" || node.value("name", "") == "elbow") {
      node["extras"]["rdtf_axis"] = {0.0, 0.0, 1.0};
      node["extras"]["rdtf_axes"] = "gltf";  // glTF's axes, though Blender wrote the file.
    }
  }
  const std::string gltf = document.dump(1);
  write_in_place(folder / "arm3.gltf", gltf);
  return content_hash(gltf, {read(folder / "arm3.bin")});
}

// The arm's gravity model from `rdtf inspect --json` of the file the daemon converts: a chain
// of links, each turning about its parent joint's axis through the joint's origin (the joint
// frame is the child link's frame, docs/format.md).
class ArmGravity {
 public:
  ArmGravity(const Json& inspected, const Eigen::Vector3d& gravity) : g_(gravity) {
    std::map<std::string, int> link_index;
    for (const auto& link : inspected["links"]) {
      Body body;
      body.mass = link["mass"].get<double>();
      const auto& t = link["pose"]["translation"];
      const auto& r = link["pose"]["rotation"];  // x, y, z, w
      const Eigen::Quaterniond R_SL(r[3].get<double>(), r[0].get<double>(), r[1].get<double>(), r[2].get<double>());
      body.origin = {t[0].get<double>(), t[1].get<double>(), t[2].get<double>()};
      const auto& c = link["centerOfMass"];
      body.com = body.origin + R_SL * Eigen::Vector3d(c[0].get<double>(), c[1].get<double>(), c[2].get<double>());
      body.R_SL = R_SL.toRotationMatrix();
      link_index[link["name"].get<std::string>()] = static_cast<int>(bodies_.size());
      bodies_.push_back(body);
    }
    for (const auto& joint : inspected["joints"]) {
      Body& child = bodies_[link_index.at(joint["child"].get<std::string>())];
      child.parent = link_index.at(joint["parent"].get<std::string>());
      const auto& a = joint["axis"];
      child.axis = child.R_SL * Eigen::Vector3d(a[0].get<double>(), a[1].get<double>(), a[2].get<double>());
      child.joint = joint["name"].get<std::string>();
    }
  }

  // Generalised gravity forces Q_j = sum over the links moved by joint j of m g . (a_j x (p - o_j)),
  // at joint positions q (by name; missing joints at 0), N m.
  std::map<std::string, double> torques(const std::map<std::string, double>& q) const {
    std::vector<Eigen::Isometry3d> X(bodies_.size());  // Displacement of each link from rest.
    for (std::size_t b = 0; b < bodies_.size(); ++b) X[b] = displacement(static_cast<int>(b), q);
    std::map<std::string, double> Q;
    for (std::size_t j = 0; j < bodies_.size(); ++j) {
      const Body& joint_link = bodies_[j];
      if (joint_link.parent < 0) continue;
      const Eigen::Vector3d o = X[j] * joint_link.origin;
      const Eigen::Vector3d a = X[j].linear() * joint_link.axis;
      double sum = 0;
      for (std::size_t b = 0; b < bodies_.size(); ++b) {
        if (!descends(static_cast<int>(b), static_cast<int>(j))) continue;
        sum += bodies_[b].mass * g_.dot(a.cross(X[b] * bodies_[b].com - o));
      }
      Q[joint_link.joint] = sum;
    }
    return Q;
  }

  // Where a PD hold (tau = kp (q* - q) - kd qdot) comes to rest: kp (q* - q) + Q(q) = 0, solved by
  // fixed-point iteration (a contraction while |dQ/dq| < kp).
  std::map<std::string, double> equilibrium(const std::map<std::string, double>& target, double kp) const {
    std::map<std::string, double> q = target;
    for (int i = 0; i < 200; ++i) {
      const auto Q = torques(q);
      for (auto& [joint, value] : q) value = target.at(joint) + Q.at(joint) / kp;
    }
    return q;
  }

  // The largest |Q_j| over every pose: each link's weight at its full lever arm from the joint.
  double max_torque(const std::string& joint) const {
    for (std::size_t j = 0; j < bodies_.size(); ++j) {
      if (bodies_[j].joint != joint) continue;
      double bound = 0;
      for (std::size_t b = 0; b < bodies_.size(); ++b) {
        if (descends(static_cast<int>(b), static_cast<int>(j))) {
          bound += bodies_[b].mass * g_.norm() * (bodies_[b].com - bodies_[j].origin).norm();
        }
      }
      return bound;
    }
    throw std::runtime_error("no joint " + joint);
  }

 private:
  struct Body {
    double mass = 0;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // Link frame origin at rest = joint origin (S).
    Eigen::Vector3d com = Eigen::Vector3d::Zero();     // Centre of mass at rest (S).
    Eigen::Matrix3d R_SL = Eigen::Matrix3d::Identity();
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();   // Parent joint's axis at rest (S).
    std::string joint;
    int parent = -1;
  };

  bool descends(int b, int ancestor) const {
    for (int at = b; at >= 0; at = bodies_[at].parent) {
      if (at == ancestor) return true;
    }
    return false;
  }

  // The rigid motion that takes link b from its rest pose to its pose at q.
  Eigen::Isometry3d displacement(int b, const std::map<std::string, double>& q) const {
    const Body& body = bodies_[b];
    if (body.parent < 0) return Eigen::Isometry3d::Identity();
    const auto angle = q.find(body.joint);
    Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
    turn.translate(body.origin);
    turn.rotate(Eigen::AngleAxisd(angle == q.end() ? 0.0 : angle->second, body.axis));
    turn.translate(-body.origin);
    return displacement(body.parent, q) * turn;
  }

  Eigen::Vector3d g_;
  std::vector<Body> bodies_;
};

}  // namespace rdtf::itest
