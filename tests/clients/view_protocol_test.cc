// rdtf-view's checks of what pages send (clients/view/page_protocol.h) and of request paths and
// WebSocket origins (clients/view/http_paths.h), and the sliders' per-joint gains (joint_gains.h).
#include <gtest/gtest.h>

#include <string>
#include <variant>

#include <cmath>
#include <numbers>

#include <nlohmann/json.hpp>

#include "diagnostic_message.h"
#include "http_paths.h"
#include "model_hub.h"
#include "page_protocol.h"

namespace rdtf::view {
namespace {

Catalog arm_catalog() {
  CommandableModel arm;
  arm.revision = 3;
  arm.simulated = true;
  arm.joints["shoulder"] = MovableJoint{-1.57, 1.57};
  arm.joints["elbow"] = MovableJoint{};  // continuous
  return {{"arm3.gltf", arm}};
}

std::string refusal(const PageRequest& request) {
  const auto* r = std::get_if<Refusal>(&request);
  return r ? r->reason : "";
}

TEST(ViewPageProtocol, TakesASetJointWithinTheLimits) {
  const auto request = parse_page_message(R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":1.57})",
                                          arm_catalog());
  ASSERT_TRUE(std::holds_alternative<SetJoint>(request)) << refusal(request);
  const auto& set = std::get<SetJoint>(request);
  EXPECT_EQ(set.model_id, "arm3.gltf");
  EXPECT_EQ(set.joint, "shoulder");
  EXPECT_EQ(set.value, 1.57);
  const auto release = parse_page_message(R"({"type":"release","model":"arm3.gltf"})", arm_catalog());
  ASSERT_TRUE(std::holds_alternative<Release>(release)) << refusal(release);
  EXPECT_EQ(std::get<Release>(release).model_id, "arm3.gltf");
}

TEST(ViewPageProtocol, RefusesEveryHostileMessageWithItsReason) {
  const Catalog catalog = arm_catalog();
  const std::pair<std::string, std::string> cases[] = {
      {"", "not JSON"},
      {"{\"type\":", "not JSON"},
      {"[1,2,3]", "not a JSON object"},
      {"{\"model\":\"arm3.gltf\"}", "no \"type\" string"},
      {R"({"type":"fly"})", "unknown type 'fly'"},
      {R"({"type":"set_joint","model":"arm9.gltf","joint":"shoulder","value":0})", "unknown model 'arm9.gltf' (not live on the bus)"},
      {R"({"type":"set_joint","model":7,"joint":"shoulder","value":0})", "\"model\" must be a string (a model id)"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"wrist","value":0})",
       "model 'arm3.gltf' revision 3 has no movable joint 'wrist'"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":["shoulder"],"value":0})", "\"joint\" must be a string (a joint's URDF name)"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":null})", "\"value\" must be a number, not null"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":"0.1"})", "\"value\" must be a number, not string"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":[1,2]})", "\"value\" must be a number, not array"},
      // nlohmann's parser refuses a number that overflows a double: no infinity gets through.
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":1e999})", "not JSON"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":NaN})", "not JSON"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":1.5700000000000001e0,"kp":5})", "unknown key 'kp' in a set_joint message"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder"})", "a set_joint message needs \"value\""},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":1.58})",
       "value 1.58 of joint 'shoulder' outside its limits [-1.57, 1.57]"},
      {R"({"type":"set_joint","model":"arm3.gltf","joint":"elbow","value":-10001})", "value -10001 of joint 'elbow' outside its limits [-10000, 10000]"},
      {R"({"type":"release","model":"arm3.gltf","all":true})", "unknown key 'all' in a release message"},
  };
  for (const auto& [text, reason] : cases) EXPECT_EQ(refusal(parse_page_message(text, catalog)), reason) << text;
  // Bytes that are not printable come back escaped, never raw.
  EXPECT_EQ(refusal(parse_page_message("{\"type\":\"set_joint\",\"model\":\"a\\u0001b\",\"joint\":\"x\",\"value\":0}", catalog)),
            "unknown model 'a\\x01b' (not live on the bus)");
}

TEST(ViewPageProtocol, RefusesHugeMessagesBeforeParsingAndModelsNotSimulated) {
  const std::string huge = "{\"type\":\"set_joint\",\"pad\":\"" + std::string(5000, 'x') + "\"}";
  EXPECT_EQ(refusal(parse_page_message(huge, arm_catalog())), "message of 5029 bytes, more than 4096");
  Catalog idle = arm_catalog();
  idle["arm3.gltf"].simulated = false;
  EXPECT_EQ(refusal(parse_page_message(R"({"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":0})", idle)),
            "model 'arm3.gltf' is not simulated (no JOINT_STATE heard)");
}

TEST(ViewPageProtocol, RateLimiterAllowsTheBurstThenTheRate) {
  RateLimiter limiter(8, 20);  // times below are exact in binary: 1/16 s is half a token
  int allowed = 0;
  for (int i = 0; i < 100; ++i) allowed += limiter.allow(5.0);
  EXPECT_EQ(allowed, 20);
  EXPECT_FALSE(limiter.allow(5.0625));  // half a token
  EXPECT_TRUE(limiter.allow(5.125));    // one token since 5.0
  EXPECT_FALSE(limiter.allow(5.125));
  allowed = 0;
  for (int i = 0; i < 100; ++i) allowed += limiter.allow(1000.0);  // refilled to the burst, not beyond
  EXPECT_EQ(allowed, 20);
}

TEST(ViewHttpPaths, RoutesThePageThreeAndModelFiles) {
  EXPECT_EQ(route("/").kind, Route::Kind::kPage);
  EXPECT_EQ(route("/ws").kind, Route::Kind::kSocket);
  const Route app = route("/app/model.js?v=1");
  EXPECT_EQ(app.kind, Route::Kind::kApp);
  EXPECT_EQ(app.path, "model.js");
  const Route three = route("/three/examples/jsm/loaders/GLTFLoader.js");
  EXPECT_EQ(three.kind, Route::Kind::kThree);
  EXPECT_EQ(three.path, "examples/jsm/loaders/GLTFLoader.js");
  const std::string url = model_file_url("arms/arm 3.gltf", 12, "arm 3.rdtf.gltf");
  EXPECT_EQ(url, "/model/arms%2Farm%203.gltf/12/arm%203.rdtf.gltf");
  const Route file = route(url);
  EXPECT_EQ(file.kind, Route::Kind::kModelFile);
  EXPECT_EQ(file.model_id, "arms/arm 3.gltf");
  EXPECT_EQ(file.revision, 12);
  EXPECT_EQ(file.path, "arm 3.rdtf.gltf");
  EXPECT_EQ(route("/model/a.gltf/2/urdf/meshes/base.stl").path, "urdf/meshes/base.stl");
}

// A model's files are named by whoever writes into rdtfd's folder: no name makes one a document
// or a script of the viewer's origin.
TEST(ViewHttpPaths, AModelFileIsNeverServedAsActiveContent) {
  for (const char* name : {"payload.0123abcd.html", "img.htm", "x.js", "x.mjs", "x.svg", "x.css", "x.xml", "x.urdf",
                           "x.xhtml", "x.bin", "noextension"}) {
    EXPECT_EQ(model_file_content_type(name), "application/octet-stream") << name;
  }
  EXPECT_EQ(model_file_content_type("arm.rdtf.gltf"), "model/gltf+json");
  EXPECT_EQ(model_file_content_type("arm.glb"), "model/gltf-binary");
  EXPECT_EQ(model_file_content_type("checker.0a1b.png"), "image/png");
  EXPECT_EQ(model_file_content_type("photo.jpeg"), "image/jpeg");
  EXPECT_EQ(content_type("index.html"), "text/html; charset=utf-8");  // The page's own, from its folder.
}

TEST(ViewHttpPaths, RefusesPathsOutsideTheirFolders) {
  for (const char* bad : {"/app/../main.cc", "/app/%2e%2e", "/app/a/b.js", "/app/x%2fy.js", "/three/../../etc/passwd",
                          "/three/build/../../../x.js", "/three/src/Three.js", "/three/build/three.module.js%00",
                          "/three/build/x.json", "/model/a.gltf/0/a.gltf", "/model/a.gltf/-1/a.gltf",
                          "/model/a.gltf/1x/a.gltf", "/model/a.gltf/1/../b", "/model/a.gltf/1//b", "/model/a.gltf/1/a%5cb",
                          "/model/%zz/1/a", "/model/a.gltf/1", "/etc/passwd", "relative", "/model/a.gltf/1/a%"}) {
    EXPECT_EQ(route(bad).kind, Route::Kind::kNotFound) << bad;
  }
  EXPECT_EQ(percent_decode("a%20b%2F"), std::optional<std::string>("a b/"));
  EXPECT_FALSE(percent_decode("%00"));
  EXPECT_FALSE(percent_decode("%4"));
}

// One decoder for request paths and glTF URIs (rdtf/percent_decode.h), with the reason.
TEST(PercentDecode, DecodesEveryEscapeAndSaysWhyNot) {
  std::string why;
  EXPECT_EQ(rdtf::percent_decode("mesh%20one+two%2Fx%C3%A9.bin", &why), std::optional<std::string>("mesh one+two/x\xC3\xA9.bin"));
  EXPECT_EQ(why, "");
  EXPECT_FALSE(rdtf::percent_decode("a.bin%00.png", &why));
  EXPECT_EQ(why, "the URI encodes a NUL byte (%00) at byte 5");
  EXPECT_FALSE(rdtf::percent_decode("ab%4", &why));
  EXPECT_EQ(why, "malformed percent-escape at byte 2");
  EXPECT_FALSE(rdtf::percent_decode("ab%g1", &why));
  EXPECT_EQ(why, "malformed percent-escape at byte 2");
  EXPECT_FALSE(rdtf::percent_decode("%", &why));
  EXPECT_EQ(rdtf::percent_decode("%41%62"), std::optional<std::string>("Ab"));
}

TEST(ViewHttpPaths, WebSocketOnlyFromTheViewersOwnPage) {
  EXPECT_EQ(check_socket_origin("127.0.0.1:8765", "http://127.0.0.1:8765", true, 8765), "");
  EXPECT_EQ(check_socket_origin("localhost:8765", "http://localhost:8765", true, 8765), "");
  EXPECT_EQ(check_socket_origin("[::1]:8765", "http://[::1]:8765", true, 8765), "");
  EXPECT_EQ(check_socket_origin("127.0.0.1:8765", "http://evil.example", true, 8765),
            "Origin 'http://evil.example' is not this viewer's page (http://127.0.0.1:8765)");
  EXPECT_EQ(check_socket_origin("127.0.0.1:8765", "", true, 8765),
            "Origin '' is not this viewer's page (http://127.0.0.1:8765)");
  // DNS rebinding: a name that resolves to loopback, Origin and Host alike.
  EXPECT_EQ(check_socket_origin("evil.example:8765", "http://evil.example:8765", true, 8765),
            "Host 'evil.example:8765' is not a loopback address (the viewer is bound to loopback)");
  EXPECT_EQ(check_socket_origin("127.0.0.1:9999", "http://127.0.0.1:9999", true, 8765),
            "Host '127.0.0.1:9999' does not name port 8765");
  EXPECT_NE(check_socket_origin("127.0.0.256:8765", "http://127.0.0.256:8765", true, 8765), "");
  // Bound to another address on purpose: any host, still only its own page.
  EXPECT_EQ(check_socket_origin("robot.lan:8765", "http://robot.lan:8765", false, 8765), "");
  EXPECT_NE(check_socket_origin("robot.lan:8765", "http://evil.example", false, 8765), "");
}

}  // namespace
}  // namespace rdtf::view

namespace rdtf::view {
namespace {

// shoulder (about z) moves upper and, through elbow, fore; elbow (about its x) moves fore; slide
// (along x) moves carriage and, through a fixed joint, tool. Hand-computed in the comments.
constexpr const char* kGainsUrdf = R"(<robot name="gains">
  <link name="base"><inertial><mass value="50"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/>
    <origin xyz="0 0 1" rpy="0 0 0"/><axis xyz="0 0 2"/><limit lower="-1" upper="1" effort="10" velocity="1"/></joint>
  <link name="upper"><inertial><origin xyz="0.5 0 0" rpy="0 0 0"/><mass value="2"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial></link>
  <joint name="elbow" type="continuous"><parent link="upper"/><child link="fore"/>
    <origin xyz="1 0 0" rpy="0 0 1.5707963267948966"/><axis xyz="1 0 0"/></joint>
  <link name="fore"><inertial><origin xyz="0 0.5 0.25" rpy="1.5707963267948966 0 0"/><mass value="1"/>
    <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.4"/></inertial></link>
  <joint name="slide" type="prismatic"><parent link="base"/><child link="carriage"/>
    <origin xyz="0 1 0" rpy="0.3 0.2 0.1"/><axis xyz="1 0 0"/><limit lower="0" upper="0.5" effort="100" velocity="1"/></joint>
  <link name="carriage"><inertial><mass value="3"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <joint name="tool_mount" type="fixed"><parent link="carriage"/><child link="tool"/><origin xyz="0.2 0 0"/></joint>
  <link name="tool"><inertial><mass value="0.5"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
</robot>)";

TEST(ViewJointGains, FollowTheInertiaEachJointMoves) {
  std::string error;
  const auto joints = joints_of_urdf(kGainsUrdf, &error);
  ASSERT_EQ(error, "");
  std::map<std::string, JointInfo> by_name;
  for (const auto& j : joints) by_name[j.name] = j;
  ASSERT_EQ(by_name.size(), 4u);
  // shoulder: upper izz + m d^2 = 0.3 + 2 (0.5)^2 = 0.8; fore's centre of mass in the shoulder
  // frame is (1, 0, 0) + Rz(90) (0, 0.5, 0.25) = (0.5, 0, 0.25), 0.5 off the axis, and the axis is
  // fore's inertial y (Rz(90) Rx(90) takes y to z): 0.2 + 1 (0.5)^2 = 0.45. Total 1.25.
  EXPECT_NEAR(by_name["shoulder"].moved_inertia, 1.25, 1e-12);
  // elbow: about fore's x, which is the inertial x: 0.1 + 1 (0.5^2 + 0.25^2) = 0.4125.
  EXPECT_NEAR(by_name["elbow"].moved_inertia, 0.4125, 1e-12);
  // slide: the mass it carries, 3 + 0.5, whatever the orientation.
  EXPECT_NEAR(by_name["slide"].moved_inertia, 3.5, 1e-12);
  EXPECT_EQ(by_name["tool_mount"].moved_inertia, 0);

  // kp = M w^2, kd = 2 M w, w = 2 pi f.
  const double w = 2 * std::numbers::pi * 4;
  const Gains g = gains_for(1.25, 4);
  EXPECT_NEAR(g.kp, 1.25 * w * w, 1e-12 * g.kp);
  EXPECT_NEAR(g.kd, 2 * 1.25 * w, 1e-12 * g.kd);
  // The rule gives every joint the same damping ratio (1) and frequency: kd^2 = 4 M kp.
  for (const auto& name : {"shoulder", "elbow", "slide"}) {
    const GainRule rule;
    const Gains j = rule.of(by_name[name]);
    EXPECT_NEAR(j.kd * j.kd, 4 * by_name[name].moved_inertia * j.kp, 1e-12 * j.kd * j.kd) << name;
    EXPECT_NEAR(std::sqrt(j.kp / by_name[name].moved_inertia), 2 * std::numbers::pi * rule.frequency_hz, 1e-12) << name;
  }
  // --kp / --kd replace the rule for every joint.
  GainRule fixed;
  fixed.kp = 200;
  const Gains f = fixed.of(by_name["elbow"]);
  EXPECT_EQ(f.kp, 200);
  EXPECT_NEAR(f.kd, 2 * 0.4125 * w, 1e-12 * f.kd);
}

// SAVING reaches the pages when it names the revision they draw, with rdtfd's settle period; one
// of an unknown model, of another revision, or with a settle period rdtfd cannot have (a page
// would hold its motion for that long), does not.
TEST(ViewHub, ASavingOfTheDrawnRevisionIsToldToThePagesAndOthersAreNot) {
  std::vector<nlohmann::json> sent;
  ModelHub hub(GainRule{}, [&](std::shared_ptr<const std::string> json) { sent.push_back(nlohmann::json::parse(*json)); },
               [](const std::string&, rdtf::joint_command_t&) {});
  hub.on_models_seen({"pending.gltf"});
  auto snapshot = std::make_shared<rdtf::client::Snapshot>();
  snapshot->description.model_id = "arm3.gltf";
  snapshot->description.revision = 4;
  snapshot->description.urdf = R"(<robot name="arm"><link name="base"/></robot>)";
  hub.on_revision(snapshot);
  sent.clear();
  rdtf::model_saving_t saving;
  saving.model_id = "arm3.gltf";
  saving.live_revision = 4;
  saving.settle_ms = 50;
  hub.on_saving(saving);
  ASSERT_EQ(sent.size(), 1u);
  EXPECT_EQ(sent[0], nlohmann::json::parse(R"({"type": "saving", "id": "arm3.gltf", "live_revision": 4, "settle_ms": 50})"));
  for (const int settle_ms : {-1, 60001, 2147483647}) {
    saving.settle_ms = settle_ms;
    hub.on_saving(saving);
  }
  saving.settle_ms = 50;
  saving.live_revision = 3;
  hub.on_saving(saving);
  saving.model_id = "pending.gltf";  // known, nothing drawn
  saving.live_revision = 0;
  hub.on_saving(saving);
  saving.model_id = "other.gltf";
  hub.on_saving(saving);
  EXPECT_EQ(sent.size(), 1u);
}

// A GLB's container error has no JSON pointer: its place is the byte offset, which the page shows.
TEST(ViewHub, AnErrorKeepsItsByteOffset) {
  std::vector<nlohmann::json> sent;
  ModelHub hub(GainRule{}, [&](std::shared_ptr<const std::string> json) { sent.push_back(nlohmann::json::parse(*json)); },
               [](const std::string&, rdtf::joint_command_t&) {});
  rdtf::model_error_t error;
  error.model_id = "chain.glb";
  error.live_revision = 0;
  Diagnostics diag("/models/chain.glb");
  diag.error_at_offset("GLB_LENGTH_MISMATCH", 8, "header says 1948 bytes but the file has 500");
  diag.error("URI_REFUSED", "/buffers/0/uri", "no offset here");
  for (const Diagnostic& d : diag.all()) error.diagnostics.push_back(to_message(d));
  error.num_diagnostics = static_cast<std::int32_t>(error.diagnostics.size());
  hub.on_error(error);
  ASSERT_FALSE(sent.empty());
  const auto& diagnostics = sent.back()["error"]["diagnostics"];
  ASSERT_EQ(diagnostics.size(), 2u) << sent.back().dump();
  EXPECT_EQ(diagnostics[0]["byte_offset"], 8);
  EXPECT_FALSE(diagnostics[1].contains("byte_offset"));
}

}  // namespace
}  // namespace rdtf::view
