#include "verdict_memo.h"

#include <openssl/evp.h>

#include <cstdint>

namespace rdtf::daemon {
namespace {

// A field added to these types must be hashed below, or a robot that differs in it would reuse a
// verdict computed for another robot: the sizes catch the addition (on the platform CI builds on;
// elsewhere the sizes may differ and the check is left out).
#if defined(__x86_64__) && defined(__GLIBCXX__)
static_assert(sizeof(LinkMesh) == 24, "a field was added to LinkMesh: hash it in check_digest");
static_assert(sizeof(MassProperties) == 112, "a field was added to MassProperties: hash it in check_digest");
static_assert(sizeof(Link) == 352, "a field was added to Link: hash it in check_digest");
static_assert(sizeof(JointLimits) == 40, "a field was added to JointLimits: hash it in check_digest");
static_assert(sizeof(Joint) == 288, "a field was added to Joint: hash it in check_digest");
static_assert(sizeof(Robot) == 104, "a field was added to Robot: hash it in check_digest");
#endif

// Feeds values to SHA-256 as their bytes: the check's arithmetic on two doubles of the same bits
// is the same.
class Hasher {
 public:
  Hasher() : context_(EVP_MD_CTX_new()) { EVP_DigestInit_ex(context_, EVP_sha256(), nullptr); }
  ~Hasher() { EVP_MD_CTX_free(context_); }
  Hasher(const Hasher&) = delete;
  Hasher& operator=(const Hasher&) = delete;

  void bytes(const void* data, std::size_t size) { EVP_DigestUpdate(context_, data, size); }
  void count(std::size_t n) {
    const std::uint64_t n64 = n;
    bytes(&n64, sizeof(n64));
  }
  void add(double v) { bytes(&v, sizeof(v)); }
  void add(int v) { bytes(&v, sizeof(v)); }
  void add(bool v) { add(v ? 1 : 0); }
  void add(const std::string& s) {
    count(s.size());
    bytes(s.data(), s.size());
  }
  void add(const std::vector<int>& v) {
    count(v.size());
    bytes(v.data(), v.size() * sizeof(int));
  }
  template <typename Matrix>
  void matrix(const Matrix& m) {
    bytes(m.data(), static_cast<std::size_t>(m.size()) * sizeof(double));
  }

  CheckDigest finish() {
    CheckDigest out{};
    unsigned int length = 0;
    EVP_DigestFinal_ex(context_, out.data(), &length);
    return out;
  }

 private:
  EVP_MD_CTX* context_;
};

void add(Hasher& h, const MassProperties& m) {
  h.add(m.volume);
  h.add(m.mass);
  h.matrix(m.center_of_mass);
  h.matrix(m.inertia);
}

void add(Hasher& h, const Link& l) {
  h.add(l.name);
  h.add(l.node);
  h.add(l.parent_joint);
  h.add(l.child_joints);
  h.matrix(l.X_SL.matrix());
  h.count(l.meshes.size());
  for (const LinkMesh& m : l.meshes) {
    h.add(m.node);
    h.add(m.volume);
    h.add(m.density);
  }
  add(h, l.inertial);
  h.add(static_cast<int>(l.inertial_source));
  h.add(l.inertial_node);
  h.add(l.ignored_inertial_extras);
}

void add(Hasher& h, const Joint& j) {
  h.add(j.name);
  h.add(j.node);
  h.add(j.frame_node);
  h.add(j.source_node);
  h.add(j.source_is_entry);
  h.add(j.ignored_extras_node);
  h.add(j.parent_link);
  h.add(j.child_link);
  h.add(static_cast<int>(j.kind));
  h.matrix(j.X_PJ.matrix());
  h.matrix(j.axis);
  h.add(j.limits.has_value());
  if (j.limits) {
    h.add(j.limits->lower);
    h.add(j.limits->upper);
    h.add(j.limits->effort);
    h.add(j.limits->velocity);
    h.add(j.limits->position);
  }
  h.add(j.damping);
  h.add(j.friction);
  h.add(j.spring_stiffness);
}

}  // namespace

CheckDigest check_digest(const std::string& source, const std::string& settings_key, const Robot& robot,
                         const LinkBounds& bounds) {
  Hasher h;
  h.add(source);
  h.add(settings_key);
  h.add(robot.name);
  h.add(robot.root_links);
  h.count(robot.links.size());
  for (const Link& l : robot.links) add(h, l);
  h.count(robot.joints.size());
  for (const Joint& j : robot.joints) add(h, j);
  h.count(bounds.size());
  for (const auto& box : bounds) {
    h.add(box.has_value());
    if (box) {
      h.matrix(box->min());
      h.matrix(box->max());
    }
  }
  return h.finish();
}

}  // namespace rdtf::daemon
