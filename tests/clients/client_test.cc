// rdtf_client against a fake rdtfd (fake_rdtfd.h): reassembly in any order, hash and size checks,
// loss and retry by range, blobs held once across revisions and models, BLOB_UNAVAILABLE, states
// of the snapshot's revision only, hostile datagrams. The client runs without LCM here (datagrams
// in through on_datagram, out through a recorder) on a clock the test moves, so every retry is
// deterministic; ClientOverLcm runs the same exchange over liblcm's memq:// provider.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include <lcm/lcm-cpp.hpp>

#include <rdtf/joint_state_t.hpp>
#include <rdtf/request_t.hpp>
#include <rdtf/status_t.hpp>
#include <rdtf/validation_report_t.hpp>

#include "clients/fake_rdtfd.h"
#include "safe_decode.h"

namespace rdtf::testing {
namespace {

using rdtf::client::Blobs;
using rdtf::client::Client;
using rdtf::client::Clock;
using rdtf::client::Snapshot;
using namespace std::chrono_literals;

std::string text_of(std::size_t size, unsigned seed) {
  std::mt19937 random(seed);
  std::string out(size, '\0');
  for (auto& c : out) c = static_cast<char>('a' + random() % 26);
  return out;
}

FakeRevision arm(std::int64_t revision = 1) {
  FakeRevision r;
  r.revision = revision;
  r.content_hash = std::string(63, 'a') + static_cast<char>('0' + revision % 10);
  r.rdtf_json = "{\"asset\":{\"version\":\"2.0\"},\"extras\":{\"RDTF\":{}},\"pad\":\"" + text_of(700, 1) + "\"}";
  r.urdf = "<robot name=\"arm\">" + text_of(500, 2) + "</robot>";
  r.json_chunk = 100;
  r.urdf_chunk = 128;
  r.links = 5;
  r.files = {{"arm.rdtf.gltf", "rdtf", r.rdtf_json},
             {"arm.0123abcd.bin", "buffer", text_of(5000, 3)},
             {"urdf/robot.urdf", "urdf", r.urdf},
             {"urdf/meshes/base.0a0b0c0d.stl", "urdf_mesh", text_of(3001, 4)},
             {"empty.bin", "buffer", ""}};
  return r;
}

// A client without LCM, a fake rdtfd answering its requests, and a clock moved by the test.
struct Bench {
  explicit Bench(Blobs blobs = Blobs::kAll, std::string model = "", std::set<std::string> roles = {},
                 std::int64_t store_bytes = rdtf::client::Limits{}.max_store_bytes)
      : server(1000) {
    rdtf::client::Options options;
    options.blobs = blobs;
    options.blob_roles = std::move(roles);
    options.limits.max_store_bytes = store_bytes;
    options.model = std::move(model);
    options.requester = "test";
    rdtf::client::Callbacks callbacks;
    callbacks.on_revision = [this](std::shared_ptr<const Snapshot> s) { revisions.push_back(std::move(s)); };
    callbacks.on_drop = [this](const std::string& channel, const std::string& why) {
      drops.push_back(channel + ": " + why);
    };
    callbacks.on_problem = [this](const std::string& model_id, const std::string& text) {
      problems.push_back(model_id + ": " + text);
    };
    callbacks.on_joint_state = [this](const Snapshot&, const rdtf::joint_state_t& s) { states.push_back(s); };
    callbacks.on_removed = [this](const rdtf::model_removed_t& r) { removed.push_back(r.model_id); };
    client = std::make_unique<Client>(
        [this](const std::string& channel, const std::vector<std::uint8_t>& bytes) { sent.emplace_back(channel, bytes); },
        options, callbacks);
  }

  void feed(const std::vector<Datagram>& datagrams) {
    for (const auto& [channel, bytes] : datagrams) client->on_datagram(channel, bytes.data(), bytes.size(), now);
  }
  void live(const FakeRevision& r) {
    live_revisions[r.model_id] = r;
    server.serve(r);
  }
  // One round: answer what the client sent (through `lose`: true drops a datagram on its way to
  // the client), then 50 ms pass and the client ticks.
  void round(const std::function<bool(const Datagram&)>& lose = nullptr) {
    auto outbox = std::move(sent);
    sent.clear();
    for (const auto& [channel, bytes] : outbox) {
      std::vector<Datagram> answer;
      if (channel == "RDTF/BLOB_REQUEST") {
        std::string why;
        auto request = rdtf::lcm_safe::decode<rdtf::blob_request_t>(bytes.data(), bytes.size(), why);
        ASSERT_TRUE(request) << why;
        blob_requests.push_back(*request);
        answer = server.answer(*request);
      } else if (channel == "RDTF/REQUEST") {
        std::string why;
        auto request = rdtf::lcm_safe::decode<rdtf::request_t>(bytes.data(), bytes.size(), why);
        ASSERT_TRUE(request) << why;
        ++requests;
        for (const auto& [id, r] : live_revisions) {
          if (request->model_id.empty() || request->model_id == id) {
            auto p = publication(r);
            answer.insert(answer.end(), p.begin(), p.end());
          }
        }
      }
      for (const auto& d : answer) {
        if (!lose || !lose(d)) feed({d});
      }
    }
    now += 50ms;
    client->tick(now);
  }
  bool run_until(const std::function<bool()>& done, int rounds = 400,
                 const std::function<bool(const Datagram&)>& lose = nullptr) {
    for (int i = 0; i < rounds && !done(); ++i) round(lose);
    return done();
  }
  // The SHA-256s the blob requests asked for.
  std::vector<std::string> requested_blobs() const {
    std::vector<std::string> out;
    for (const auto& r : blob_requests) out.insert(out.end(), r.sha256.begin(), r.sha256.end());
    return out;
  }

  Clock::time_point now = Clock::time_point{} + 1h;
  FakeBlobServer server;
  std::map<std::string, FakeRevision> live_revisions;
  std::unique_ptr<Client> client;
  std::vector<Datagram> sent;
  std::vector<rdtf::blob_request_t> blob_requests;
  int requests = 0;
  std::vector<std::shared_ptr<const Snapshot>> revisions;
  std::vector<std::string> drops;
  std::vector<std::string> problems;
  std::vector<rdtf::joint_state_t> states;
  std::vector<std::string> removed;
};

// rdtfd's heartbeat, listing `live` as its live models.
// pid, start: the rdtfd that sends it (STATUS carries utime and uptime; start = utime - uptime).
Datagram status_listing(std::vector<std::string> live, std::int32_t pid = 0, std::int64_t start_us = 1,
                        double uptime_s = 0) {
  rdtf::status_t s{};
  s.utime = start_us + static_cast<std::int64_t>(uptime_s * 1e6);
  s.pid = pid;
  s.uptime = uptime_s;
  s.version = "test";
  s.model_ids = std::move(live);
  s.num_model_ids = static_cast<std::int32_t>(s.model_ids.size());
  s.num_models = s.num_model_ids;
  return datagram("RDTF/STATUS", s);
}

// A revision the gate refused: its failed VALIDATION, and nothing more of it.
Datagram refused_validation(const std::string& model_id) {
  rdtf::validation_report_t v{};
  v.utime = 1;
  v.model_id = model_id;
  v.revision = 1;
  v.content_hash = std::string(64, 'b');
  v.passed = false;
  v.num_diagnostics = 0;
  return datagram("RDTF/" + model_id + "/VALIDATION", v);
}

// The snapshot is the revision, every part of it.
void expect_snapshot(const Snapshot& s, const FakeRevision& r, bool with_blobs = true) {
  EXPECT_EQ(s.model_id(), r.model_id);
  EXPECT_EQ(s.revision(), r.revision);
  EXPECT_EQ(s.content_hash(), r.content_hash);
  EXPECT_EQ(s.description.rdtf_json, r.rdtf_json);
  EXPECT_EQ(s.description.urdf, r.urdf);
  ASSERT_EQ(s.inertia.num_links, r.links);
  ASSERT_EQ(s.inertia.links.size(), static_cast<std::size_t>(r.links));
  for (int i = 0; i < r.links; ++i) {
    EXPECT_EQ(s.inertia.links[static_cast<std::size_t>(i)].name, link_of(i).name);
    EXPECT_EQ(s.inertia.links[static_cast<std::size_t>(i)].mass, link_of(i).mass);
  }
  if (!with_blobs) return;
  ASSERT_TRUE(s.has_manifest);
  ASSERT_EQ(s.manifest.size(), r.files.size());
  for (const auto& f : r.files) {
    const std::string* bytes = s.file(f.path);
    ASSERT_NE(bytes, nullptr) << f.path;
    EXPECT_EQ(*bytes, f.bytes) << f.path;
  }
}

TEST(Client, SendsARequestAtStartAndAgainWithBackOffUntilAnswered) {
  Bench b(Blobs::kNone, "arm.gltf");
  ASSERT_EQ(b.sent.size(), 0u);  // Without LCM the first tick sends it.
  b.client->tick(b.now);
  ASSERT_EQ(b.sent.size(), 1u);
  EXPECT_EQ(b.sent[0].first, "RDTF/REQUEST");
  // No rdtfd yet: asked again after 250 ms, 500 ms, 1 s, 2 s, 2 s ...: at 0, 0.25, 0.75, 1.75
  // and 3.75 s in the first 5 s.
  for (int i = 0; i < 100; ++i) b.round();
  EXPECT_EQ(b.requests, 5);
  b.live(arm());
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }, 60));
  const int answered = b.requests;
  for (int i = 0; i < 100; ++i) b.round();
  EXPECT_EQ(b.requests, answered) << "a client with its model asks no more";
}

// A model deleted while rdtfd was down never gets a REMOVED: once two STATUS in a row no longer
// list it as live, the client drops it as if REMOVED had come (one STATUS alone may have been
// composed as its first revision went out).
TEST(Client, AModelTheStatusNoLongerListsIsRemoved) {
  Bench b(Blobs::kNone);
  std::string why;
  FakeRevision other = arm();
  other.model_id = "other.gltf";
  b.feed(publication(arm()));
  b.feed(publication(other));
  ASSERT_TRUE(b.client->snapshot("arm.gltf"));
  b.feed({status_listing({"arm.gltf", "other.gltf"})});
  b.feed({status_listing({"other.gltf"})});
  EXPECT_TRUE(b.client->snapshot("arm.gltf")) << "dropped after one STATUS";
  b.feed({status_listing({"arm.gltf", "other.gltf"})});
  b.feed({status_listing({"other.gltf"})});
  EXPECT_TRUE(b.client->snapshot("arm.gltf")) << "two STATUS that were not in a row";
  // While rdtfd has conversions pending (a restart's first scan: it lists a model once converted),
  // a model it does not list yet is not gone.
  Datagram busy = status_listing({"other.gltf"});
  rdtf::status_t pending = *rdtf::lcm_safe::decode<rdtf::status_t>(busy.second.data(), busy.second.size(), why);
  pending.pending = 1;
  for (int i = 0; i < 5; ++i) b.feed({datagram("RDTF/STATUS", pending)});
  EXPECT_TRUE(b.client->snapshot("arm.gltf")) << "dropped while rdtfd was still converting";
  b.feed({status_listing({"other.gltf"})});
  EXPECT_FALSE(b.client->snapshot("arm.gltf"));
  EXPECT_TRUE(b.client->snapshot("other.gltf"));
  EXPECT_EQ(b.removed, (std::vector<std::string>{"arm.gltf"}));
  EXPECT_EQ(b.client->models_seen(), (std::set<std::string>{"other.gltf"}));
}

// A model whose revision the gate refused: asked again, rdtfd only republishes the refusal, so a
// client that asked on every retry made it republish every 2 s for ever. Neither the stalled
// revision nor the start request asks again once rdtfd's STATUS lists no followed model as live.
TEST(Client, NeverAsksAgainForARevisionTheGateRefused) {
  Bench b(Blobs::kNone, "broken.gltf");
  b.client->tick(b.now);
  ASSERT_EQ(b.sent.size(), 1u);  // The start request.
  b.feed({refused_validation("broken.gltf"), status_listing({"arm.gltf"})});
  const int asked = static_cast<int>(b.sent.size());
  for (int i = 0; i < 200; ++i) {  // 10 s
    b.now += 50ms;
    b.client->tick(b.now);
  }
  EXPECT_EQ(static_cast<int>(b.sent.size()), asked);
  // It goes live: published as any save is, and taken.
  FakeRevision fixed = arm();
  fixed.model_id = "broken.gltf";
  b.feed(publication(fixed));
  EXPECT_TRUE(b.client->snapshot("broken.gltf"));
}

TEST(Client, ReassemblesEveryPartInAnyOrder) {
  const FakeRevision r = arm();
  auto datagrams = publication(r);
  ASSERT_GT(datagrams.size(), 15u);
  std::mt19937 random(7);
  for (int trial = 0; trial < 20; ++trial) {
    Bench b(Blobs::kNone);
    std::shuffle(datagrams.begin(), datagrams.end(), random);
    // Except the INERTIA parts among themselves: they carry no index, so rdtfd's order (one
    // socket to one socket) is what joins them.
    std::vector<std::size_t> slots;
    for (std::size_t i = 0; i < datagrams.size(); ++i) {
      if (datagrams[i].first.find("INERTIA") != std::string::npos) slots.push_back(i);
    }
    std::vector<Datagram> parts;
    for (const auto& d : publication(r)) {
      if (d.first.find("INERTIA") != std::string::npos) parts.push_back(d);
    }
    for (std::size_t i = 0; i < slots.size(); ++i) datagrams[slots[i]] = parts[i];
    b.feed(datagrams);
    ASSERT_EQ(b.revisions.size(), 1u) << "trial " << trial;
    expect_snapshot(*b.revisions[0], r, false);
    EXPECT_TRUE(b.drops.empty()) << b.drops.front();
  }
}

TEST(Client, FetchesEveryBlobAndChecksIt) {
  Bench b;
  b.live(arm());
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }));
  expect_snapshot(*b.revisions[0], arm());
  EXPECT_TRUE(b.drops.empty());
  EXPECT_EQ(b.client->stats().blob_retries, 0u);
  // Each distinct blob was asked for once (the .rdtf.gltf and the URDF are blobs too).
  auto asked = b.requested_blobs();
  std::sort(asked.begin(), asked.end());
  EXPECT_EQ(std::adjacent_find(asked.begin(), asked.end()), asked.end());
  EXPECT_EQ(asked.size(), arm().files.size());
}

TEST(Client, FetchesOnlyTheBlobsOfTheRolesAskedFor) {
  Bench b(Blobs::kAll, "", {"rdtf", "buffer"});
  b.live(arm());
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }));
  const Snapshot& s = *b.revisions[0];
  expect_snapshot(s, arm(), /*with_blobs=*/false);
  ASSERT_EQ(s.manifest.size(), arm().files.size());  // the manifest is whole
  std::set<std::string> wanted;
  for (const auto& f : arm().files) {
    const std::string* bytes = s.file(f.path);
    if (f.role == "rdtf" || f.role == "buffer") {
      wanted.insert(client::sha256_hex(f.bytes.data(), f.bytes.size()));
      ASSERT_NE(bytes, nullptr) << f.path;
      EXPECT_EQ(*bytes, f.bytes) << f.path;
    } else {
      EXPECT_EQ(bytes, nullptr) << f.path;
    }
  }
  const auto asked = b.requested_blobs();
  EXPECT_EQ(std::set<std::string>(asked.begin(), asked.end()), wanted);
  EXPECT_TRUE(b.drops.empty());
}

// With no room beyond what is in use, a blob goes as soon as no snapshot holds it: the next
// tick after the caller dropped the old revision. A later revision with that content fetches it
// again (with room, NeverAsksAgain... below shows it is not).
TEST(Client, EvictsBlobsNoSnapshotHoldsAtTheNextTickWhenTheStoreHasNoRoom) {
  Bench b(Blobs::kAll, "", {}, /*store_bytes=*/0);
  const FakeRevision r1 = arm(1);
  b.live(r1);
  ASSERT_TRUE(b.run_until([&] { return b.revisions.size() == 1; }));
  const std::string& buffer = r1.files[1].bytes;
  const std::string buffer_sha = client::sha256_hex(buffer.data(), buffer.size());
  const auto asked_for_buffer = [&] {
    const auto asked = b.requested_blobs();
    return std::count(asked.begin(), asked.end(), buffer_sha);
  };
  ASSERT_EQ(asked_for_buffer(), 1);
  FakeRevision r2 = arm(2);
  r2.files[1].bytes = text_of(5000, 9);  // another buffer
  b.live(r2);
  b.feed(publication(r2));
  ASSERT_TRUE(b.run_until([&] { return b.revisions.size() == 2; }));
  expect_snapshot(*b.revisions[1], r2);
  b.revisions.erase(b.revisions.begin());  // the caller lets revision 1 go
  b.round();                               // a tick
  FakeRevision r3 = arm(3);                // revision 1's content again
  b.live(r3);
  b.feed(publication(r3));
  ASSERT_TRUE(b.run_until([&] { return b.revisions.size() == 2; }));
  expect_snapshot(*b.revisions[1], r3);
  EXPECT_EQ(asked_for_buffer(), 2);
  EXPECT_TRUE(b.drops.empty());
}

TEST(Client, NeverAsksAgainForABlobItHoldsFromAnEarlierRevisionOrAnotherModel) {
  Bench b;
  b.live(arm(1));
  ASSERT_TRUE(b.run_until([&] { return b.revisions.size() == 1; }));
  const std::size_t before = b.requested_blobs().size();
  // Revision 2 changes one joint limit: the RDTF JSON and URDF change, the meshes do not.
  FakeRevision r2 = arm(2);
  r2.rdtf_json += " ";
  r2.files[0].bytes = r2.rdtf_json;
  r2.urdf += " ";
  r2.files[2].bytes = r2.urdf;
  b.live(r2);
  b.feed(publication(r2));
  ASSERT_TRUE(b.run_until([&] { return b.revisions.size() == 2; }));
  expect_snapshot(*b.revisions[1], r2);
  const auto asked = b.requested_blobs();
  ASSERT_EQ(asked.size(), before + 2);
  const std::set<std::string> new_ones(asked.begin() + static_cast<long>(before), asked.end());
  EXPECT_EQ(new_ones, (std::set<std::string>{client::sha256_hex(r2.rdtf_json.data(), r2.rdtf_json.size()),
                                             client::sha256_hex(r2.urdf.data(), r2.urdf.size())}));
  // Another model with the same mesh and buffer: only its own documents are asked for.
  FakeRevision other = arm(1);
  other.model_id = "other.glb";
  other.rdtf_json += "  ";
  other.files[0].bytes = other.rdtf_json;
  other.urdf += "  ";
  other.files[2].bytes = other.urdf;
  b.live(other);
  b.feed(publication(other));
  ASSERT_TRUE(b.run_until([&] { return b.revisions.size() == 3; }));
  expect_snapshot(*b.revisions[2], other);
  EXPECT_EQ(b.requested_blobs().size(), before + 4);
}

TEST(Client, RecoversLostChunksByRangeWithBackOff) {
  Bench b;
  b.live(arm());
  // Lose 40% of every datagram on the way in, descriptions and blob chunks alike.
  std::mt19937 random(11);
  auto lose = [&](const Datagram&) { return random() % 100 < 40; };
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }, 2000, lose))
      << b.client->stats().blob_retries << " retries";
  expect_snapshot(*b.revisions[0], arm());
  EXPECT_GT(b.client->stats().blob_retries, 0u);
  // A re-request names chunk ranges, not whole blobs, once the chunk size is known.
  bool ranged = false;
  for (const auto& r : b.blob_requests) {
    for (int i = 0; i < r.num_ranges; ++i) ranged |= r.num_chunks[i] > 0;
  }
  EXPECT_TRUE(ranged);
}

// A lossy link (Wi-Fi) loses chunks all over a large blob. The requests that recover them must
// arrive: each fits one Ethernet frame (a request split into IP fragments is lost when any of them
// is: 256 ranges were about 16 fragments, which arrived 3% of the time at 20% loss), and they are
// paced below rdtfd's 50 a second per requester, beyond which it drops them.
TEST(Client, RecoveryRequestsFitOneFrameAndArePaced) {
  Bench b;
  FakeRevision r = arm();
  r.files[1].bytes = text_of(2'000'000, 5);  // 2,000 chunks of 1,000 bytes
  b.live(r);
  // Every chunk is lost the first time it comes at random, one in two: about 500 ranges.
  std::mt19937 random(17);
  std::set<std::pair<std::string, std::int32_t>> seen;
  auto lose = [&](const Datagram& d) {
    if (d.first != "RDTF/BLOB") return false;
    std::string why;
    const auto chunk = rdtf::lcm_safe::decode<rdtf::blob_chunk_t>(d.second.data(), d.second.size(), why);
    return chunk && seen.insert({chunk->sha256, chunk->index}).second && random() % 2 == 0;
  };
  std::vector<std::size_t> sent_by_round;
  for (int i = 0; i < 2000 && b.revisions.empty(); ++i) {
    const std::size_t before = b.blob_requests.size();
    b.round(lose);
    sent_by_round.push_back(b.blob_requests.size() - before);
  }
  ASSERT_FALSE(b.revisions.empty()) << b.blob_requests.size() << " requests";
  expect_snapshot(*b.revisions[0], r);
  std::size_t ranges = 0;
  for (rdtf::blob_request_t request : b.blob_requests) {
    EXPECT_LE(request.getEncodedSize(), 1200) << request.num_ranges << " ranges";
    ranges += static_cast<std::size_t>(request.num_ranges);
  }
  EXPECT_GT(ranges, 400u);  // the losses were scattered: this took many requests
  // Requests answered in round k were sent at its start: any 20 rounds (1 s) hold at most 50.
  for (std::size_t k = 0; k < sent_by_round.size(); ++k) {
    std::size_t in_second = 0;
    for (std::size_t j = k; j < std::min(sent_by_round.size(), k + 20); ++j) in_second += sent_by_round[j];
    EXPECT_LE(in_second, 50u) << "rounds " << k << " to " << k + 19;
  }
}

// A network that duplicates datagrams (Wi-Fi retries, a bridge) is harmless: every part of the
// revision twice in a row assembles it as once, and nothing is counted as a bad datagram. A
// duplicated INERTIA part was "INERTIA parts with more than the 5 links announced".
TEST(Client, DuplicatedDatagramsAreHarmless) {
  Bench b;
  b.live(arm());
  const auto twice = [](const std::vector<Datagram>& datagrams) {
    std::vector<Datagram> out;
    for (const auto& d : datagrams) out.insert(out.end(), {d, d});
    return out;
  };
  b.feed(twice(publication(arm())));
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }));
  expect_snapshot(*b.revisions[0], arm());
  EXPECT_EQ(b.drops, std::vector<std::string>{});
  EXPECT_EQ(b.problems, std::vector<std::string>{});
}

TEST(Client, RefetchesABlobWhoseBytesFailTheirHash) {
  Bench b;
  b.live(arm());
  bool corrupted = false;
  // The first chunk 2 of the .bin arrives with one byte changed.
  auto corrupt = [&](const Datagram& d) {
    if (corrupted || d.first != "RDTF/BLOB") return false;
    std::string why;
    auto c = rdtf::lcm_safe::decode<rdtf::blob_chunk_t>(d.second.data(), d.second.size(), why);
    if (!c || c->blob_size != 5000 || c->index != 2) return false;
    c->data[17] ^= 1;
    corrupted = true;
    b.feed({datagram("RDTF/BLOB", *c)});
    return true;
  };
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }, 400, corrupt));
  EXPECT_TRUE(corrupted);
  expect_snapshot(*b.revisions[0], arm());
  EXPECT_EQ(b.client->stats().blobs_fetched, arm().files.size());
}

TEST(Client, DropsDocumentChunksThatFailTheAnnouncedHash) {
  Bench b(Blobs::kNone);
  const FakeRevision r = arm();
  auto datagrams = publication(r);
  for (auto& [channel, bytes] : datagrams) {
    if (channel.find("DESCRIPTION_CHUNK") == std::string::npos) continue;
    std::string why;
    auto c = rdtf::lcm_safe::decode<rdtf::description_chunk_t>(bytes.data(), bytes.size(), why);
    if (c->index != 3) continue;
    c->data[0] ^= 0x20;
    bytes = datagram(channel, *c).second;
  }
  b.feed(datagrams);
  EXPECT_TRUE(b.revisions.empty());
  ASSERT_FALSE(b.drops.empty());
  EXPECT_NE(b.drops.back().find("RDTF JSON chunks do not match the announced SHA-256"), std::string::npos) << b.drops.back();
  // The next publication is whole again.
  b.feed(publication(r));
  ASSERT_EQ(b.revisions.size(), 1u);
  expect_snapshot(*b.revisions[0], r, false);
}

TEST(Client, ReportsABlobRdtfdDoesNotServe) {
  Bench b;
  FakeRevision r = arm();
  b.live(r);
  // The server has every file but the mesh.
  FakeBlobServer partial(1000);
  FakeRevision without = r;
  without.files.erase(without.files.begin() + 3);
  partial.serve(without);
  b.server = partial;
  ASSERT_TRUE(b.run_until([&] { return !b.problems.empty(); }));
  EXPECT_TRUE(b.revisions.empty());
  EXPECT_NE(b.problems[0].find("not available: not a file of any live revision"), std::string::npos) << b.problems[0];
  EXPECT_EQ(b.problems[0].rfind("arm.gltf: blob " + manifest_files(r)[3].sha256, 0), 0u) << b.problems[0];
}

TEST(Client, HandsOverOnlyStatesOfTheSnapshotsRevision) {
  Bench b(Blobs::kNone);
  b.feed(publication(arm(2)));
  ASSERT_EQ(b.revisions.size(), 1u);
  rdtf::joint_state_t s{};
  s.model_id = "arm.gltf";
  s.num_joints = 0;
  for (const auto& [revision, hash] : std::vector<std::pair<std::int64_t, std::string>>{
           {1, arm(1).content_hash}, {2, arm(1).content_hash}, {2, arm(2).content_hash}, {3, arm(2).content_hash}}) {
    s.revision = revision;
    s.content_hash = hash;
    b.feed({datagram("RDTF/arm.gltf/JOINT_STATE", s)});
  }
  ASSERT_EQ(b.states.size(), 1u);
  EXPECT_EQ(b.states[0].revision, 2);
  EXPECT_EQ(b.states[0].content_hash, arm(2).content_hash);
}

TEST(Client, ReplacesItsSnapshotWithTheNextRevision) {
  Bench b(Blobs::kNone);
  b.feed(publication(arm(1)));
  b.feed(publication(arm(1)));  // A republication: no new revision.
  b.feed(publication(arm(3)));
  ASSERT_EQ(b.revisions.size(), 2u);
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 3);
}

// Revisions only grow while one rdtfd serves a model: a lower one (a log played back while the
// rdtfd that described the newer one still runs) is held, not taken, and a controller keeps
// commanding the live revision. Once a STATUS shows another rdtfd (a restart without its state
// folder, which numbers from 1 again) the held revision is the model's. STATUS of an earlier run,
// played back from the same log, is no restart.
TEST(Client, ALowerRevisionIsTakenOnlyFromARestartedRdtfd) {
  Bench b(Blobs::kNone);
  std::vector<std::string> problems;
  b.feed({status_listing({"arm.gltf"}, 100, 5'000'000, 10.0)});
  b.feed(publication(arm(2)));
  ASSERT_EQ(b.client->snapshot("arm.gltf")->revision(), 2);
  b.feed(publication(arm(1)));  // Played back.
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 2) << "a lower revision of the same rdtfd was taken";
  EXPECT_EQ(b.revisions.size(), 1u);
  b.feed({status_listing({"arm.gltf"}, 100, 5'000'000, 11.0)});    // the same rdtfd, a second later
  b.feed({status_listing({"arm.gltf"}, 100, 5'000'200, 12.0)});    // its utime and uptime read apart
  b.feed({status_listing({"arm.gltf"}, 90, 1'000'000, 3.0)});      // an earlier run's, played back
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 2);
  // The same revision number with other content is no newer either.
  FakeRevision other = arm(2);
  other.content_hash = std::string(64, 'c');
  b.feed(publication(other));
  EXPECT_EQ(b.client->snapshot("arm.gltf")->content_hash(), arm(2).content_hash);
  // rdtfd restarted (another pid, a later start): the newest held revision is taken.
  b.feed({status_listing({"arm.gltf"}, 200, 60'000'000, 0.5)});
  ASSERT_EQ(b.client->snapshot("arm.gltf")->revision(), 2);
  EXPECT_EQ(b.client->snapshot("arm.gltf")->content_hash(), other.content_hash);
  // A lower one after that is held again, until the next restart.
  b.feed(publication(arm(1)));
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 2) << "revision 1 after revision 2 of one rdtfd was taken";
  b.feed({status_listing({"arm.gltf"}, 201, 70'000'000, 0.5)});
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 1);
}

// A client that has heard no STATUS yet (its first second) cannot tell one rdtfd from another:
// an rdtfd restarted then, numbering from 1 again, is followed, not held back for ever.
TEST(Client, BeforeAnyStatusTheRevisionDescribedLastIsTaken) {
  Bench b(Blobs::kNone);
  b.feed(publication(arm(2)));
  b.feed(publication(arm(1)));
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 1);
  // From the first STATUS on, the rule holds.
  b.feed({status_listing({"arm.gltf"}, 300, 9'000'000, 1.0)});
  b.feed(publication(arm(3)));
  b.feed(publication(arm(2)));
  EXPECT_EQ(b.client->snapshot("arm.gltf")->revision(), 3);
}

// Hostile or malformed datagrams: each is dropped with a reason, none crashes or stalls the client.
TEST(Client, DropsHostileDatagramsWithAReasonAndGoesOn) {
  Bench b;
  const FakeRevision r = arm();
  b.live(r);
  std::vector<std::pair<Datagram, std::string>> hostile;
  auto chunk = chunks_of(r, r.rdtf_json, r.json_chunk)[0];
  auto with_chunk = [&](auto change, const std::string& why) {
    auto c = chunk;
    change(c);
    hostile.push_back({datagram(prefixed(r, "DESCRIPTION_CHUNK"), c), why});
  };
  with_chunk([](auto& c) { c.count = 1 << 30; }, "chunk count 1073741824 outside");
  with_chunk([](auto& c) { c.index = -1; }, "chunk index -1 outside");
  with_chunk([](auto& c) { c.index = 8; c.count = 9; }, "chunk count 9 differs");
  with_chunk([](auto& c) { c.model_id = "other.gltf"; }, "is not the channel's");
  auto d = description_of(r);
  auto with_description = [&](auto change, const std::string& why) {
    auto copy = d;
    change(copy);
    hostile.push_back({datagram(prefixed(r, "DESCRIPTION"), copy), why});
  };
  with_description([](auto& x) { x.rdtf_json_size = std::int64_t{1} << 40; }, "rdtf_json_size 1099511627776 outside");
  with_description([](auto& x) { x.num_links = -3; }, "num_links -3 out of range");
  with_description([](auto& x) { x.urdf_sha256 = "zz"; }, "urdf_sha256 is not 64 hex digits");
  with_description([](auto& x) { x.revision = 0; }, "revision 0 or content_hash not valid");
  auto m = rdtf::manifest_t{};
  m.model_id = r.model_id;
  m.revision = r.revision;
  m.content_hash = r.content_hash;
  m.part = 0;
  m.num_parts = 1;
  m.total_files = 1;
  m.num_files = 1;
  m.files = {manifest_files(r)[1]};
  auto with_manifest = [&](auto change, const std::string& why) {
    auto copy = m;
    change(copy);
    hostile.push_back({datagram(prefixed(r, "MANIFEST"), copy), why});
  };
  with_manifest([](auto& x) { x.files[0].path = "../escape.bin"; }, "has an empty, '.' or '..' part");
  with_manifest([](auto& x) { x.files[0].path = "/etc/passwd"; }, "absolute path");
  with_manifest([](auto& x) { x.files[0].path = "a//b"; }, "has an empty");
  with_manifest([](auto& x) { x.files[0].size = std::int64_t{1} << 50; }, "size 1125899906842624 outside");
  with_manifest([](auto& x) { x.total_files = 1 << 30; }, "total_files 1073741824 outside");
  with_manifest([](auto& x) { x.part = 5; }, "part 5 outside");
  auto blob = [&] {
    FakeBlobServer one(1000);
    one.serve(r);
    rdtf::blob_request_t request{};
    request.num_ranges = 1;
    request.sha256 = {manifest_files(r)[1].sha256};
    request.first_chunk = {0};
    request.num_chunks = {1};
    std::string why;
    const auto answer = one.answer(request);
    return *rdtf::lcm_safe::decode<rdtf::blob_chunk_t>(answer[0].second.data(), answer[0].second.size(), why);
  }();
  auto with_blob = [&](auto change, const std::string& why) {
    auto copy = blob;
    change(copy);
    hostile.push_back({datagram("RDTF/BLOB", copy), why});
  };
  with_blob([](auto& x) { x.blob_size = std::int64_t{1} << 40; }, "blob_size 1099511627776 but the manifest says 5000");
  with_blob([](auto& x) { x.chunk_size = 0; }, "chunk_size 0 out of range");
  with_blob([](auto& x) { x.count = 1 << 30; }, "count 1073741824 but");
  with_blob([](auto& x) { x.index = 99; }, "index 99 outside");
  with_blob([](auto& x) { x.data.pop_back(); x.size -= 1; }, "of 999 bytes, expected 1000");
  with_blob([](auto& x) { x.sha256 = "../../x"; }, "sha256 is not 64");
  // Not the type of the channel; a truncated datagram; a length field claiming 2 GiB.
  hostile.push_back({{prefixed(r, "DESCRIPTION"), datagram("x", chunk).second}, "fingerprint"});
  auto cut = datagram(prefixed(r, "INERTIA"), rdtf::inertia_table_t{});
  cut.second.resize(cut.second.size() / 2);
  hostile.push_back({cut, ""});
  auto huge = datagram(prefixed(r, "DESCRIPTION_CHUNK"), chunk);
  huge.second[huge.second.size() - chunk.data.size() - 4] = 0x7f;
  hostile.push_back({huge, ""});

  auto feed_hostile = [&](const std::pair<Datagram, std::string>& h) {
    const std::size_t before = b.drops.size();
    b.feed({h.first});
    ASSERT_EQ(b.drops.size(), before + 1) << "not dropped: " << h.second;
    EXPECT_NE(b.drops.back().find(h.second), std::string::npos) << b.drops.back() << "\nexpected: " << h.second;
  };
  // Description parts while the revision is incomplete (one good chunk held to compare with);
  // blob chunks once its blobs are being fetched.
  b.feed({datagram(prefixed(r, "DESCRIPTION_CHUNK"), chunk)});
  for (const auto& h : hostile) {
    if (h.first.first != "RDTF/BLOB") feed_hostile(h);
  }
  b.feed(publication(r));
  b.run_until([&] { return b.client->stats().blob_requests_sent > 0; });
  for (const auto& h : hostile) {
    if (h.first.first == "RDTF/BLOB") feed_hostile(h);
  }
  // Still working: the revision completes.
  ASSERT_TRUE(b.run_until([&] { return !b.revisions.empty(); }));
  expect_snapshot(*b.revisions[0], r);
}

// Chunks of incomplete revisions, of every model together, stay within max_pending_bytes.
TEST(Client, HoldsNoMoreThanMaxPendingBytesOfIncompleteRevisions) {
  rdtf::client::Options options;
  options.limits.max_pending_bytes = 1000;
  std::vector<std::string> drops;
  rdtf::client::Callbacks callbacks;
  callbacks.on_drop = [&](const std::string&, const std::string& why) { drops.push_back(why); };
  Client client([](const std::string&, const std::vector<std::uint8_t>&) {}, options, callbacks);
  const auto now = Clock::time_point{} + 1h;
  int fed = 0;
  for (int model = 0; model < 20; ++model) {
    FakeRevision r = arm();
    r.model_id = "m" + std::to_string(model) + ".gltf";
    for (const auto& c : chunks_of(r, r.rdtf_json, r.json_chunk)) {
      const auto d = datagram(prefixed(r, "DESCRIPTION_CHUNK"), c);
      client.on_datagram(d.first, d.second.data(), d.second.size(), now);
      ++fed;
    }
  }
  // Each chunk holds 100 bytes (its datagram more): the first few fit, every later one is dropped.
  ASSERT_FALSE(drops.empty());
  EXPECT_LT(fed - static_cast<int>(drops.size()), 10);
  EXPECT_NE(drops.back().find("max_pending_bytes (1000)"), std::string::npos) << drops.back();
}

// The same exchange through liblcm (memq://: in-process): subscriptions, handlers, publishing.
TEST(ClientOverLcm, PullsARevisionThroughLiblcm) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  const FakeRevision r = arm();
  FakeBlobServer server(1000);
  server.serve(r);
  struct Rdtfd {
    lcm::LCM& lcm;
    const FakeRevision& r;
    const FakeBlobServer& server;
    void send(const std::vector<Datagram>& datagrams) {
      for (const auto& [channel, bytes] : datagrams) lcm.publish(channel, bytes.data(), static_cast<unsigned>(bytes.size()));
    }
    void on_request(const lcm::ReceiveBuffer*, const std::string&) { send(publication(r)); }
    void on_blob_request(const lcm::ReceiveBuffer* buffer, const std::string&) {
      std::string why;
      auto request = rdtf::lcm_safe::decode<rdtf::blob_request_t>(buffer->data, buffer->data_size, why);
      if (request) send(server.answer(*request));
    }
  } rdtfd{lcm, r, server};
  lcm.subscribe("RDTF/REQUEST", &Rdtfd::on_request, &rdtfd);
  lcm.subscribe("RDTF/BLOB_REQUEST", &Rdtfd::on_blob_request, &rdtfd);

  rdtf::client::Options options;
  options.model = r.model_id;
  options.blobs = Blobs::kAll;
  std::shared_ptr<const Snapshot> got;
  rdtf::client::Callbacks callbacks;
  callbacks.on_revision = [&](std::shared_ptr<const Snapshot> s) { got = std::move(s); };
  Client client(lcm, options, callbacks);
  for (int i = 0; i < 1000 && !got; ++i) {
    lcm.handleTimeout(10);
    client.tick();
  }
  ASSERT_TRUE(got);
  expect_snapshot(*got, r);
  EXPECT_EQ(client.stats().dropped, 0u);
}

TEST(ClientPaths, AcceptsOnlyPlainRelativePaths) {
  for (const char* good : {"a.gltf", "urdf/meshes/x.0a0b.stl", "sub/dir/file", "..a", "a..b/c"}) {
    EXPECT_EQ(client::check_relative_path(good), "") << good;
  }
  for (const char* bad : {"", "/abs", "../up", "a/../b", "a/./b", "./a", "a/", "a//b", "a\\b", "a\nb", ".."}) {
    EXPECT_NE(client::check_relative_path(bad), "") << bad;
  }
}

}  // namespace
}  // namespace rdtf::testing
