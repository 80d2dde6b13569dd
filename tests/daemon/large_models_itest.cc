// Models with many links over real LCM (one network namespace per case; see harness.h): every
// message rdtfd sends fits in one datagram (max_chunk_bytes), and a subscriber puts the RDTF JSON
// and the URDF back together byte for byte (docs/lcm.md, "Large descriptions").
#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

// The pieces of one document on `kind` for (id, revision), each index once, joined in order;
// nothing when one is missing or the counts disagree.
std::optional<std::string> reassemble(const std::vector<Message>& all, const std::string& kind, const std::string& id,
                                      std::int64_t revision, const std::string& hash) {
  std::map<int, std::string> parts;
  int count = -1;
  for (const auto& chunk : decoded<rdtf::description_chunk_t>(all, kind, id)) {
    if (chunk.revision != revision || chunk.content_hash != hash) continue;
    if (count >= 0 && chunk.count != count) return std::nullopt;
    count = chunk.count;
    if (chunk.size != static_cast<std::int32_t>(chunk.data.size())) return std::nullopt;
    parts[chunk.index] = std::string(chunk.data.begin(), chunk.data.end());
  }
  if (count <= 0 || static_cast<int>(parts.size()) != count) return std::nullopt;
  std::string text;
  for (int i = 0; i < count; ++i) {
    if (!parts.count(i)) return std::nullopt;
    text += parts[i];
  }
  return text;
}

// Links in the inertia tables of `id` that came after its last description.
std::size_t links_after_last_description(const std::vector<Message>& all, const std::string& id) {
  std::size_t last = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].kind() == "DESCRIPTION" && all[i].model_id() == id) last = i;
  }
  std::size_t links = 0;
  for (std::size_t i = last; i < all.size(); ++i) {
    if (all[i].kind() == "INERTIA" && all[i].model_id() == id) links += all[i].as<rdtf::inertia_table_t>().links.size();
  }
  return links;
}

// Everything a subscriber needs of the last description of `id` has arrived.
bool received_whole(const std::vector<Message>& all, const std::string& id) {
  const auto d = last_description(all, id);
  if (!d) return false;
  if (d->num_chunks > 0 && !reassemble(all, "DESCRIPTION_CHUNK", id, d->revision, d->content_hash)) return false;
  if (d->urdf.empty() && !d->urdf_path.empty() && !reassemble(all, "URDF_CHUNK", id, d->revision, d->content_hash)) {
    return false;
  }
  return links_after_last_description(all, id) == static_cast<std::size_t>(d->num_links);
}

// A datagram that the receiving socket dropped (its default buffer is small, and a loaded machine
// drains it late) is recovered the way docs/lcm.md tells subscribers to: by asking again. What
// the daemon sent is checked on its own: every message within the limit. Returns the messages
// as they were when `id` was whole: a republication that is still arriving when the caller looks
// again would end the recorded messages with a description whose table has not come yet.
// Requests are printed so that losses stay visible.
std::vector<Message> recover(Session& s, const Subscriber& subscriber, const std::string& id) {
  std::vector<Message> whole;
  const auto capture = [&](const std::vector<Message>& all) {
    if (!received_whole(all, id)) return false;
    whole = all;
    return true;
  };
  int requests = 0;
  while (!subscriber.wait_for(capture, 0s) && requests < 5) {
    ++requests;
    s.request(id, "recovery");
    if (subscriber.wait_for(capture, 3s)) break;
  }
  if (requests > 0) std::cout << id << ": asked again " << requests << " times for datagrams the socket dropped\n";
  return whole;
}

void expect_whole(const std::vector<Message>& all, const std::string& id, const GeneratedModel& model) {
  SCOPED_TRACE(id);
  const auto d = last_description(all, id);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->num_links, model.links);
  const std::string hash = content_hash(model);
  ASSERT_EQ(d->content_hash, hash);

  std::string json = d->rdtf_json;
  if (d->num_chunks > 0) {
    EXPECT_EQ(d->rdtf_json, "");
    const auto joined = reassemble(all, "DESCRIPTION_CHUNK", id, d->revision, hash);
    ASSERT_TRUE(joined) << "RDTF JSON chunks incomplete";
    json = *joined;
  }
  EXPECT_EQ(static_cast<std::int64_t>(json.size()), d->rdtf_json_size);
  EXPECT_EQ(sha256_plain(json), d->rdtf_json_sha256);
  EXPECT_EQ(json, read(d->output_path));

  ASSERT_FALSE(d->urdf_path.empty());
  std::string urdf = d->urdf;
  if (urdf.empty()) {  // The documented sign that the URDF came in URDF_CHUNK messages.
    EXPECT_GT(d->num_urdf_chunks, 0);
    const auto joined = reassemble(all, "URDF_CHUNK", id, d->revision, hash);
    ASSERT_TRUE(joined) << "URDF chunks incomplete";
    urdf = *joined;
  } else {
    EXPECT_EQ(d->num_urdf_chunks, 0);
  }
  EXPECT_EQ(urdf, read(d->urdf_path));
  // The announced size and hash check the reassembled text, as for the JSON.
  EXPECT_EQ(static_cast<std::int64_t>(urdf.size()), d->urdf_size);
  EXPECT_EQ(sha256_plain(urdf), d->urdf_sha256);

  // The inertia table, in as many messages as it takes: every link once, in order. Its messages
  // follow the description, so those after the last description are one whole table.
  EXPECT_EQ(links_after_last_description(all, id), static_cast<std::size_t>(model.links));
  std::size_t last = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].kind() == "DESCRIPTION" && all[i].model_id() == id) last = i;
  }
  std::vector<std::string> names;
  for (const auto& t : decoded<rdtf::inertia_table_t>({all.begin() + static_cast<std::ptrdiff_t>(last), all.end()}, "INERTIA", id)) {
    if (t.revision != d->revision) continue;
    EXPECT_EQ(t.num_links, static_cast<std::int32_t>(t.links.size()));
    EXPECT_NEAR(t.total_mass, model.link_mass * model.links, 1e-9 * model.link_mass * model.links);
    for (const auto& link : t.links) names.push_back(link.name);
  }
  ASSERT_EQ(names.size(), static_cast<std::size_t>(model.links));
  EXPECT_EQ(names.front(), "chain_base");
  for (int i = 1; i < model.links; ++i) EXPECT_EQ(names[i], "link_" + std::to_string(i));
}

TEST(DaemonLarge, EveryMessageIsOneDatagramAndBothDocumentsReassemble) {
  Session s;
  const auto medium = box_model("chain_base", 0.02, 80);
  const auto large = box_model("chain_base", 0.02, 1000);
  write_model(s.watch, "c80.gltf", medium);
  write_model(s.watch, "c1000.gltf", large);
  constexpr std::size_t kMaxChunkBytes = 60000;  // The default, stated: the bound checked below.
  s.start(DaemonOptions().with("max_chunk_bytes", kMaxChunkBytes));
  ASSERT_TRUE(s.wait_revision("c80.gltf", 1, content_hash(medium), 60s)) << s.daemon->log();
  // A thousand links take seconds: a thousand mesh files, each written and synced.
  ASSERT_TRUE(s.wait_revision("c1000.gltf", 1, content_hash(large), 60s)) << s.daemon->log();
  ASSERT_TRUE(s.wait_idle(3, 10s));

  // A late subscriber asks for everything: the same limits hold for answers to requests.
  Subscriber late;
  s.request();
  ASSERT_TRUE(late.wait_for([](const auto& got) { return on_kind(got, "DESCRIPTION").size() >= 2; }));
  ASSERT_TRUE(s.wait_idle());

  const auto all = s.messages();
  // The 80-link chain's URDF alone is larger than a datagram: this is what needs chunks.
  ASSERT_GT(read(last_description(all, "c80.gltf")->urdf_path).size(), kMaxChunkBytes);
  std::size_t largest = 0;
  for (const auto& m : all) {
    if (m.kind() == "REQUEST") continue;  // The test's own.
    EXPECT_LE(m.bytes.size(), kMaxChunkBytes) << m.channel;
    largest = std::max(largest, m.bytes.size());
  }
  EXPECT_GT(largest, kMaxChunkBytes / 2) << "no message came close to the limit: the test proves nothing";
  EXPECT_FALSE(on_kind(all, "URDF_CHUNK", "c80.gltf").empty());
  EXPECT_FALSE(on_kind(all, "URDF_CHUNK", "c1000.gltf").empty());
  for (const auto& [id, model] : {std::pair{"c80.gltf", medium}, std::pair{"c1000.gltf", large}}) {
    const auto now = recover(s, s.subscriber, id);
    for (const auto& m : now) EXPECT_LE(m.bytes.size(), kMaxChunkBytes) << m.channel;
    expect_whole(now, id, model);
    // The late subscriber, from the answers to its requests alone.
    expect_whole(recover(s, late, id), id, model);
  }
}

TEST(DaemonLarge, ASmallerLimitHoldsForEveryMessageAndLongReportsSayWhatTheyLeftOut) {
  Session s;
  // Every joint of the chain has no limits: one URDF warning each, far more than 8,000 bytes of
  // them in the VALIDATION report.
  const auto chain = box_model("chain_base", 0.02, 60);
  write_model(s.watch, "c60.gltf", chain);
  constexpr std::size_t kMaxChunkBytes = 8000;
  // publish_failed: whatever the verdict on a long chain, its description is published.
  s.start(DaemonOptions()
              .with("max_chunk_bytes", kMaxChunkBytes)
              .with("validate", true)
              .with("validation_seconds", 0.2)
              .with("publish_failed", true));
  // Not asserted here: a datagram lost under load is asked for again by recover(), below.
  s.wait_revision("c60.gltf", 1, content_hash(chain), 20s);
  ASSERT_TRUE(s.wait_idle(3, 10s));
  const auto all = recover(s, s.subscriber, "c60.gltf");
  for (const auto& m : all) EXPECT_LE(m.bytes.size(), kMaxChunkBytes) << m.channel;
  expect_whole(all, "c60.gltf", chain);

  // One report per publication of revision 1 (a recovery request sends it again), all alike.
  const auto reports = decoded<rdtf::validation_report_t>(all, "VALIDATION", "c60.gltf");
  ASSERT_FALSE(reports.empty());
  const auto& report = reports.back();
  EXPECT_EQ(report.revision, 1);
  ASSERT_FALSE(report.diagnostics.empty());
  EXPECT_EQ(report.num_diagnostics, static_cast<std::int32_t>(report.diagnostics.size()));
  const auto& note = report.diagnostics.back();
  ASSERT_EQ(note.code, "DIAGNOSTICS_TRUNCATED");
  std::size_t warnings = 0, infos = 0;
  for (std::size_t k = 0; k + 1 < report.diagnostics.size(); ++k) {
    warnings += report.diagnostics[k].code == "URDF_REVOLUTE_WITHOUT_LIMITS";
    infos += report.diagnostics[k].severity == rdtf::diagnostic_t::INFO;
  }
  // The most severe are kept: with warnings left out, no info is sent; the note counts the
  // warnings left out and the infos beside them. The log has all 59 warnings.
  EXPECT_GT(warnings, 0u);
  EXPECT_LT(warnings, 59u);
  EXPECT_EQ(infos, 0u);
  EXPECT_GE(std::stoul(note.message.substr(0, note.message.find(' '))), 59 - warnings) << note.message;
  std::size_t logged = 0;
  const std::string log = s.daemon->log();
  for (std::size_t at = log.find("warning URDF_REVOLUTE_WITHOUT_LIMITS"); at != std::string::npos;
       at = log.find("warning URDF_REVOLUTE_WITHOUT_LIMITS", at + 1)) {
    ++logged;
  }
  EXPECT_EQ(logged, 59u);
}

}  // namespace
}  // namespace rdtf::itest
