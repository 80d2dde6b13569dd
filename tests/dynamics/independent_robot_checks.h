// Checks of a URDF robot that do not use rdtf's code: they label the robots of tests/data/robots
// sound or broken, and rdtf must then agree (real_robots_test.cc).
//
// 1. Authored inertials (urdfdom's parser, Eigen's eigen solver). Every real mass distribution has
//    an inertia tensor that is positive semi-definite and whose principal moments A <= B <= C meet
//    the triangle inequality A + B >= C (C = integral of x^2 + y^2 dm <= the sum of the other two).
//    A link with mass also has positive principal moments: "positive definite". A moving body (the
//    links welded together by fixed joints, not welded to the world) must have mass and a positive
//    definite inertia about its centre of mass, or a torque on it has no finite answer.
// 2. MuJoCo: the URDF compiled by mj_loadXML (fixed base, fusestatic: welded links are one body,
//    as MuJoCo users load these robots) and simulated passively under gravity from rest.
#pragma once

#include <mujoco/mujoco.h>
#include <urdf_parser/urdf_parser.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "support/test_support.h"

namespace rdtf::robots {

// Relative tolerance on principal moments (of the largest moment of the tensor). Authored inertias
// are decimals with 5 to 12 significant digits; an inertia that is impossible by less than one part
// in a million is within the rounding of its own digits (the eigen solver adds ~1e-15), anything
// more is a real violation.
constexpr double kMomentTolerance = 1e-6;

struct Finding {
  std::string link;
  std::string problem;
};

struct InertiaReport {
  std::vector<Finding> findings;
  int links_with_inertial = 0;
  int moving_bodies = 0;
};

inline Eigen::Matrix3d rotation_of(const urdf::Rotation& r) {
  double x = 0, y = 0, z = 0, w = 1;
  r.getQuaternion(x, y, z, w);
  return Eigen::Quaterniond(w, x, y, z).normalized().toRotationMatrix();
}
inline Eigen::Vector3d vector_of(const urdf::Vector3& v) { return {v.x, v.y, v.z}; }

// The authored tensor about the link's centre of mass, in the inertial frame (URDF's entries are
// the tensor's elements).
inline Eigen::Matrix3d tensor_of(const urdf::Inertial& in) {
  Eigen::Matrix3d I;
  I << in.ixx, in.ixy, in.ixz, in.ixy, in.iyy, in.iyz, in.ixz, in.iyz, in.izz;
  return I;
}

inline Eigen::Vector3d principal_moments(const Eigen::Matrix3d& I) {
  return Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I, Eigen::EigenvaluesOnly).eigenvalues();  // ascending
}

inline std::string moments_text(const Eigen::Vector3d& m) {
  std::ostringstream out;
  out.precision(6);
  out << "principal moments (" << m(0) << ", " << m(1) << ", " << m(2) << ") kg m^2";
  return out.str();
}

// Per authored link: PSD, triangle inequality, and positive definite when the link has mass.
inline void check_link(const urdf::Link& link, InertiaReport& report) {
  const urdf::Inertial& in = *link.inertial;
  ++report.links_with_inertial;
  const Eigen::Vector3d m = principal_moments(tensor_of(in));
  const double tolerance = kMomentTolerance * std::max(m.cwiseAbs().maxCoeff(), 1e-300);
  if (!(in.mass >= 0) || !std::isfinite(in.mass)) {
    report.findings.push_back({link.name, "mass " + std::to_string(in.mass) + " kg is not a mass"});
  } else if (m(0) < -tolerance) {
    report.findings.push_back({link.name, "not positive semi-definite: " + moments_text(m)});
  } else if (m(0) + m(1) < m(2) - tolerance) {
    report.findings.push_back({link.name, "triangle inequality A + B >= C violated: " + moments_text(m)});
  } else if (in.mass > 0 && m(0) <= tolerance) {
    report.findings.push_back({link.name, "has mass but its inertia is not positive definite: " + moments_text(m)});
  }
}

struct Body {
  std::vector<const urdf::Link*> links;  // links[0] is the body's frame: its joint is not fixed
  std::vector<Eigen::Isometry3d> X_BL;   // each link's pose in the body frame
};

// Adds `link` and the links welded to it by fixed joints to `body`; the subtrees hanging from moving
// joints start bodies of their own.
inline void collect_body(const urdf::Link& link, const Eigen::Isometry3d& X_BL, Body& body,
                         std::vector<const urdf::Link*>& moving_roots) {
  body.links.push_back(&link);
  body.X_BL.push_back(X_BL);
  for (const auto& child : link.child_links) {
    const urdf::Joint& joint = *child->parent_joint;
    if (joint.type == urdf::Joint::FIXED) {
      Eigen::Isometry3d X_LC = Eigen::Isometry3d::Identity();
      X_LC.linear() = rotation_of(joint.parent_to_joint_origin_transform.rotation);
      X_LC.translation() = vector_of(joint.parent_to_joint_origin_transform.position);
      collect_body(*child, X_BL * X_LC, body, moving_roots);
    } else {
      moving_roots.push_back(child.get());
    }
  }
}

// Mass, centre of mass and inertia about it of a body in its frame (parallel-axis theorem).
inline void check_moving_body(const Body& body, InertiaReport& report) {
  ++report.moving_bodies;
  double mass = 0;
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < body.links.size(); ++i) {
    if (const auto& in = body.links[i]->inertial) {
      mass += in->mass;
      first_moment += in->mass * (body.X_BL[i] * vector_of(in->origin.position));
    }
  }
  const std::string& name = body.links[0]->name;
  if (!(mass > 0)) {
    report.findings.push_back({name, "moving body without mass"});
    return;
  }
  const Eigen::Vector3d p_BoBcm = first_moment / mass;
  Eigen::Matrix3d I_Bcm = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < body.links.size(); ++i) {
    const auto& in = body.links[i]->inertial;
    if (!in) continue;
    const Eigen::Matrix3d R_BI = body.X_BL[i].linear() * rotation_of(in->origin.rotation);
    const Eigen::Vector3d d = body.X_BL[i] * vector_of(in->origin.position) - p_BoBcm;
    I_Bcm += R_BI * tensor_of(*in) * R_BI.transpose() +
             in->mass * (d.squaredNorm() * Eigen::Matrix3d::Identity() - d * d.transpose());
  }
  const Eigen::Vector3d m = principal_moments(I_Bcm);
  if (m(0) <= kMomentTolerance * std::max(m(2), 0.0)) {
    report.findings.push_back({name, "moving body (with the links welded to it) has no positive definite inertia: " +
                                         moments_text(m)});
  }
}

// The root link is welded to the world (a fixed base, as rdtf validates and MuJoCo loads a URDF).
inline InertiaReport check_inertials(const urdf::ModelInterface& model) {
  InertiaReport report;
  for (const auto& [name, link] : model.links_) {
    if (link->inertial) check_link(*link, report);
  }
  std::vector<const urdf::Link*> moving_roots;
  Body welded_to_world;
  collect_body(*model.getRoot(), Eigen::Isometry3d::Identity(), welded_to_world, moving_roots);
  while (!moving_roots.empty()) {
    const urdf::Link* root = moving_roots.back();
    moving_roots.pop_back();
    Body body;
    collect_body(*root, Eigen::Isometry3d::Identity(), body, moving_roots);
    check_moving_body(body, report);
  }
  return report;
}

// ---- MuJoCo ----------------------------------------------------------------------------------

struct MujocoRun {
  bool loaded = false;
  std::string error;          // mj_loadXML's message when it refuses the model
  int bodies = 0, dofs = 0;   // after fusestatic, the world body included
  double seconds = 0;         // simulated
  bool finite = true;         // qpos, qvel, qacc finite at every step
  int bad_qacc_warnings = 0;  // MuJoCo resets the state when the acceleration is not finite
  double energy_scale = 0;    // J: total mass x g x reach of the bodies from the base
  double worst_energy_rise = 0;  // J: largest E(t) - E(0), E = kinetic + potential
};

// Passive motion dissipates (joint damping, friction loss, MuJoCo's soft limits): the energy may
// not rise. MuJoCo's semi-implicit Euler at its default 2 ms step lets it rise by at most 0.51% of
// m g L on these robots (the undamped UR5; printed by the test); an unstable model grows it by
// orders of magnitude. 5% of m g L separates the two with a margin of 10 on the sound side.
constexpr double kEnergyRiseBound = 0.05;

struct MjModelDeleter {
  void operator()(mjModel* m) const { mj_deleteModel(m); }
};
struct MjDataDeleter {
  void operator()(mjData* d) const { mj_deleteData(d); }
};

// The URDF as MuJoCo users load it, with the compiler options written out (these are MuJoCo's
// URDF defaults, stated so a change of default cannot change the verdict): welded links fused,
// visual geometry dropped, no inertia "balancing" or mass bounds that would repair a broken file.
inline std::string with_mujoco_compiler(std::string urdf) {
  std::size_t robot = urdf.find("<robot");
  while (robot != std::string::npos && !std::isspace(static_cast<unsigned char>(urdf[robot + 6]))) {
    robot = urdf.find("<robot", robot + 1);
  }
  const std::size_t end = urdf.find('>', robot);
  urdf.insert(end + 1,
              "<mujoco><compiler fusestatic=\"true\" discardvisual=\"true\" balanceinertia=\"false\" "
              "boundmass=\"0\" boundinertia=\"0\"/></mujoco>");
  return urdf;
}

inline MujocoRun run_in_mujoco(const std::filesystem::path& urdf, double seconds) {
  MujocoRun run;
  testing::TempDir dir;
  const std::filesystem::path copy = dir / "robot.urdf";
  testing::write_file(copy, with_mujoco_compiler(testing::read_file(urdf)));
  char error[1000] = "";
  std::unique_ptr<mjModel, MjModelDeleter> m(mj_loadXML(copy.c_str(), nullptr, error, sizeof error));
  run.error = error;
  if (!m) return run;
  run.loaded = true;
  run.bodies = m->nbody;
  run.dofs = m->nv;
  m->opt.enableflags |= mjENBL_ENERGY;
  // The tree's own dynamics, as rdtf's gate simulates it: no contacts (collision shapes that overlap
  // at rest, e.g. a thigh's cylinder in the trunk's box, would push the bodies apart and add energy).
  m->opt.disableflags |= mjDSBL_CONTACT;
  std::unique_ptr<mjData, MjDataDeleter> d(mj_makeData(m.get()));
  // Start at rest inside every joint's range: a joint whose zero is outside it (the A1's calves,
  // [-2.70, -0.92] rad) starts at the nearest limit, as rdtf does; started at zero, MuJoCo's soft
  // limit would push it back with energy the test does not count.
  for (int j = 0; j < m->njnt; ++j) {
    if (!m->jnt_limited[j] || (m->jnt_type[j] != mjJNT_HINGE && m->jnt_type[j] != mjJNT_SLIDE)) continue;
    mjtNum& q = d->qpos[m->jnt_qposadr[j]];
    q = std::clamp(q, m->jnt_range[2 * j], m->jnt_range[2 * j + 1]);
  }
  mj_forward(m.get(), d.get());
  const double e0 = d->energy[0] + d->energy[1];
  double total_mass = 0, reach = 0;
  for (int b = 1; b < m->nbody; ++b) {
    total_mass += m->body_mass[b];
    const Eigen::Vector3d p(d->xipos[3 * b], d->xipos[3 * b + 1], d->xipos[3 * b + 2]);
    reach = std::max(reach, p.norm());
  }
  const double g = Eigen::Vector3d(m->opt.gravity[0], m->opt.gravity[1], m->opt.gravity[2]).norm();
  run.energy_scale = total_mass * g * std::max(reach, 1e-3);
  const auto finite = [](const mjtNum* v, int n) {
    for (int i = 0; i < n; ++i) {
      if (!std::isfinite(v[i])) return false;
    }
    return true;
  };
  while (d->time < seconds) {
    mj_step(m.get(), d.get());
    run.finite = run.finite && finite(d->qpos, m->nq) && finite(d->qvel, m->nv) && finite(d->qacc, m->nv);
    run.worst_energy_rise = std::max(run.worst_energy_rise, d->energy[0] + d->energy[1] - e0);
  }
  run.seconds = d->time;
  run.bad_qacc_warnings = d->warning[mjWARN_BADQACC].number;
  return run;
}

}  // namespace rdtf::robots
