#include "support/harness/messages.h"

#include <algorithm>

#include <gtest/gtest.h>

#include <rdtf/description_chunk_t.hpp>
#include <rdtf/model_error_t.hpp>
#include <rdtf/model_removed_t.hpp>
#include <rdtf/model_saving_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "support/harness/hashes.h"

namespace rdtf::itest {

std::vector<Message> on_kind(const std::vector<Message>& all, const std::string& kind,
                             const std::string& model_id) {
  std::vector<Message> out;
  for (const auto& m : all) {
    if (m.kind() == kind && (model_id == "*" || m.model_id() == model_id)) out.push_back(m);
  }
  return out;
}

std::vector<rdtf::status_t> statuses(const std::vector<Message>& all) {
  return decoded<rdtf::status_t>(all, "STATUS");
}

std::string describe(const Message& m) {
  const std::string kind = m.kind();
  const std::string head = m.model_id() + " " + kind;
  if (kind == "DESCRIPTION") {
    const auto d = m.as<rdtf::description_t>();
    return head + " r" + std::to_string(d.revision) + " " + short_hash(d.content_hash);
  }
  if (kind == "INERTIA") {
    const auto t = m.as<rdtf::inertia_table_t>();
    return head + " r" + std::to_string(t.revision) + " " + short_hash(t.content_hash);
  }
  if (kind == "DESCRIPTION_CHUNK" || kind == "URDF_CHUNK") {
    const auto c = m.as<rdtf::description_chunk_t>();
    return head + " r" + std::to_string(c.revision) + " " + std::to_string(c.index) + "/" + std::to_string(c.count);
  }
  if (kind == "ERROR") {
    const auto e = m.as<rdtf::model_error_t>();
    return head + " live=" + std::to_string(e.live_revision) + " " + short_hash(e.content_hash);
  }
  if (kind == "VALIDATION") {
    const auto v = m.as<rdtf::validation_report_t>();
    return head + " r" + std::to_string(v.revision) + " " + short_hash(v.content_hash) +
           (v.passed ? " passed" : " failed");
  }
  if (kind == "SAVING") {
    return head + " live=" + std::to_string(m.as<rdtf::model_saving_t>().live_revision);
  }
  if (kind == "REMOVED") {
    return head + " last=" + std::to_string(m.as<rdtf::model_removed_t>().last_revision);
  }
  return head;
}

std::vector<std::string> model_events(const std::vector<Message>& all, const std::string& model_id) {
  std::vector<std::string> out;
  for (const auto& m : all) {
    if (m.model_id().empty() || m.kind() == "MANIFEST" || m.kind() == "DELTA" || m.kind() == "SAVING") continue;
    if (model_id != "*" && m.model_id() != model_id) continue;
    out.push_back(describe(m));
  }
  return out;
}

std::vector<std::string> revision_events(const std::string& id, int revision, const std::string& hash) {
  return {id + " DESCRIPTION r" + std::to_string(revision) + " " + short_hash(hash),
          id + " INERTIA r" + std::to_string(revision) + " " + short_hash(hash)};
}

std::vector<std::string> concat(std::vector<std::vector<std::string>> parts) {
  std::vector<std::string> out;
  for (auto& part : parts) out.insert(out.end(), part.begin(), part.end());
  return out;
}

bool has_revision(const std::vector<Message>& all, const std::string& id, std::int64_t revision,
                         const std::string& hash) {
  for (const auto& d : decoded<rdtf::description_t>(all, "DESCRIPTION", id)) {
    if (d.revision == revision && d.content_hash == hash) return true;
  }
  return false;
}

std::optional<rdtf::description_t> last_description(const std::vector<Message>& all, const std::string& id) {
  auto all_of = decoded<rdtf::description_t>(all, "DESCRIPTION", id);
  if (all_of.empty()) return std::nullopt;
  return all_of.back();
}

std::optional<rdtf::inertia_table_t> last_inertia(const std::vector<Message>& all, const std::string& id) {
  auto all_of = decoded<rdtf::inertia_table_t>(all, "INERTIA", id);
  if (all_of.empty()) return std::nullopt;
  return all_of.back();
}


void expect_document(const rdtf::description_t& d, const std::string& base_name) {
  SCOPED_TRACE("description of " + d.model_id + " r" + std::to_string(d.revision));
  EXPECT_EQ(d.num_chunks, 0);
  EXPECT_EQ(static_cast<std::size_t>(d.rdtf_json_size), d.rdtf_json.size());
  Json document;
  ASSERT_NO_THROW(document = Json::parse(d.rdtf_json));
  ASSERT_TRUE(document.contains("extras") && document["extras"].contains("RDTF")) << d.rdtf_json.substr(0, 300);
  EXPECT_TRUE(document["extras"]["RDTF"].is_object());
  EXPECT_EQ(document["asset"]["version"], "2.0");
  if (!base_name.empty()) {
    bool found = false;
    for (const auto& node : document["nodes"]) found |= node.value("name", "") == base_name;
    EXPECT_TRUE(found) << "no node named " << base_name << " in the published document";
  }
  // The published document is the output file the daemon wrote.
  EXPECT_TRUE(fs::exists(d.output_path)) << d.output_path;
}

void expect_inertia_matches(const rdtf::inertia_table_t& table, const Json& inspected) {
  SCOPED_TRACE("inertia of " + table.model_id + " r" + std::to_string(table.revision));
  ASSERT_EQ(table.num_links, static_cast<std::int32_t>(table.links.size()));
  ASSERT_EQ(table.links.size(), inspected["links"].size());
  double total = 0;
  for (std::size_t i = 0; i < table.links.size(); ++i) {
    const Json& link = inspected["links"][i];
    // `rdtf inspect` names links as the glTF does; the table's `name` is the URDF's.
    EXPECT_EQ(table.links[i].gltf_name, link["name"].get<std::string>());
    const double mass = link["mass"].get<double>();
    EXPECT_NEAR(table.links[i].mass, mass, 1e-9 * std::max(1.0, mass)) << table.links[i].name;
    total += mass;
  }
  EXPECT_NEAR(table.total_mass, total, 1e-9 * std::max(1.0, total));
}

}  // namespace rdtf::itest
