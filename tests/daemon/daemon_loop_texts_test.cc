// A live revision's .rdtf.gltf document and URDF are held in memory only until its first
// publication; later ones (requests, republishing) read them back from the output files. With the
// loop stepped in-process (daemon_loop.h): what a subscriber gets is byte for byte what the first
// publication sent, and an output changed behind rdtfd's back is not described from.
#include <fstream>

#include "daemon_loop.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

class DaemonLiveTexts : public DaemonLoop {
 protected:
  // The full pipeline (the gate, the URDF), as rdtfd runs by default; no live simulation.
  void start_full(ConfigLoader reload = {}) {
    rdtf::testing::write_file(watch_ / "arm3.glb", fixture("arm3.glb"));
    rdtf::testing::write_file(watch_ / "two_cylinder.gltf", fixture("two_cylinder.gltf"));
    rdtf::testing::write_file(watch_ / "two_cylinder.bin", fixture("two_cylinder.bin"));
    start(
        [](DaemonConfig& config) {
          config.validate = true;
          config.urdf = true;
        },
        std::move(reload));
    advance(50ms);  // The settle of the initial scan.
    convert();
  }
  // Every message about `id`'s revision (description, inertia table, verdict, manifest), in order,
  // with the time of sending (every type's first field, after the 8-byte fingerprint) zeroed.
  std::vector<std::string> revision_messages(const std::string& id) {
    std::vector<std::string> out;
    for (const auto& sent : bus_->sent) {
      if (sent.channel.rfind("RDTF/" + id + "/", 0) != 0) continue;
      const auto kind = sent.channel.substr(sent.channel.rfind('/') + 1);
      if (kind != "DESCRIPTION" && kind != "INERTIA" && kind != "VALIDATION" && kind != "MANIFEST") continue;
      std::string bytes(sent.bytes.begin(), sent.bytes.end());
      EXPECT_GE(bytes.size(), 16u);
      if (bytes.size() >= 16) bytes.replace(8, 8, 8, '\0');
      out.push_back(sent.channel + " " + bytes);
    }
    return out;
  }
  const ModelRecord& record(const std::string& name) {
    const ModelRecord* found = daemon_->registry().find_id(name);
    EXPECT_NE(found, nullptr) << name;
    return *found;
  }
  void request(const std::string& id) {
    bus_->incoming.emplace_back("RDTF/REQUEST", fakes::encode_request(id, "test"));
    step();
    // The send queue drains at its byte rate on the loop's clock: time for every answer to go out.
    for (int i = 0; i < 20; ++i) advance(10ms);
  }
};

TEST_F(DaemonLiveTexts, RequestsAreAnsweredByteForByteAsTheFirstPublicationFromTheOutputFiles) {
  start_full();
  std::map<std::string, std::vector<std::string>> published;
  for (const std::string id : {"arm3.glb", "two_cylinder.gltf"}) published[id] = revision_messages(id);
  for (const auto& [id, first] : published) {
    SCOPED_TRACE(id);
    ASSERT_EQ(first.size(), 4u);  // VALIDATION, MANIFEST, DESCRIPTION, INERTIA
    // Once published, the record no longer holds the texts; the files it wrote do.
    const ModelRecord& model = record(id);
    ASSERT_TRUE(model.live);
    EXPECT_TRUE(model.texts_on_disk);
    EXPECT_TRUE(model.live->rdtf_json.empty());
    EXPECT_TRUE(model.live->urdf.empty());
    LiveTexts texts;
    std::string why;
    ASSERT_TRUE(live_texts(model, texts, why)) << why;
    EXPECT_EQ(texts.rdtf_json, rdtf::testing::read_file(model.live->output_path));
    EXPECT_EQ(texts.urdf, rdtf::testing::read_file(model.live->urdf_path));
    EXPECT_FALSE(texts.urdf.empty());

    clear_bus();
    request(id);
    EXPECT_EQ(revision_messages(id), first);
  }
  // Every model at once ("" asks for all): the same again.
  clear_bus();
  request("");
  EXPECT_EQ(revision_messages("arm3.glb").size(), 4u);
  EXPECT_EQ(revision_messages("two_cylinder.gltf").size(), 4u);
}

TEST_F(DaemonLiveTexts, AnOutputChangedOnDiskIsNotDescribedAndTheOtherModelsStillAre) {
  start_full();
  const fs::path document = record("arm3.glb").live->output_path;
  {
    std::ofstream out(document, std::ios::binary | std::ios::app);
    out << ' ';  // Still JSON, but not the bytes rdtfd wrote.
  }
  LiveTexts texts;
  std::string why;
  EXPECT_FALSE(live_texts(record("arm3.glb"), texts, why));
  EXPECT_NE(why.find("no longer the file rdtfd wrote"), std::string::npos) << why;

  clear_bus();
  request("");
  EXPECT_TRUE(revision_messages("arm3.glb").empty()) << "described from a file rdtfd did not write";
  EXPECT_EQ(revision_messages("two_cylinder.gltf").size(), 4u);

  fs::remove(record("two_cylinder.gltf").live->urdf_path);
  EXPECT_FALSE(live_texts(record("two_cylinder.gltf"), texts, why));
  EXPECT_NE(why.find("cannot read"), std::string::npos) << why;
}

TEST_F(DaemonLiveTexts, ANewRevisionIsPublishedWithItsOwnTextsAndThenReleasesThem) {
  start_full();
  const std::string first_json = rdtf::testing::read_file(record("two_cylinder.gltf").live->output_path);
  // An asset copyright: other content, and another document (the asset is carried over).
  std::string gltf = fixture("two_cylinder.gltf");
  const std::string from = "\"generator\"";
  ASSERT_NE(gltf.find(from), std::string::npos);
  gltf.replace(gltf.find(from), from.size(), "\"copyright\":\"rdtf test\",\"generator\"");
  clear_bus();
  save("two_cylinder.gltf", gltf);
  advance(50ms);
  convert();
  EXPECT_EQ(events("two_cylinder.gltf"), (std::vector<std::string>{"DESCRIPTION r2", "INERTIA"}));
  const ModelRecord& model = record("two_cylinder.gltf");
  EXPECT_EQ(model.revisions, 2);
  EXPECT_TRUE(model.texts_on_disk);
  LiveTexts texts;
  std::string why;
  ASSERT_TRUE(live_texts(model, texts, why)) << why;
  EXPECT_NE(texts.rdtf_json, first_json);
  const auto published = revision_messages("two_cylinder.gltf");
  clear_bus();
  request("two_cylinder.gltf");
  EXPECT_EQ(revision_messages("two_cylinder.gltf"), published);
}

// A reload that changes a setting every result depends on in general, but not these models'
// results, converts them again and finds the same result: no new revision, though the live
// revision's texts are on disk only (the manifests, with both texts' SHA-256, are compared).
TEST_F(DaemonLiveTexts, AReloadThatGivesTheSameResultKeepsTheRevisionOfTextsOnDisk) {
  start_full([this](std::string&) -> std::optional<DaemonConfig> {
    DaemonConfig fresh = config_;
    fresh.convert.limits.max_file_bytes = config_.convert.limits.max_file_bytes / 2;  // Still far above the fixtures.
    return fresh;
  });
  ASSERT_TRUE(record("arm3.glb").texts_on_disk);
  const auto converted = daemon_->counters().conversions;
  clear_bus();
  daemon_->reload_config();
  for (int i = 0; i < 5; ++i) {
    advance(50ms);
    convert();
  }
  EXPECT_EQ(daemon_->counters().skipped_unchanged, 2);
  EXPECT_EQ(daemon_->counters().conversions, converted);
  EXPECT_TRUE(events("arm3.glb").empty()) << ::testing::PrintToString(events("arm3.glb"));
  EXPECT_TRUE(events("two_cylinder.gltf").empty()) << ::testing::PrintToString(events("two_cylinder.gltf"));
  EXPECT_EQ(record("arm3.glb").revisions, 1);
  EXPECT_EQ(record("two_cylinder.gltf").revisions, 1);
}

}  // namespace
}  // namespace rdtf::daemon
