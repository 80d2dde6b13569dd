// Views of recorded messages (by kind and model, decoded, one line per event) and checks of
// their content.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <rdtf/description_t.hpp>
#include <rdtf/inertia_table_t.hpp>
#include <rdtf/status_t.hpp>

#include "support/harness/subscriber.h"

namespace rdtf::itest {

std::vector<Message> on_kind(const std::vector<Message>& all, const std::string& kind, const std::string& model_id = "*");

template <typename T>
std::vector<T> decoded(const std::vector<Message>& all, const std::string& kind, const std::string& model_id = "*") {
  std::vector<T> out;
  for (const auto& m : on_kind(all, kind, model_id)) out.push_back(m.as<T>());
  return out;
}

std::vector<rdtf::status_t> statuses(const std::vector<Message>& all);

// One line per message about models (not STATUS or REQUEST), in arrival order:
//   "arm.gltf DESCRIPTION r2 0123456789ab", "arm.gltf INERTIA r2 ...", "arm.gltf ERROR live=1 ...",
//   "arm.gltf REMOVED last=2", "big.gltf DESCRIPTION_CHUNK r1 0/3", "big.gltf URDF_CHUNK r1 0/2"
std::string describe(const Message& m);

// Left out: the MANIFEST that precedes every DESCRIPTION (blobs_itest.cc checks it and its place),
// the DELTA that follows each new revision's INERTIA, never a republication (revisions_itest.cc),
// and the SAVING that announces a save of a live model (watch_itest.cc).
std::vector<std::string> model_events(const std::vector<Message>& all, const std::string& model_id = "*");

// What one accepted revision looks like to a subscriber (small models: no chunks).
std::vector<std::string> revision_events(const std::string& id, int revision, const std::string& hash);

std::vector<std::string> concat(std::vector<std::vector<std::string>> parts);

// True when a DESCRIPTION of `id` with this revision and hash has arrived.
bool has_revision(const std::vector<Message>& all, const std::string& id, std::int64_t revision, const std::string& hash);

std::optional<rdtf::description_t> last_description(const std::vector<Message>& all, const std::string& id);
std::optional<rdtf::inertia_table_t> last_inertia(const std::vector<Message>& all, const std::string& id);

// A description's document: valid JSON, a glTF with extras.RDTF, the announced size and link count
// (gtest expectations).
void expect_document(const rdtf::description_t& d, const std::string& base_name = "");

// The inertia table against `rdtf inspect --json` of the same file (the same conversion).
void expect_inertia_matches(const rdtf::inertia_table_t& table, const Json& inspected);

}  // namespace rdtf::itest
