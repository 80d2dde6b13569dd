// rdtf-echo on rdtf_client: started after rdtfd published (republishing off), it asks at start and
// prints the live revision of every model, reassembled and checked (--snapshots).
#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

constexpr const char* kArm = "arm3.gltf";

TEST(Echo, ALateEchoAsksAtStartAndPrintsEveryLiveRevision) {
  Session s;
  copy_fixture(s.watch, "arm3");
  const GeneratedModel big = many_parts_model("big", 1500, 0.01);  // RDTF JSON in several chunks
  write_model(s.watch, "big.gltf", big);
  s.start();
  ASSERT_TRUE(s.wait_revision(kArm, 1, fixture_hash("arm3")));
  ASSERT_TRUE(s.wait_revision("big.gltf", 1, content_hash(big)));
  // Only its snapshot lines: no channel matches -c.
  ChildProcess echo({RDTF_ECHO_PATH, "-c", "NOTHING", "--snapshots", "-n", "2"}, s.root / "echo.out");
  ASSERT_EQ(echo.wait_exit(10s), std::optional<int>(0)) << echo.output();
  std::map<std::string, Json> snapshots;
  std::istringstream lines(echo.output());
  for (std::string line; std::getline(lines, line);) {
    const Json j = Json::parse(line);
    snapshots[j["snapshot"]["model_id"].get<std::string>()] = j["snapshot"];
  }
  ASSERT_EQ(snapshots.size(), 2u) << echo.output();
  const auto arm = last_description(s.messages(), kArm);
  const auto chunked = last_description(s.messages(), "big.gltf");
  ASSERT_TRUE(arm && chunked);
  EXPECT_GT(chunked->num_chunks, 1);
  for (const rdtf::description_t& d : std::vector<rdtf::description_t>{*arm, *chunked}) {
    const Json& got = snapshots[d.model_id];
    EXPECT_EQ(got["revision"], d.revision);
    EXPECT_EQ(got["content_hash"], d.content_hash);
    EXPECT_EQ(got["rdtf_json_size"], d.rdtf_json_size);
    EXPECT_EQ(got["urdf_size"], d.urdf_size);
    EXPECT_EQ(got["num_links"], d.num_links);
  }
}

// Any peer can put any bytes in an LCM string. A REQUEST whose strings are not UTF-8 (it killed
// every rdtf-echo on the bus: the JSON printer threw) prints with U+FFFD in their place.
TEST(Echo, StringsThatAreNotUtf8PrintReplaced) {
  Session s;
  s.start();
  ChildProcess echo({RDTF_ECHO_PATH, "-c", "RDTF/REQUEST", "--no-request", "-n", "1"}, s.root / "echo.out");
  rdtf::request_t request;
  request.model_id = "\xff\xfe\xc0\xaf";
  request.requester = "mallory\xff";
  std::optional<int> exit;
  // Sent until the echo, which may not have subscribed yet, has printed it.
  for (int tries = 0; tries < 50 && !exit; ++tries) {
    s.subscriber.publish("RDTF/REQUEST", request);
    exit = echo.wait_exit(100ms);
  }
  ASSERT_EQ(exit, std::optional<int>(0)) << echo.output();
  const Json line = Json::parse(echo.output().substr(0, echo.output().find('\n')));
  EXPECT_EQ(line["message"]["requester"], "mallory\xef\xbf\xbd") << line.dump();
  EXPECT_EQ(line["message"]["model_id"], "\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd\xef\xbf\xbd") << line.dump();
}

}  // namespace
}  // namespace rdtf::itest
