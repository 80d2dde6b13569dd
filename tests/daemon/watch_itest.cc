// rdtfd against the ways files really get saved: each test drives a real rdtfd on a temporary
// folder and checks, over real LCM, exactly which revisions a subscriber sees, with which content,
// and that nothing else is published. See harness.h for how these tests run. How events are
// scheduled (bursts, skips, renames, recreation) is tested in-process, faster and without wall
// time, in daemon_loop_test.cc and watcher_test.cc; these keep what needs the real process.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <set>

#include <rdtf/model_saving_t.hpp>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

// Every description and inertia table of `id` published so far carries `hash`'s content:
// document with extras.RDTF, and the masses `rdtf inspect --json` gives for `file`.
void expect_content(const Session& s, const std::string& id, const fs::path& file, const std::string& hash,
                    const std::string& base_name = "") {
  SCOPED_TRACE("content of " + id);
  const auto all = s.messages();
  const auto description = last_description(all, id);
  const auto inertia = last_inertia(all, id);
  ASSERT_TRUE(description && inertia);
  EXPECT_EQ(description->content_hash, hash);
  EXPECT_EQ(inertia->content_hash, hash);
  EXPECT_EQ(inertia->revision, description->revision);
  EXPECT_EQ(description->model_id, id);
  EXPECT_EQ(fs::path(description->source_path), fs::canonical(file));
  expect_document(*description, base_name);
  const Json inspected = inspect(file);
  EXPECT_EQ(description->num_links, static_cast<std::int32_t>(inspected["links"].size()));
  EXPECT_EQ(description->num_joints, static_cast<std::int32_t>(inspected["joints"].size()));
  expect_inertia_matches(*inertia, inspected);
}

std::vector<std::string> sorted(std::vector<std::string> v) {
  std::sort(v.begin(), v.end());
  return v;
}

TEST(DaemonWatch, InitialScanPublishesEachModelOnce) {
  Session s;
  copy_fixture(s.watch, "arm3");
  copy_fixture(s.watch, "two_cylinder");
  copy_fixture(s.watch, "transforms");
  fs::create_directories(s.watch / "sub");
  const auto box = box_model("box_base", 0.1);
  write_model(s.watch / "sub", "box.gltf", box);
  s.start();

  const std::map<std::string, std::string> expected = {
      {"arm3.gltf", fixture_hash("arm3")},
      {"two_cylinder.gltf", fixture_hash("two_cylinder")},
      {"transforms.gltf", fixture_hash("transforms")},
      {"sub/box.gltf", content_hash(box)}};
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    for (const auto& [id, hash] : expected) {
      if (!has_revision(all, id, 1, hash)) return false;
    }
    return true;
  })) << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 4);
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(idle->num_models, 4);
  EXPECT_EQ(idle->rescans, 1);  // The start.
  EXPECT_EQ(sorted(idle->model_ids), sorted({"arm3.gltf", "two_cylinder.gltf", "transforms.gltf", "sub/box.gltf"}));

  const auto all = s.messages();
  for (const auto& [id, hash] : expected) {
    EXPECT_EQ(model_events(all, id), revision_events(id, 1, hash)) << id;
  }
  EXPECT_EQ(model_events(all).size(), 8u) << ::testing::PrintToString(model_events(all));
  expect_content(s, "arm3.gltf", s.watch / "arm3.gltf", expected.at("arm3.gltf"), "base_link");
  expect_content(s, "two_cylinder.gltf", s.watch / "two_cylinder.gltf", expected.at("two_cylinder.gltf"));
  expect_content(s, "transforms.gltf", s.watch / "transforms.gltf", expected.at("transforms.gltf"));
  expect_content(s, "sub/box.gltf", s.watch / "sub" / "box.gltf", expected.at("sub/box.gltf"), "box_base");
  // A 0.2 m cube of water: 8 kg.
  EXPECT_NEAR(last_inertia(all, "sub/box.gltf")->total_mass, 8.0, 1e-5);
  // Logged after the description is sent: it may come a moment after the revision arrived.
  EXPECT_TRUE(s.daemon->wait_log("converted arm3.gltf revision 1 (3 links, 2 joints) in ")) << s.daemon->log();
}

TEST(DaemonWatch, CopyingInAModelConvertsItOnce) {
  Session s;
  s.start();
  ASSERT_TRUE(s.wait_idle());
  // As `cp` does it: the .gltf, then the .bin it refers to.
  const fs::path source = testing::data_dir() / "blender";
  fs::copy_file(source / "arm3.gltf", s.watch / "arm3.gltf");
  fs::copy_file(source / "arm3.bin", s.watch / "arm3.bin");
  const std::string hash = fixture_hash("arm3");
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, hash)) << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 1);
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(model_events(s.messages()), revision_events("arm3.gltf", 1, hash));
  expect_content(s, "arm3.gltf", s.watch / "arm3.gltf", hash, "base_link");
}

TEST(DaemonWatch, BlenderStyleSaveGltfThenBinInPlaceGivesOneRevision) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05, 1, "robot.bin");
  const auto path = write_model(s.watch, "robot.gltf", v1);
  s.start(DaemonOptions().with_settle(150));
  ASSERT_TRUE(s.wait_revision("robot.gltf", 1, content_hash(v1)));
  ASSERT_TRUE(s.wait_idle());

  // Blender: the .gltf, then the .bin, each written in place. New JSON with the old .bin (or the
  // old JSON with the new .bin) would give a wrong model: only the pair may be converted.
  const auto v2 = box_model("v2_base", 0.08, 3, "robot.bin");
  write_in_place(path, v2.gltf);
  write_in_place(s.watch / "robot.bin", v2.bin);
  ASSERT_TRUE(s.wait_revision("robot.gltf", 2, content_hash(v2)))
      << ::testing::PrintToString(model_events(s.messages()));
  ASSERT_TRUE(s.wait_idle());
  expect_content(s, "robot.gltf", path, content_hash(v2), "v2_base");
  EXPECT_NEAR(last_inertia(s.messages(), "robot.gltf")->total_mass, 3 * v2.link_mass, 1e-6);

  // A slower exporter: the .bin starts 50 ms after the .gltf closed (within the 150 ms settle).
  const auto v3 = box_model("v3_base", 0.06, 2, "robot.bin");
  write_in_place(path, v3.gltf);
  std::this_thread::sleep_for(50ms);  // Deliberate spacing of the two writes.
  write_in_place(s.watch / "robot.bin", v3.bin);
  ASSERT_TRUE(s.wait_revision("robot.gltf", 3, content_hash(v3)))
      << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 3);
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(model_events(s.messages()),
            concat({revision_events("robot.gltf", 1, content_hash(v1)),
                    revision_events("robot.gltf", 2, content_hash(v2)),
                    revision_events("robot.gltf", 3, content_hash(v3))}));
  expect_content(s, "robot.gltf", path, content_hash(v3), "v3_base");
}

TEST(DaemonWatch, FirstExportOfANewModelWaitsForItsSlowBin) {
  // Blender exporting a new model: the .gltf, then a large .bin that takes longer than the settle
  // period to write. facts.md: "group a .gltf with the files it references and settle on the
  // group". The .bin is held open while written, so the model must wait for it: one conversion
  // of the whole, and no ERROR for a half-written .bin.
  Session s;
  s.start(DaemonOptions().with_settle(100));
  ASSERT_TRUE(s.wait_idle());
  const auto model = box_model("new_base", 0.05, 2, "new.bin");
  const auto path = s.watch / "new.gltf";
  write_in_place(path, model.gltf);
  {
    OpenFile bin(s.watch / "new.bin");
    bin.write(model.bin.substr(0, 100));
    std::this_thread::sleep_for(300ms);  // Deliberate: the writer is still busy with the .bin.
    bin.write(model.bin.substr(100));
  }
  ASSERT_TRUE(s.wait_revision("new.gltf", 1, content_hash(model)))
      << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(model_events(s.messages()), revision_events("new.gltf", 1, content_hash(model)));
  EXPECT_EQ(idle->rejections, 0);
  expect_content(s, "new.gltf", path, content_hash(model), "new_base");
}

TEST(DaemonWatch, EditorStyleSavesByRenameGiveOneRevisionEach) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05);
  const auto path = write_model(s.watch, "arm.gltf", v1);
  s.start();
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(v1)));

  // Write a temporary file, rename it over the model (names the daemon ignores meanwhile).
  const auto v2 = box_model("v2_base", 0.06);
  write_by_rename(path, v2.gltf, "arm.gltf.tmp");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(v2)))
      << ::testing::PrintToString(model_events(s.messages()));
  const auto v3 = box_model("v3_base", 0.07);
  write_by_rename(path, v3.gltf, ".arm.gltf.swp");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 3, content_hash(v3)))
      << ::testing::PrintToString(model_events(s.messages()));
  // vim with backupcopy=no: the model moves to a backup name, a new file takes its name.
  const auto v4 = box_model("v4_base", 0.08);
  fs::rename(path, s.watch / "arm.gltf~");
  write_in_place(path, v4.gltf);
  fs::remove(s.watch / "arm.gltf~");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 4, content_hash(v4)))
      << ::testing::PrintToString(model_events(s.messages()));

  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 4);
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(idle->num_models, 1);  // The temporary names never became models.
  EXPECT_EQ(model_events(s.messages()),
            concat({revision_events("arm.gltf", 1, content_hash(v1)), revision_events("arm.gltf", 2, content_hash(v2)),
                    revision_events("arm.gltf", 3, content_hash(v3)), revision_events("arm.gltf", 4, content_hash(v4))}));
  expect_content(s, "arm.gltf", path, content_hash(v4), "v4_base");
}

TEST(DaemonWatch, ThreePartialWritesOfAnOpenFileGiveOneConversion) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05);
  const auto path = write_model(s.watch, "arm.gltf", v1);
  s.start(DaemonOptions().with_settle(50));
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(v1)));
  ASSERT_TRUE(s.wait_idle());

  // One writer, three writes 150 ms apart (each longer than the settle period), then close:
  // the file is open for writing throughout, so no half of it may be converted.
  const auto v2 = box_model("v2_base", 0.09, 2);
  const std::size_t third = v2.gltf.size() / 3;
  {
    OpenFile file(path);
    file.write(v2.gltf.substr(0, third));
    std::this_thread::sleep_for(150ms);  // Deliberate spacing.
    file.write(v2.gltf.substr(third, third));
    std::this_thread::sleep_for(150ms);
    file.write(v2.gltf.substr(2 * third));
  }
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(v2)))
      << ::testing::PrintToString(model_events(s.messages()));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 2);
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(model_events(s.messages()),
            concat({revision_events("arm.gltf", 1, content_hash(v1)), revision_events("arm.gltf", 2, content_hash(v2))}));
  expect_content(s, "arm.gltf", path, content_hash(v2), "v2_base");
}

TEST(DaemonWatch, DeletingAModelAnnouncesItRemoved) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05);
  const auto path = write_model(s.watch, "gone.gltf", v1);
  const auto stays = box_model("stays_base", 0.05);
  write_model(s.watch, "stays.gltf", stays);
  s.start();
  ASSERT_TRUE(s.wait_revision("gone.gltf", 1, content_hash(v1)));
  ASSERT_TRUE(s.wait_revision("stays.gltf", 1, content_hash(stays)));
  fs::remove(path);
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "REMOVED").empty(); }));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  const auto all = s.messages();
  EXPECT_EQ(model_events(all, "gone.gltf"),
            concat({revision_events("gone.gltf", 1, content_hash(v1)), {"gone.gltf REMOVED last=1"}}));
  EXPECT_EQ(model_events(all, "stays.gltf"), revision_events("stays.gltf", 1, content_hash(stays)));
  const auto removed = decoded<rdtf::model_removed_t>(all, "REMOVED");
  ASSERT_EQ(removed.size(), 1u);
  EXPECT_EQ(removed[0].model_id, "gone.gltf");
  EXPECT_EQ(fs::path(removed[0].source_path), fs::canonical(s.watch) / "gone.gltf");
  EXPECT_EQ(idle->num_models, 1);
  EXPECT_EQ(idle->model_ids, std::vector<std::string>{"stays.gltf"});
  EXPECT_NE(s.daemon->log().find("removed gone.gltf"), std::string::npos) << s.daemon->log();

  // A request afterwards no longer mentions it.
  const std::size_t before = s.messages().size();
  s.request();
  ASSERT_TRUE(s.wait_for([&](const auto& a) { return on_kind(a, "DESCRIPTION").size() == 3; }));
  ASSERT_TRUE(s.wait_idle());
  const auto everything = s.messages();
  const std::vector<Message> after(everything.begin() + static_cast<std::ptrdiff_t>(before), everything.end());
  EXPECT_EQ(model_events(after), revision_events("stays.gltf", 1, content_hash(stays)));
}

TEST(DaemonWatch, SavingIdenticalContentIsSkipped) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05, 1, "arm.bin");
  const auto path = write_model(s.watch, "arm.gltf", v1);
  s.start();
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(v1)));
  ASSERT_TRUE(s.wait_idle());
  write_in_place(path, v1.gltf);                  // Same bytes saved again.
  write_in_place(s.watch / "arm.bin", v1.bin);   // And its .bin.
  ASSERT_TRUE(s.wait_for([](const auto& all) {
    const auto st = statuses(all);
    return !st.empty() && st.back().skipped_unchanged >= 1;
  }));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->skipped_unchanged, 1);
  EXPECT_EQ(idle->conversions, 1);
  EXPECT_EQ(model_events(s.messages()), revision_events("arm.gltf", 1, content_hash(v1)));

  // The .bin alone changing is a change of the model (its content hash covers the .bin). Swap
  // corners 0 and 7 in the vertex data and in the indices: the same box in other bytes.
  auto bin = v1.bin;
  std::swap_ranges(bin.begin(), bin.begin() + 12, bin.begin() + 7 * 12);
  for (std::size_t offset = 96; offset < bin.size(); offset += 2) {
    std::uint16_t index;
    std::memcpy(&index, bin.data() + offset, 2);
    index = index == 0 ? 7 : index == 7 ? 0 : index;
    std::memcpy(bin.data() + offset, &index, 2);
  }
  ASSERT_NE(bin, v1.bin);
  write_in_place(s.watch / "arm.bin", bin);
  const auto hash2 = content_hash(v1.gltf, {bin});
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, hash2)) << ::testing::PrintToString(model_events(s.messages()));
  ASSERT_TRUE(s.wait_idle());
  EXPECT_EQ(model_events(s.messages()),
            concat({revision_events("arm.gltf", 1, content_hash(v1)), revision_events("arm.gltf", 2, hash2)}));
  EXPECT_NEAR(last_inertia(s.messages(), "arm.gltf")->total_mass, v1.link_mass, 1e-6);
}

// SAVING (lcmtypes/rdtf_model_saving_t.lcm): once per save of a live model, before the revision
// it gives, naming the live revision and the settle period; never for the start's scan, nor for
// the first conversion of a model (nothing is live to be replaced).
TEST(DaemonWatch, ASaveOfALiveModelIsAnnouncedOnceBeforeItsRevision) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05, 1, "arm.bin");
  const auto path = write_model(s.watch, "arm.gltf", v1);
  s.start(DaemonOptions().with_settle(120));
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(v1)));
  ASSERT_TRUE(s.wait_idle());
  EXPECT_TRUE(decoded<rdtf::model_saving_t>(s.messages(), "SAVING", "arm.gltf").empty());

  // Three writes within the settle period: one save, one SAVING.
  const auto v2 = box_model("v2_base", 0.05, 1, "arm.bin");
  write_in_place(path, v2.gltf);
  write_in_place(path, v2.gltf);
  write_in_place(path, v2.gltf);
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(v2)));
  ASSERT_TRUE(s.wait_idle());
  const auto all = s.messages();
  const auto savings = decoded<rdtf::model_saving_t>(all, "SAVING", "arm.gltf");
  ASSERT_EQ(savings.size(), 1u);
  EXPECT_EQ(savings[0].model_id, "arm.gltf");
  EXPECT_EQ(savings[0].live_revision, 1);
  EXPECT_EQ(savings[0].settle_ms, 120);
  // In order: revision 1's DESCRIPTION, the SAVING, revision 2's DESCRIPTION.
  std::vector<std::string> order;
  for (const auto& m : all) {
    if (m.model_id() != "arm.gltf") continue;
    if (m.kind() == "SAVING") order.push_back("SAVING");
    if (m.kind() == "DESCRIPTION") order.push_back("r" + std::to_string(m.as<rdtf::description_t>().revision));
  }
  EXPECT_EQ(order, (std::vector<std::string>{"r1", "SAVING", "r2"}));
}

TEST(DaemonWatch, BrokenSaveKeepsTheGoodRevisionAndPublishesTheError) {
  Session s;
  const auto good = box_model("good_base", 0.05);
  const auto path = write_model(s.watch, "arm.gltf", good);
  s.start();
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(good)));
  ASSERT_TRUE(s.wait_idle());

  const std::string broken = broken_model();
  write_by_rename(path, broken, "arm.gltf.tmp");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR").empty(); }));
  auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->rejections, 1);
  EXPECT_EQ(idle->num_models, 1);  // Still served.
  EXPECT_EQ(idle->model_ids, std::vector<std::string>{"arm.gltf"});

  const auto errors = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "arm.gltf");
  ASSERT_EQ(errors.size(), 1u);
  const auto& error = errors[0];
  EXPECT_EQ(error.model_id, "arm.gltf");
  EXPECT_EQ(fs::path(error.source_path), fs::canonical(path));
  EXPECT_EQ(error.live_revision, 1);
  EXPECT_EQ(error.content_hash, content_hash(broken));
  ASSERT_EQ(error.num_diagnostics, static_cast<std::int32_t>(error.diagnostics.size()));
  ASSERT_FALSE(error.diagnostics.empty());
  bool located = false;
  for (const auto& d : error.diagnostics) {
    if (d.severity != rdtf::diagnostic_t::ERROR) continue;
    EXPECT_EQ(fs::path(d.file), fs::canonical(path)) << d.code << ": " << d.message;
    EXPECT_FALSE(d.code.empty());
    EXPECT_FALSE(d.message.empty());
    // The bad reference is /meshes/0/primitives/0/attributes/POSITION (accessor 7 of 2).
    if (d.pointer.rfind("/meshes/0/primitives/0", 0) == 0) located = true;
  }
  EXPECT_TRUE(located) << "no error points at the mesh: " << on_kind(s.messages(), "ERROR").at(0).json().dump();
  EXPECT_NE(s.daemon->log().find("rejected arm.gltf"), std::string::npos) << s.daemon->log();
  EXPECT_NE(s.daemon->log().find("still serving revision 1"), std::string::npos) << s.daemon->log();

  // A late subscriber's request gets the good revision, with its old number.
  s.request("arm.gltf");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return on_kind(all, "DESCRIPTION").size() == 2; }));
  ASSERT_TRUE(s.wait_idle());
  const auto descriptions = decoded<rdtf::description_t>(s.messages(), "DESCRIPTION", "arm.gltf");
  EXPECT_EQ(descriptions[1].revision, 1);
  EXPECT_EQ(descriptions[1].content_hash, content_hash(good));
  EXPECT_EQ(descriptions[1].rdtf_json, descriptions[0].rdtf_json);
  expect_document(descriptions[1], "good_base");

  // Fixing the file gives revision 2.
  const auto fixed = box_model("fixed_base", 0.06);
  write_by_rename(path, fixed.gltf, "arm.gltf.tmp");
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(fixed)));
  idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(model_events(s.messages()),
            concat({revision_events("arm.gltf", 1, content_hash(good)),
                    {"arm.gltf ERROR live=1 " + short_hash(content_hash(broken))},
                    revision_events("arm.gltf", 1, content_hash(good)),
                    revision_events("arm.gltf", 2, content_hash(fixed))}));
  expect_content(s, "arm.gltf", path, content_hash(fixed), "fixed_base");
}

TEST(DaemonWatch, NewSubfoldersAreWatchedAndTheirModelsConverted) {
  Session s;
  s.start();
  ASSERT_TRUE(s.wait_idle());
  // A folder, then a model in it straight away (before the daemon may have added its watch).
  fs::create_directories(s.watch / "sub");
  const auto x = box_model("x_base", 0.05, 1, "x.bin");
  write_model(s.watch / "sub", "x.gltf", x);
  ASSERT_TRUE(s.wait_revision("sub/x.gltf", 1, content_hash(x)))
      << ::testing::PrintToString(model_events(s.messages()));
  // Several levels at once.
  fs::create_directories(s.watch / "deep" / "a" / "b");
  const auto y = box_model("y_base", 0.06);
  write_model(s.watch / "deep" / "a" / "b", "y.gltf", y);
  ASSERT_TRUE(s.wait_revision("deep/a/b/y.gltf", 1, content_hash(y)));
  // A folder with a model, prepared elsewhere and moved in.
  fs::create_directories(s.root / "staging" / "z");
  const auto z = box_model("z_base", 0.07);
  write_model(s.root / "staging" / "z", "z.gltf", z);
  fs::rename(s.root / "staging" / "z", s.watch / "moved");
  ASSERT_TRUE(s.wait_revision("moved/z.gltf", 1, content_hash(z)));
  // And a single model file moved in.
  const auto w = box_model("w_base", 0.08);
  write_model(s.root / "staging", "w.gltf", w);
  fs::rename(s.root / "staging" / "w.gltf", s.watch / "sub" / "w.gltf");
  ASSERT_TRUE(s.wait_revision("sub/w.gltf", 1, content_hash(w)));

  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 4);
  EXPECT_EQ(idle->rejections, 0);
  const auto all = s.messages();
  EXPECT_EQ(model_events(all),
            concat({revision_events("sub/x.gltf", 1, content_hash(x)), revision_events("deep/a/b/y.gltf", 1, content_hash(y)),
                    revision_events("moved/z.gltf", 1, content_hash(z)), revision_events("sub/w.gltf", 1, content_hash(w))}));
  // The channels are <prefix>/<path below the watched folder>/<kind>.
  EXPECT_EQ(on_kind(all, "DESCRIPTION", "sub/x.gltf").at(0).channel, "RDTF/sub/x.gltf/DESCRIPTION");
  EXPECT_EQ(on_kind(all, "INERTIA", "deep/a/b/y.gltf").at(0).channel, "RDTF/deep/a/b/y.gltf/INERTIA");
  expect_content(s, "sub/x.gltf", s.watch / "sub" / "x.gltf", content_hash(x), "x_base");
  expect_content(s, "moved/z.gltf", s.watch / "moved" / "z.gltf", content_hash(z), "z_base");
}

TEST(DaemonWatch, MovingModelsOutOfTheTreeRemovesThem) {
  Session s;
  fs::create_directories(s.watch / "sub");
  fs::create_directories(s.root / "elsewhere");
  const auto a = box_model("a_base", 0.05);
  const auto b = box_model("b_base", 0.06);
  const auto c = box_model("c_base", 0.07);
  write_model(s.watch, "a.gltf", a);
  write_model(s.watch / "sub", "b.gltf", b);
  write_model(s.watch, "c.gltf", c);
  s.start();
  ASSERT_TRUE(s.wait_revision("a.gltf", 1, content_hash(a)));
  ASSERT_TRUE(s.wait_revision("sub/b.gltf", 1, content_hash(b)));
  ASSERT_TRUE(s.wait_revision("c.gltf", 1, content_hash(c)));
  fs::rename(s.watch / "a.gltf", s.root / "elsewhere" / "a.gltf");  // A file moved out.
  fs::rename(s.watch / "sub", s.root / "elsewhere" / "sub");         // A folder moved out.
  ASSERT_TRUE(s.wait_for([](const auto& all) { return on_kind(all, "REMOVED").size() >= 2; }));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  const auto all = s.messages();
  EXPECT_EQ(model_events(all, "a.gltf"), concat({revision_events("a.gltf", 1, content_hash(a)), {"a.gltf REMOVED last=1"}}));
  EXPECT_EQ(model_events(all, "sub/b.gltf"),
            concat({revision_events("sub/b.gltf", 1, content_hash(b)), {"sub/b.gltf REMOVED last=1"}}));
  EXPECT_EQ(model_events(all, "c.gltf"), revision_events("c.gltf", 1, content_hash(c)));
  EXPECT_EQ(idle->model_ids, std::vector<std::string>{"c.gltf"});
  // Changes in the moved-away folder are no longer ours.
  write_model(s.root / "elsewhere" / "sub", "b.gltf", box_model("b2_base", 0.08));
  const auto later = s.wait_idle();
  ASSERT_TRUE(later);
  EXPECT_EQ(model_events(s.messages()), model_events(all));
  EXPECT_EQ(later->conversions, idle->conversions);
}

TEST(DaemonWatch, OutputsInsideTheWatchedFolderNeverTriggerConversions) {
  Session s;
  const auto v1 = box_model("v1_base", 0.05, 2, "arm.bin");
  const auto path = write_model(s.watch, "arm.gltf", v1);
  const fs::path output = s.watch / "out";  // Inside the watched tree.
  s.start(DaemonOptions().with_output(output));
  ASSERT_TRUE(s.wait_revision("arm.gltf", 1, content_hash(v1)));
  auto idle = s.wait_idle(5);
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 1);
  EXPECT_EQ(idle->skipped_unchanged, 0);
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(idle->num_models, 1);

  // The output is where the description says, and is the published document.
  const auto d = last_description(s.messages(), "arm.gltf");
  ASSERT_TRUE(d);
  const fs::path written = d->output_path;
  EXPECT_EQ(written.parent_path().parent_path(), fs::canonical(output)) << written;
  EXPECT_EQ(written.filename(), "arm.rdtf.gltf");
  ASSERT_TRUE(fs::exists(written));
  EXPECT_EQ(read(written), d->rdtf_json);

  const auto v2 = box_model("v2_base", 0.06, 2, "arm.bin");
  write_in_place(path, v2.gltf);
  write_in_place(s.watch / "arm.bin", v2.bin);
  ASSERT_TRUE(s.wait_revision("arm.gltf", 2, content_hash(v2)));
  idle = s.wait_idle(5);
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 2);
  EXPECT_EQ(idle->skipped_unchanged, 0);
  EXPECT_EQ(idle->num_models, 1);
  EXPECT_EQ(model_events(s.messages()),
            concat({revision_events("arm.gltf", 1, content_hash(v1)), revision_events("arm.gltf", 2, content_hash(v2))}));
  // No temporary file of the atomic writes is left behind.
  for (const auto& entry : fs::recursive_directory_iterator(output)) {
    EXPECT_EQ(entry.path().extension() == ".tmp", false) << entry.path();
  }
}

TEST(DaemonWatch, QueueOverflowTriggersARescanAndNothingIsMissed) {
  Session s;
  std::map<std::string, GeneratedModel> v1;
  for (const char* name : {"m1", "m2", "m3", "m4"}) {
    v1[name] = box_model(std::string(name) + "_v1", 0.05);
    write_model(s.watch, std::string(name) + ".gltf", v1[name]);
  }
  fs::create_directories(s.watch / "noise");
  auto& daemon = s.start();
  for (const auto& [name, model] : v1) ASSERT_TRUE(s.wait_revision(name + ".gltf", 1, content_hash(model)));
  ASSERT_TRUE(s.wait_idle());

  // Hold the daemon still (as if busy) so the kernel queue (max_queued_events 16384) fills.
  daemon.signal(SIGSTOP);
  const auto m1 = box_model("m1_v2", 0.06);
  write_by_rename(s.watch / "m1.gltf", m1.gltf, "m1.gltf.tmp");  // Queued before the overflow.
  // 10,000 new files: IN_CREATE + IN_CLOSE_WRITE each, 20,000 events.
  for (int i = 0; i < 10000; ++i) {
    const auto file = s.watch / "noise" / ("f" + std::to_string(i));
    const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0644);
    ASSERT_GE(fd, 0);
    ::close(fd);
  }
  // These events are dropped: only a rescan can find them.
  const auto m2 = box_model("m2_v2", 0.07);
  write_by_rename(s.watch / "m2.gltf", m2.gltf, "m2.gltf.tmp");
  fs::remove(s.watch / "m3.gltf");
  const auto m5 = box_model("m5_v1", 0.08);
  write_model(s.watch, "m5.gltf", m5);
  daemon.signal(SIGCONT);

  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    return has_revision(all, "m1.gltf", 2, content_hash(m1)) && has_revision(all, "m2.gltf", 2, content_hash(m2)) &&
           has_revision(all, "m5.gltf", 1, content_hash(m5)) && !on_kind(all, "REMOVED").empty();
  }, 10s)) << ::testing::PrintToString(model_events(s.messages())) << daemon.log();
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->rescans, 2);  // The start and the overflow.
  EXPECT_EQ(idle->skipped_unchanged, 1);  // m4, checked by the rescan, unchanged.
  EXPECT_EQ(idle->rejections, 0);
  EXPECT_EQ(sorted(idle->model_ids), sorted({"m1.gltf", "m2.gltf", "m4.gltf", "m5.gltf"}));
  const auto all = s.messages();
  EXPECT_EQ(model_events(all, "m1.gltf"),
            concat({revision_events("m1.gltf", 1, content_hash(v1["m1"])), revision_events("m1.gltf", 2, content_hash(m1))}));
  EXPECT_EQ(model_events(all, "m2.gltf"),
            concat({revision_events("m2.gltf", 1, content_hash(v1["m2"])), revision_events("m2.gltf", 2, content_hash(m2))}));
  EXPECT_EQ(model_events(all, "m3.gltf"), concat({revision_events("m3.gltf", 1, content_hash(v1["m3"])), {"m3.gltf REMOVED last=1"}}));
  EXPECT_EQ(model_events(all, "m4.gltf"), revision_events("m4.gltf", 1, content_hash(v1["m4"])));
  EXPECT_EQ(model_events(all, "m5.gltf"), revision_events("m5.gltf", 1, content_hash(m5)));
  EXPECT_NE(daemon.log().find("rescan (inotify queue overflow"), std::string::npos) << daemon.log();
  expect_content(s, "m2.gltf", s.watch / "m2.gltf", content_hash(m2), "m2_v2");

  // Still watching after the rescan.
  const auto m4 = box_model("m4_v2", 0.09);
  write_by_rename(s.watch / "m4.gltf", m4.gltf, "m4.gltf.tmp");
  EXPECT_TRUE(s.wait_revision("m4.gltf", 2, content_hash(m4)));
}

}  // namespace
}  // namespace rdtf::itest
