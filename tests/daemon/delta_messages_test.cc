// make_deltas and make_manifests: a delta or a manifest too long for one datagram goes in parts,
// each within the limit, together every row once and in order.
#include <gtest/gtest.h>

#include "blob_manifest.h"
#include "delta_messages.h"
#include "messages.h"
#include "registry.h"
#include "conversion.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf::daemon {
namespace {

// Every part within `limit` bytes, numbered 0..n-1 of n.
template <typename Part>
void expect_numbered_parts_within(const std::vector<Part>& parts, std::size_t limit) {
  for (std::size_t p = 0; p < parts.size(); ++p) {
    EXPECT_LE(static_cast<std::size_t>(parts[p].getEncodedSize()), limit) << "part " << p;
    EXPECT_EQ(parts[p].part, static_cast<std::int32_t>(p));
    EXPECT_EQ(parts[p].num_parts, static_cast<std::int32_t>(parts.size()));
  }
}

TEST(DeltaMessages, ManyChangesGoInPartsEachWithinTheLimit) {
  std::vector<ElementChange> changes;
  for (int i = 0; i < 500; ++i) {
    changes.push_back({i % 2 ? ElementChange::Element::kJoint : ElementChange::Element::kLink,
                       ElementChange::Kind::kChanged, "element_" + std::to_string(i), "urdf_" + std::to_string(i),
                       kAspectOrigin | kAspectLimits});
  }
  const DeltaHeader header{"arm.gltf", 3, "aaa", 5, "bbb"};
  constexpr std::size_t kLimit = 2000;
  const auto parts = make_deltas(header, changes, 42, kLimit);
  ASSERT_GT(parts.size(), 1u);
  expect_numbered_parts_within(parts, kLimit);
  std::size_t next = 0;
  for (const auto& part : parts) {
    EXPECT_EQ(part.total_changes, 500);
    EXPECT_EQ(part.num_changes, static_cast<std::int32_t>(part.changes.size()));
    EXPECT_EQ(part.previous_revision, 3);
    EXPECT_EQ(part.previous_content_hash, "aaa");
    EXPECT_EQ(part.revision, 5);
    EXPECT_EQ(part.content_hash, "bbb");
    EXPECT_EQ(part.utime, 42);
    for (const auto& c : part.changes) {
      EXPECT_EQ(c.name, "element_" + std::to_string(next));
      EXPECT_EQ(c.urdf_name, "urdf_" + std::to_string(next));
      EXPECT_EQ(c.element, next % 2 ? "joint" : "link");
      EXPECT_EQ(c.change, "changed");
      EXPECT_EQ(c.aspects, (std::vector<std::string>{"origin", "limits"}));
      EXPECT_EQ(c.num_aspects, 2);
      ++next;
    }
  }
  EXPECT_EQ(next, 500u);
}

TEST(ManifestMessages, ManyFilesGoInPartsEachWithinTheLimit) {
  std::vector<OutputFile> files;
  for (int i = 0; i < 300; ++i) {
    files.push_back({"urdf/meshes/part_" + std::to_string(i) + ".stl", std::string(64, 'a' + i % 6), 1000 + i,
                     "urdf_mesh"});
  }
  constexpr std::size_t kLimit = 3000;
  const auto parts = make_manifests("arm.gltf", 7, "ccc", files, kLimit);
  ASSERT_GT(parts.size(), 1u);
  expect_numbered_parts_within(parts, kLimit);
  std::size_t next = 0;
  for (const auto& part : parts) {
    EXPECT_EQ(part.total_files, 300);
    EXPECT_EQ(part.num_files, static_cast<std::int32_t>(part.files.size()));
    EXPECT_EQ(part.model_id, "arm.gltf");
    EXPECT_EQ(part.revision, 7);
    EXPECT_EQ(part.content_hash, "ccc");
    for (const auto& row : part.files) {
      ASSERT_LT(next, files.size());
      EXPECT_EQ(row.path, files[next].path);
      EXPECT_EQ(row.sha256, files[next].sha256);
      EXPECT_EQ(row.size, files[next].size);
      EXPECT_EQ(row.role, "urdf_mesh");
      ++next;
    }
  }
  EXPECT_EQ(next, files.size());
  // No file: one part that says so.
  const auto none = make_manifests("arm.gltf", 7, "ccc", {}, kLimit);
  ASSERT_EQ(none.size(), 1u);
  EXPECT_EQ(none[0].num_files, 0);
  EXPECT_EQ(none[0].num_parts, 1);
}

// A report cut to one datagram keeps the most severe diagnostics, in their own order: it kept the
// infos that came first and dropped the warnings after them (s100java D2: arm3's
// URDF_REVOLUTE_WITHOUT_LIMITS lost at max_chunk_bytes 1400).
TEST(ValidationMessages, AReportCutToSizeKeepsTheMostSevere) {
  ValidationSummary summary;
  summary.passed = true;
  for (int k = 0; k < 20; ++k) {
    summary.diagnostics.info(codes::LINK_MESH_SPLIT, "/nodes/" + std::to_string(k), std::string(60, 'i'));
  }
  for (int k = 0; k < 3; ++k) {
    summary.diagnostics.warning(codes::URDF_REVOLUTE_WITHOUT_LIMITS, "/nodes/" + std::to_string(k), std::string(60, 'w'));
  }
  const auto report = make_validation_report("arm.gltf", 1, "aaa", summary, 1400);
  EXPECT_LE(static_cast<std::size_t>(report.getEncodedSize()), 1400u);
  ASSERT_GE(report.diagnostics.size(), 5u);
  std::size_t warnings = 0, infos = 0;
  for (std::size_t k = 0; k + 1 < report.diagnostics.size(); ++k) {
    warnings += report.diagnostics[k].code == "URDF_REVOLUTE_WITHOUT_LIMITS";
    infos += report.diagnostics[k].code == "LINK_MESH_SPLIT";
    // Their own order: the infos kept come before the warnings, as found.
    if (k > 0 && report.diagnostics[k].code == "LINK_MESH_SPLIT") {
      EXPECT_EQ(report.diagnostics[k - 1].code, "LINK_MESH_SPLIT");
    }
  }
  EXPECT_EQ(warnings, 3u);
  EXPECT_GT(infos, 0u);
  EXPECT_LT(infos, 20u);
  const auto& note = report.diagnostics.back();
  EXPECT_EQ(note.code, "DIAGNOSTICS_TRUNCATED");
  EXPECT_EQ(note.message.substr(0, note.message.find(' ')), std::to_string(20 - infos)) << note.message;
}

TEST(DeltaMessages, NoChangeIsOneMessageWithNone) {
  const auto parts = make_deltas(DeltaHeader{"a.gltf", 1, "x", 2, "y"}, {}, 1, 60000);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].num_parts, 1);
  EXPECT_EQ(parts[0].total_changes, 0);
  EXPECT_TRUE(parts[0].changes.empty());
}

// At the documented smallest max_chunk_bytes, 1024, a description's chunks encoded to up to 1,150
// bytes: the piece of text had a floor of 1024 beside the chunk's own fields (s80client D4).
TEST(DescriptionMessages, EveryMessageFitsTheSmallestLimit) {
  ModelRecord record;
  record.id = "sub/arm3.gltf";
  record.revisions = 3;
  record.live.emplace();
  record.live->content_hash = std::string(64, 'a');
  const LiveTexts texts{std::string(5000, 'j'), std::string(3000, 'u')};
  for (const std::size_t limit : {1024u, 1100u, 4096u}) {
    const DescriptionMessages messages = make_description(record, texts, limit);
    ASSERT_FALSE(messages.json_chunks.empty());
    std::string json, urdf;
    for (const auto& chunk : messages.json_chunks) {
      EXPECT_LE(static_cast<std::size_t>(chunk.getEncodedSize()), limit);
      json.append(chunk.data.begin(), chunk.data.end());
    }
    for (const auto& chunk : messages.urdf_chunks) {
      EXPECT_LE(static_cast<std::size_t>(chunk.getEncodedSize()), limit);
      urdf.append(chunk.data.begin(), chunk.data.end());
    }
    EXPECT_LE(static_cast<std::size_t>(messages.description.getEncodedSize()), limit);
    EXPECT_EQ(json, texts.rdtf_json);
    EXPECT_EQ(urdf.empty() ? messages.description.urdf : urdf, texts.urdf);
  }
}

}  // namespace
}  // namespace rdtf::daemon
