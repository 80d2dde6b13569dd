// Properties of a moving joint given without its type (s101fmt D8): the joint is fixed by default,
// so an empty given an axis, limits and damping but no rdtf_joint made a fixed joint without a word.
#include <gtest/gtest.h>

#include "rdtf/convert.h"
#include "rdtf/diagnostic_codes.h"
#include "urdf/urdf_test_support.h"

namespace rdtf {
namespace {

using urdf_test::GltfBuilder;

std::vector<Diagnostic> warnings_of(const Diagnostics& diag) {
  std::vector<Diagnostic> found;
  for (const Diagnostic& d : diag.all()) {
    if (d.code == codes::JOINT_TYPE_MISSING) found.push_back(d);
  }
  return found;
}

// base, then an empty `elbow` with `keys` in its extras, then the forearm.
GltfBuilder elbow(const Json& keys) {
  GltfBuilder b;
  const int base = b.node("base", -1, Json{{"mesh", b.box_mesh({0.2f, 0.1f, 0.2f})}});
  const int joint = b.node("elbow", base, Json{{"translation", {0, 0.2, 0}}, {"extras", keys}});
  b.link_with_mesh("forearm", joint, b.box_mesh({0.05f, 0.3f, 0.05f}));
  return b;
}

TEST(JointTypeMissing, MovingJointPropertiesWithoutATypeAreNamed) {
  Diagnostics diag;
  const Conversion c =
      elbow(Json{{"rdtf_axis", {1, 0, 0}}, {"rdtf_lower", -1}, {"rdtf_upper", 1}, {"rdtf_damping", 0.5}}).convert(diag);
  const auto found = warnings_of(diag);
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].severity, Severity::kWarning);
  EXPECT_EQ(found[0].pointer, "/nodes/1/extras");
  EXPECT_EQ(found[0].message,
            "node 1 'elbow': rdtf_axis, rdtf_lower, rdtf_upper, rdtf_damping given without rdtf_joint, so the joint is "
            "fixed and they do nothing; set rdtf_joint to revolute, continuous or prismatic, or remove them");
  for (const Joint& joint : c.robot.joints) EXPECT_EQ(joint.kind, JointKind::kFixed);
}

TEST(JointTypeMissing, ATypedJointOrAFixedOneSaysNothing) {
  for (const Json& keys : {Json{{"rdtf_joint", "revolute"}, {"rdtf_axis", {1, 0, 0}}, {"rdtf_lower", -1}},
                           Json{{"rdtf_joint", "fixed"}}}) {
    SCOPED_TRACE(keys.dump());
    Diagnostics diag;
    elbow(keys).convert(diag);
    EXPECT_TRUE(warnings_of(diag).empty());
  }
}

}  // namespace
}  // namespace rdtf
