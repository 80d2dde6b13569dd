// rdtfd's publishing: late subscribers (request and periodic republication), large descriptions
// in chunks, one model's channels by regex, and recording and replaying a session with
// lcm-logger / lcm-logplayer (and rdtf-echo printing it). See harness.h for how these tests run.
#include <signal.h>

#include <algorithm>
#include <set>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

std::vector<std::string> sorted(std::vector<std::string> v) {
  std::sort(v.begin(), v.end());
  return v;
}

TEST(DaemonPublish, LateSubscriberGetsEveryModelOnRequest) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  copy_fixture(s.watch, "arm3");
  s.start();  // No periodic republishing.
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  ASSERT_TRUE(s.wait_idle());

  // Started now: it has missed everything, and LCM does not latch.
  Subscriber late;
  Subscriber only_arm3(R"(RDTF/arm3\.gltf/.*)");  // One model's traffic, by regex.
  s.request("", "late subscriber");
  ASSERT_TRUE(late.wait_for([](const auto& all) { return on_kind(all, "INERTIA").size() >= 2; }));
  ASSERT_TRUE(s.wait_idle());
  auto got = late.messages();
  EXPECT_EQ(sorted(model_events(got)),
            sorted(concat({revision_events("a.gltf", 1, content_hash(a)),
                           revision_events("arm3.gltf", 1, fixture_hash("arm3"))})));
  // The same documents and tables as first published.
  for (const std::string id : {"a.gltf", "arm3.gltf"}) {
    const auto first = on_kind(s.messages(), "DESCRIPTION", id).at(0).as<rdtf::description_t>();
    const auto again = last_description(got, id);
    ASSERT_TRUE(again);
    EXPECT_EQ(again->rdtf_json, first.rdtf_json);
    EXPECT_EQ(again->output_path, first.output_path);
    expect_document(*again);
    expect_inertia_matches(*last_inertia(got, id), inspect(s.watch / id));
  }
  EXPECT_NE(s.daemon->log().find("republished every model on request of 'late subscriber'"), std::string::npos);
  EXPECT_EQ(model_events(only_arm3.messages()), revision_events("arm3.gltf", 1, fixture_hash("arm3")));

  // A request for one model answers with that model only; an unknown id with nothing.
  Subscriber later;
  s.request("arm3.gltf");
  s.request("no-such-model.gltf");
  ASSERT_TRUE(later.wait_for([](const auto& all) { return on_kind(all, "INERTIA").size() >= 1; }));
  ASSERT_TRUE(s.wait_idle());
  EXPECT_EQ(model_events(later.messages()), revision_events("arm3.gltf", 1, fixture_hash("arm3")));
}

TEST(DaemonPublish, LateSubscriberGetsEveryModelFromPeriodicRepublication) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  const auto b = box_model("b_base", 0.07, 2, "b.bin");
  write_model(s.watch, "a.gltf", a);
  write_model(s.watch, "b.gltf", b);
  s.start(DaemonOptions().with_republish(300));
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("b.gltf", 1, content_hash(b)));

  Subscriber late;  // Asks for nothing.
  // Two rounds of republication reach it.
  ASSERT_TRUE(late.wait_for([](const auto& all) { return on_kind(all, "DESCRIPTION").size() >= 4; }, 3s))
      << ::testing::PrintToString(model_events(late.messages()));
  const auto got = late.messages();
  for (const auto& [id, hash] : {std::pair<std::string, std::string>{"a.gltf", content_hash(a)}, {"b.gltf", content_hash(b)}}) {
    const auto descriptions = decoded<rdtf::description_t>(got, "DESCRIPTION", id);
    ASSERT_GE(descriptions.size(), 2u) << id;
    for (const auto& d : descriptions) {
      EXPECT_EQ(d.revision, 1);
      EXPECT_EQ(d.content_hash, hash);
      expect_document(d, id == "a.gltf" ? "a_base" : "b_base");
    }
    // Each description with its table, and nothing else.
    for (const auto& line : model_events(got, id)) {
      EXPECT_TRUE(line == id + " DESCRIPTION r1 " + short_hash(hash) || line == id + " INERTIA r1 " + short_hash(hash))
          << line;
    }
    expect_inertia_matches(*last_inertia(got, id), inspect(s.watch / id));
    // About one round per period.
    const auto times = on_kind(got, "DESCRIPTION", id);
    const auto gap = times[1].received - times[0].received;
    EXPECT_GT(gap, 200ms);
    EXPECT_LT(gap, 1000ms);
  }
  EXPECT_EQ(on_kind(got, "REQUEST").size(), 0u);
}

TEST(DaemonPublish, LargeDescriptionArrivesInChunksAndReassembles) {
  Session s;
  const auto big = many_parts_model("big_base", 1500, 0.01);
  const auto path = write_model(s.watch, "big.gltf", big);
  s.start();
  ASSERT_TRUE(s.wait_revision("big.gltf", 1, content_hash(big), 10s))
      << ::testing::PrintToString(model_events(s.messages())) << s.daemon->log();
  ASSERT_TRUE(s.wait_idle());

  const auto all = s.messages();
  const auto description = last_description(all, "big.gltf");
  ASSERT_TRUE(description);
  ASSERT_GT(description->rdtf_json_size, 60000) << "the model is too small to need chunks";
  EXPECT_EQ(description->rdtf_json, "");
  ASSERT_GT(description->num_chunks, 1);

  // Chunks 0..count-1 of this revision, each once, each one datagram, all before the description.
  std::map<int, std::string> parts;
  std::size_t description_at = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].kind() == "DESCRIPTION") description_at = i;
  }
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].kind() != "DESCRIPTION_CHUNK") continue;
    EXPECT_LT(i, description_at);
    EXPECT_LT(all[i].bytes.size(), 65000u);
    const auto chunk = all[i].as<rdtf::description_chunk_t>();
    EXPECT_EQ(chunk.model_id, "big.gltf");
    EXPECT_EQ(chunk.revision, 1);
    EXPECT_EQ(chunk.content_hash, content_hash(big));
    EXPECT_EQ(chunk.count, description->num_chunks);
    EXPECT_EQ(chunk.size, static_cast<std::int32_t>(chunk.data.size()));
    EXPECT_LE(chunk.data.size(), 60000u);
    EXPECT_FALSE(parts.count(chunk.index)) << "chunk " << chunk.index << " twice";
    parts[chunk.index] = std::string(chunk.data.begin(), chunk.data.end());
  }
  ASSERT_EQ(parts.size(), static_cast<std::size_t>(description->num_chunks));
  std::string json;
  for (int i = 0; i < description->num_chunks; ++i) {
    ASSERT_TRUE(parts.count(i)) << "chunk " << i << " missing";
    json += parts[i];
  }
  EXPECT_EQ(static_cast<std::int64_t>(json.size()), description->rdtf_json_size);
  EXPECT_EQ(json, read(description->output_path)) << "reassembled JSON differs from the output file";
  // The announced hash is "hex SHA-256 of the full JSON" (lcmtypes/rdtf_description_t.lcm): what
  // a subscriber computes with any SHA-256 (sha256sum, hashlib) over the reassembled bytes.
  EXPECT_EQ(description->rdtf_json_sha256, sha256_plain(json))
      << "announced " << description->rdtf_json_sha256 << "; the daemon's length-prefixed hash of the JSON is "
      << sha256({json}, true);
  Json document;
  ASSERT_NO_THROW(document = Json::parse(json));
  ASSERT_TRUE(document["extras"].contains("RDTF"));
  // Every part is in the published document (the conversion may add nodes of its own).
  std::set<std::string> names;
  for (const auto& node : document["nodes"]) names.insert(node.value("name", ""));
  EXPECT_TRUE(names.count("big_base"));
  EXPECT_TRUE(names.count("part_00000") && names.count("part_01499"));
  EXPECT_GE(document["nodes"].size(), 1501u);
  EXPECT_EQ(description->num_links, 1);
  const auto inertia = last_inertia(all, "big.gltf");
  ASSERT_TRUE(inertia);
  EXPECT_NEAR(inertia->total_mass, big.link_mass, 1e-6 * big.link_mass);
  expect_inertia_matches(*inertia, inspect(path));
  EXPECT_EQ(model_events(all, "big.gltf").size(), static_cast<std::size_t>(description->num_chunks) + 2);

  // A late subscriber asking for it gets every chunk again.
  Subscriber late;
  s.request("big.gltf");
  ASSERT_TRUE(late.wait_for([](const auto& got) { return !on_kind(got, "INERTIA").empty(); }));
  const auto got = late.messages();
  std::string again;
  for (const auto& chunk : decoded<rdtf::description_chunk_t>(got, "DESCRIPTION_CHUNK")) {
    again += std::string(chunk.data.begin(), chunk.data.end());
  }
  EXPECT_EQ(again, json);
  EXPECT_EQ(on_kind(got, "DESCRIPTION_CHUNK").size(), static_cast<std::size_t>(description->num_chunks));
}

TEST(DaemonPublish, DescriptionAnnouncesThePlainSha256OfItsJson) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  const auto d = last_description(s.messages(), "a.gltf");
  ASSERT_TRUE(d);
  ASSERT_FALSE(d->rdtf_json.empty());
  EXPECT_EQ(d->rdtf_json_sha256, sha256_plain(d->rdtf_json))
      << "the daemon announces sha256(uint64 length || json) = " << sha256({d->rdtf_json}, true);
}

TEST(DaemonPublish, ChannelPrefixAndLongModelIdsFitLcmChannelNames) {
  const std::string prefix = "LABORATORY_ROBOT";  // 16 characters: the longest allowed.
  Session s(prefix);
  const fs::path deep = s.watch / "a_rather_long_folder_name_for_a_project" / "another_level_of_nesting";
  fs::create_directories(deep);
  const auto long_model = box_model("long_base", 0.05);
  write_model(deep, "robot_model_final.gltf", long_model);
  const auto short_model = box_model("short_base", 0.06);
  write_model(s.watch, "short.gltf", short_model);
  s.start(DaemonOptions().with_args({"--channel-prefix", prefix}));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return on_kind(all, "INERTIA").size() >= 2; }))
      << ::testing::PrintToString(model_events(s.messages())) << s.daemon->log();
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  ASSERT_EQ(idle->model_ids.size(), 2u);
  const auto all = s.messages();
  // The long path's id: shortened to fit, keeping the end of the file name.
  std::string long_id;
  for (const auto& id : idle->model_ids) {
    if (id != "short.gltf") long_id = id;
  }
  EXPECT_LE(long_id.size(), 63u - prefix.size() - 1 - std::string("/DESCRIPTION_CHUNK").size()) << long_id;
  // With a 16-character prefix only about 28 characters are left for an id: a hash and the end.
  EXPECT_EQ(long_id.substr(long_id.size() - 11), "_final.gltf") << long_id;
  for (const auto& m : all) {
    EXPECT_LE(m.channel.size(), 63u) << m.channel;
    EXPECT_EQ(m.channel.rfind(prefix + "/", 0), 0u) << m.channel;
  }
  EXPECT_EQ(model_events(all, "short.gltf"), revision_events("short.gltf", 1, content_hash(short_model)));
  EXPECT_EQ(model_events(all, long_id), revision_events(long_id, 1, content_hash(long_model)));
  const auto d = last_description(all, long_id);
  ASSERT_TRUE(d);
  EXPECT_EQ(d->model_id, long_id);
  EXPECT_EQ(fs::path(d->source_path), fs::canonical(deep / "robot_model_final.gltf"));
  expect_document(*d, "long_base");
  // Requests go to <prefix>/REQUEST and find the model by its (shortened) id.
  Subscriber late(prefix + "/.*");
  s.request(long_id);
  ASSERT_TRUE(late.wait_for([](const auto& got) { return !on_kind(got, "INERTIA").empty(); }));
  ASSERT_TRUE(s.wait_idle());
  EXPECT_EQ(model_events(late.messages()), revision_events(long_id, 1, content_hash(long_model)));
}

// The messages of a recording, without the probes the test itself sent.
std::vector<Message> without_probes(std::vector<Message> all) {
  all.erase(std::remove_if(all.begin(), all.end(), [](const Message& m) { return m.kind() == "ITEST_PROBE"; }),
            all.end());
  return all;
}

TEST(DaemonPublish, LcmLoggerRecordingReplaysTheSameMessages) {
  Session s;
  const auto a = box_model("a_base", 0.05);
  write_model(s.watch, "a.gltf", a);
  copy_fixture(s.watch, "arm3");
  const fs::path log = s.root / "session.lcmlog";

  // Record everything, as the README shows. The logger is ready once a probe reaches its file.
  ChildProcess logger({"lcm-logger", "-f", log.string()}, s.root / "logger.out");
  ASSERT_TRUE(s.wait_logger_recording(log)) << "lcm-logger recorded nothing: " << logger.output();

  // A session: initial scan, a new revision, a broken save, a removal, a request.
  auto& daemon = s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  const auto a2 = box_model("a2_base", 0.06);
  write_by_rename(s.watch / "a.gltf", a2.gltf, "a.gltf.tmp");
  ASSERT_TRUE(s.wait_revision("a.gltf", 2, content_hash(a2)));
  write_by_rename(s.watch / "arm3.gltf", broken_model(), "arm3.gltf.tmp");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR").empty(); }));
  fs::remove(s.watch / "a.gltf");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "REMOVED").empty(); }));
  s.request("", "logger test");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return on_kind(all, "DESCRIPTION", "arm3.gltf").size() == 2; }));
  ASSERT_TRUE(s.wait_idle());
  daemon.signal(SIGTERM);
  ASSERT_EQ(daemon.wait_exit(5s), std::optional<int>(0));
  const auto live = without_probes(s.messages());
  ASSERT_EQ(model_events(live, "a.gltf"),
            concat({revision_events("a.gltf", 1, content_hash(a)), revision_events("a.gltf", 2, content_hash(a2)),
                    {"a.gltf REMOVED last=2"}}));
  ASSERT_EQ(model_events(live, "arm3.gltf"),
            concat({revision_events("arm3.gltf", 1, fixture_hash("arm3")),
                    {"arm3.gltf ERROR live=1 " + short_hash(content_hash(broken_model()))},
                    revision_events("arm3.gltf", 1, fixture_hash("arm3"))}));

  // The logger flushes every 100 ms and on SIGINT.
  logger.signal(SIGINT);
  ASSERT_TRUE(logger.wait_exit(5s).has_value()) << logger.output();

  // rdtf-echo prints what it receives; it is ready once it has printed a probe.
  // --no-request: an answer to its request would add to what the replay is compared with.
  ChildProcess echo({RDTF_ECHO_PATH, "-c", "RDTF/.*", "--no-request"}, s.root / "echo.out");
  rdtf::request_t probe;
  probe.utime = 0;
  probe.model_id = "";
  probe.requester = "probe";
  ASSERT_TRUE(wait_until(
      [&] {
        s.subscriber.publish("RDTF/ITEST_PROBE", probe);
        return echo.output().find("ITEST_PROBE") != std::string::npos;
      },
      5s));
  Subscriber replay;
  ChildProcess player({"lcm-logplayer", "-s", "4", log.string()}, s.root / "player.out");
  ASSERT_EQ(player.wait_exit(30s), std::optional<int>(0)) << player.output();
  ASSERT_TRUE(replay.wait_for([&](const auto& all) { return without_probes(all).size() >= live.size(); }, 5s))
      << "replayed " << without_probes(replay.messages()).size() << " of " << live.size();
  const auto replayed = without_probes(replay.messages());

  // The same messages, channels and payload bytes, in the same order.
  ASSERT_EQ(replayed.size(), live.size());
  for (std::size_t i = 0; i < live.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, live[i].channel) << i;
    EXPECT_EQ(replayed[i].bytes, live[i].bytes) << i << " on " << live[i].channel;
  }

  // And rdtf-echo printed each as one JSON line, decoded.
  echo.signal(SIGTERM);
  ASSERT_EQ(echo.wait_exit(5s), std::optional<int>(0));
  std::vector<Json> lines;
  std::istringstream text(echo.output());
  for (std::string line; std::getline(text, line);) {
    if (line.empty()) continue;
    Json parsed;
    ASSERT_NO_THROW(parsed = Json::parse(line)) << line;
    if (parsed["channel"].get<std::string>().find("ITEST_PROBE") != std::string::npos) continue;
    lines.push_back(parsed);
  }
  ASSERT_EQ(lines.size(), live.size());
  for (std::size_t i = 0; i < live.size(); ++i) {
    EXPECT_EQ(lines[i]["channel"], live[i].channel) << i;
    EXPECT_EQ(lines[i]["message"], live[i].json()) << i;
    EXPECT_FALSE(live[i].json().is_null()) << live[i].channel << " is no rdtf type";
  }
}

}  // namespace
}  // namespace rdtf::itest
