// rdtf-view end to end: the real rdtfd, rdtf-view and Debian's headless chromium (puppeteer-core,
// SwiftShader's WebGL) in the test case's network namespace (tests/clients/view_page.h). The page
// is read through its test hook window.rdtfView (docs/view.md); the bus through the harness's
// Subscriber. Screenshots go to build/test-artifacts/view/.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <rdtf/joint_command_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/model_saving_t.hpp>

#include "clients/live_arm.h"
#include "clients/view_page.h"

namespace rdtf::itest {
namespace {

DaemonOptions simulating() { return DaemonOptions().with("simulate", true).with("state_rate_hz", 50); }

// The page's model once it draws `revision` with a state from the simulation.
Json wait_drawn(Page& page, const std::string& id, std::int64_t revision, Clock::duration timeout = 20s) {
  Json m;
  page.wait_state([&](const Json& st) {
    m = model_in(st, id);
    return !m.is_null() && m["revision"] == revision && !m["sim_time"].is_null();
  }, timeout);
  return m;
}

// From the newest message back, up to the first older step of that revision: the waits below run
// this on every message that arrives, and decoding every state so far (50 Hz for each model) was
// quadratic, which under ASan on a loaded machine starved the subscriber's thread until the kernel
// dropped the very steps waited for.
std::optional<rdtf::link_state_t> link_state_at(const std::vector<Message>& all, const std::string& id,
                                                std::int64_t revision, double sim_time) {
  for (auto m = all.rbegin(); m != all.rend(); ++m) {
    if (m->kind() != "LINK_STATE" || m->model_id() != id) continue;
    const auto s = m->as<rdtf::link_state_t>();
    if (s.revision != revision) continue;
    if (s.sim_time == sim_time) return s;
    if (s.sim_time < sim_time) break;  // one simulation's steps arrive in order
  }
  return std::nullopt;
}

// Every drawn link at the position LINK_STATE gave it for the step the page shows. The page (through
// rdtf-view) and this test's subscriber receive the same datagrams on two sockets, and UDP may drop
// one on either: when the subscriber never gets the step the page shows, a later step the page
// draws is compared instead, up to five steps; the comparison itself is never relaxed.
// With `inertia` (the revision's INERTIA table), each link's centre-of-mass sphere is checked too:
// drawn at X_SF c_F, c_F the table's centre of mass in the link frame F.
void expect_links_where_link_state_puts_them(Session& s, Page& page, Json m, const std::string& id,
                                             const rdtf::inertia_table_t* inertia = nullptr) {
  const auto revision = m["revision"].get<std::int64_t>();
  std::optional<rdtf::link_state_t> state;
  std::vector<double> missed;
  for (int step = 0; step < 5; ++step) {
    const double sim_time = m["sim_time"].get<double>();
    // Under load the page may have drawn a step before the subscriber's thread stored it.
    if (s.wait_for([&](const std::vector<Message>& all) { return link_state_at(all, id, revision, sim_time).has_value(); },
                   5s)) {
      state = link_state_at(s.messages(), id, revision, sim_time);
      break;
    }
    missed.push_back(sim_time);
    Json later;
    ASSERT_TRUE(page.wait_state([&](const Json& st) {
      later = model_in(st, id);
      return !later.is_null() && later["revision"] == revision && later["sim_time"].is_number() &&
             later["sim_time"].get<double>() > sim_time;
    }, 10s)) << "the page draws no step after sim_time " << sim_time << ": " << later.dump();
    m = later;
  }
  ASSERT_TRUE(state) << "the subscriber has none of the steps the page drew, sim_time " << Json(missed).dump();
  ASSERT_EQ(m["links"].size(), state->name.size());
  for (const auto& link : m["links"]) {
    const auto at = std::find(state->name.begin(), state->name.end(), link["name"].get<std::string>());
    ASSERT_NE(at, state->name.end()) << link["name"];
    const auto i = static_cast<std::size_t>(at - state->name.begin());
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(link["position"][k].get<double>(), state->position[i][k], 1e-6) << link["name"];
    if (inertia == nullptr) continue;
    const auto row = std::find_if(inertia->links.begin(), inertia->links.end(), [&](const auto& l) { return l.name == link["name"]; });
    ASSERT_NE(row, inertia->links.end()) << link["name"];
    const Eigen::Quaterniond q_SF(state->orientation[i][0], state->orientation[i][1], state->orientation[i][2], state->orientation[i][3]);
    const Eigen::Vector3d c_S = Eigen::Vector3d(state->position[i].data()) + q_SF * Eigen::Vector3d(row->center_of_mass);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(link["com_drawn"][k].get<double>(), c_S[k], 1e-6) << link["name"];
  }
}

TEST(View, DrawsEveryLinkWhereLinkStatePutsItWithItsInertiaBox) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating());
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  const Json m = wait_drawn(page, kArm, 1);
  ASSERT_FALSE(m.is_null()) << page.state().dump() << "\n" << page.driver_log() << view.log();
  EXPECT_EQ(m["status"], "live");
  const auto table = last_inertia(s.messages(), kArm);
  ASSERT_TRUE(table);
  expect_links_where_link_state_puts_them(s, page, m, kArm, &*table);

  // Mass and the equivalent-inertia boxes, against Eigen's eigenvalues of the INERTIA table's
  // tensors: sides sqrt(6 (Ij + Ik - Ii) / m).
  EXPECT_NEAR(m["total_mass"].get<double>(), table->total_mass, 1e-12 * table->total_mass);
  for (const auto& l : table->links) {
    Eigen::Matrix3d I;
    I << l.ixx, l.ixy, l.ixz, l.ixy, l.iyy, l.iyz, l.ixz, l.iyz, l.izz;
    const Eigen::Vector3d p = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(I).eigenvalues();
    std::vector<double> expected = {std::sqrt(6 * (p[1] + p[2] - p[0]) / l.mass), std::sqrt(6 * (p[0] + p[2] - p[1]) / l.mass),
                                    std::sqrt(6 * (p[0] + p[1] - p[2]) / l.mass)};
    std::vector<double> drawn;
    for (const auto& link : m["links"]) {
      if (link["name"] == l.name) drawn = link["box"].get<std::vector<double>>();
    }
    ASSERT_EQ(drawn.size(), 3u) << l.name;
    std::sort(expected.begin(), expected.end());
    std::sort(drawn.begin(), drawn.end());
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(drawn[k], expected[k], 1e-9 * expected[2]) << l.name;
  }
  // Every overlay of every link in four draw calls (docs/view.md, "Overlays in four draw calls"):
  // with all shown, a frame draws the links' meshes, the grid and those four.
  // The frame count read in the same task as the toggle: the next frame draws everything shown.
  const auto frame =
      page.eval("(window.rdtfView.show({frames: true, com: true, inertia: true}), window.rdtfView.state().frame)")
          .get<std::int64_t>();
  std::int64_t meshes = 0;
  for (const auto& link : m["links"]) meshes += link["meshes"].get<std::int64_t>();
  Json drawn_all;
  ASSERT_TRUE(page.wait_state([&](const Json& st) { drawn_all = st; return st["frame"].get<std::int64_t>() > frame; }, 10s));
  EXPECT_EQ(drawn_all["renderer"]["draw_calls"].get<std::int64_t>(), meshes + 1 + 4) << drawn_all["renderer"].dump();
  page.screenshot("arm3_live_with_inertia_boxes.png");
  // Headless chromium rasterizes with SwiftShader, on the CPU: the page leaves multisampling off
  // there (docs/view.md, "Multisampling").
  const Json renderer = page.state()["renderer"];
  EXPECT_EQ(renderer["software"], true) << renderer.dump();
  EXPECT_EQ(renderer["antialias"], false) << renderer.dump();

  // Z up turns the drawing, not the scene frame the hook reports in.
  page.eval("window.rdtfView.setUp('z')");
  const Json turned = wait_drawn(page, kArm, 1);
  expect_links_where_link_state_puts_them(s, page, turned, kArm);
  page.screenshot("arm3_z_up.png");
}

TEST(View, ShowsASavedRevisionInPlaceWithoutReloadingThePage) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating());
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  ASSERT_FALSE(wait_drawn(page, kArm, 1).is_null()) << page.driver_log();
  page.eval("window.sameDocument = 'yes'");

  // The base raised from y = 0.1 to 0.3: every link 0.2 m higher.
  Json document = Json::parse(read(s.watch / kArm));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "base_link") node["translation"] = {0.0, 0.3, 0.0};
  }
  write_in_place(s.watch / kArm, document.dump(1));
  const Json m = wait_drawn(page, kArm, 2);
  ASSERT_FALSE(m.is_null()) << page.state().dump();
  EXPECT_EQ(page.eval("window.sameDocument"), "yes") << "the page was reloaded";
  // rdtfd announced the save (SAVING) and the page, rasterizing on the CPU, held its motion frames
  // until revision 2 was drawn (docs/view.md, "Live motion"): one save heard, nothing held now.
  EXPECT_EQ(decoded<rdtf::model_saving_t>(s.messages(), "SAVING", kArm).size(), 1u);
  const Json hold = page.state()["motion_hold"];
  EXPECT_EQ(hold["saves_heard"], 1) << hold.dump();
  EXPECT_TRUE(hold["model"].is_null()) << hold.dump();
  expect_links_where_link_state_puts_them(s, page, m, kArm);
  for (const auto& link : m["links"]) {
    if (link["name"] == "base_link") {
      EXPECT_NEAR(link["position"][1].get<double>(), 0.3, 1e-6);
    }
  }
  page.screenshot("arm3_revision_2.png");
}

TEST(View, ARejectedSaveShowsTheErrorWithTheCulpritInRedAndKeepsTheLastGoodModel) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating());
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  ASSERT_FALSE(wait_drawn(page, kArm, 1).is_null()) << page.driver_log();

  Json document = Json::parse(read(s.watch / kArm));
  for (auto& node : document["nodes"]) {
    if (node.value("name", "") == "elbow") node["extras"]["rdtf_axis"] = {0, 0, 0};
  }
  write_in_place(s.watch / kArm, document.dump(1));
  Json m;
  ASSERT_TRUE(page.wait_state([&](const Json& st) {
    m = model_in(st, kArm);
    return m["status"] == "error";
  }, 10s)) << m.dump();
  bool named = false;
  for (const auto& d : m["diagnostics"]) named = named || d["code"] == "JOINT_AXIS_ZERO";
  EXPECT_TRUE(named) << m["diagnostics"].dump();
  EXPECT_EQ(m["highlighted"]["joints"], Json::array({"elbow"}));
  EXPECT_EQ(m["highlighted"]["links"], Json::array({"forearm"}));  // the part the joint moves
  // Revision 1 stays drawn, still moving with LINK_STATE.
  EXPECT_EQ(m["revision"], 1);
  EXPECT_EQ(m["links"].size(), 3u);
  expect_links_where_link_state_puts_them(s, page, m, kArm);
  page.screenshot("arm3_rejected_save.png");
}

TEST(View, SetJointMovesTheJointInTheLiveSimulation) {
  Session s;
  const std::string hash = write_arm3_across_gravity(s.watch);
  // No gravity: nothing loads the joints, so the PD law rests exactly at its target (up to ODE's
  // joint error, far below the tolerance).
  s.start(simulating().with("gravity", Json::array({0.0, 0.0, 0.0})));
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  ASSERT_FALSE(wait_drawn(page, kArm, 1).is_null()) << page.driver_log();

  EXPECT_EQ(page.eval("window.rdtfView.setJoint('arm3.gltf', 'shoulder', 0.5)"), "");
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    const auto last = last_state(all, 1);
    return last && std::abs(*position_of(*last, "shoulder") - 0.5) < 1e-3;
  }, 20s)) << "shoulder did not reach 0.5";
  bool commanded = false;
  for (const auto& c : decoded<rdtf::joint_command_t>(s.messages(), "JOINT_COMMAND", kArm)) {
    commanded = commanded || (c.name == std::vector<std::string>{"shoulder"} && c.value[0] == 0.5 &&
                              c.mode[0] == rdtf::joint_command_t::POSITION && c.revision == 1 && c.content_hash == hash);
  }
  EXPECT_TRUE(commanded);
  EXPECT_TRUE(rejections(s.messages()).empty()) << rejections(s.messages()).front();
  // The page shows it: the joint's position and the links where LINK_STATE puts them.
  Json m;
  ASSERT_TRUE(page.wait_state([&](const Json& st) {
    m = model_in(st, kArm);
    for (const auto& j : m["joints"]) {
      if (j["name"] == "shoulder" && j["position"].is_number()) return std::abs(j["position"].get<double>() - 0.5) < 1e-3;
    }
    return false;
  })) << m.dump();
  expect_links_where_link_state_puts_them(s, page, m, kArm);
  // The commands carry the shoulder's own gains, which the page shows (docs/view.md, "Sliders").
  double kp = -1, kd = -1;
  for (const auto& j : m["joints"]) {
    if (j["name"] == "shoulder" && j["kp"].is_number()) {
      kp = j["kp"].get<double>();
      kd = j["kd"].get<double>();
    }
  }
  ASSERT_GT(kp, 0) << m.dump();
  ASSERT_GT(kd, 0) << m.dump();
  bool with_its_gains = false;
  for (const auto& c : decoded<rdtf::joint_command_t>(s.messages(), "JOINT_COMMAND", kArm)) {
    with_its_gains = with_its_gains || (c.name == std::vector<std::string>{"shoulder"} && c.kp[0] == kp && c.kd[0] == kd);
  }
  EXPECT_TRUE(with_its_gains) << "no JOINT_COMMAND with the shoulder's kp " << kp << " and kd " << kd;
  // Beyond the limit (1.57): refused with the reason, nothing sent.
  const Json refused = page.eval("window.rdtfView.setJoint('arm3.gltf', 'shoulder', 2)");
  EXPECT_NE(refused.get<std::string>().find("outside its limits"), std::string::npos) << refused;
  page.screenshot("arm3_shoulder_set_to_0.5.png");
}

// A model at rest (no gravity, started at rest) streams the very same poses: the page draws no
// frame for them, each of which would cost a software rasterizer what the next revision needs,
// and still follows the simulation's time.
TEST(View, DrawsNoFrameForStatesThatMoveNothing) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating().with("gravity", Json::array({0.0, 0.0, 0.0})));
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  const Json m = wait_drawn(page, kArm, 1);
  ASSERT_FALSE(m.is_null()) << page.state().dump() << "\n" << page.driver_log() << view.log();
  // The frames of the model's arrival (camera fitted, panel) are drawn first: 10 steps later at 50 Hz.
  auto later_than = [&](double sim_time, Json& out) {
    return page.wait_state([&](const Json& st) {
      out = st;
      const Json now = model_in(st, kArm);
      return !now.is_null() && now["sim_time"].is_number() && now["sim_time"].get<double>() > sim_time;
    }, 10s);
  };
  Json st;
  ASSERT_TRUE(later_than(m["sim_time"].get<double>() + 0.2, st)) << st.dump();
  const auto frame = st["frame"].get<std::int64_t>();
  const double from = model_in(st, kArm)["sim_time"].get<double>();
  ASSERT_TRUE(later_than(from + 0.5, st)) << st.dump();  // 25 more states at 50 Hz
  EXPECT_EQ(st["frame"].get<std::int64_t>(), frame) << "frames drawn for " << (model_in(st, kArm)["sim_time"].get<double>() - from)
                                                    << " s of states that moved nothing";
  expect_links_where_link_state_puts_them(s, page, model_in(st, kArm), kArm);
}

TEST(View, ShowsTwoModelsAndOneRemoved) {
  Session s;
  copy_fixture(s.watch, "arm3");
  copy_fixture(s.watch, "two_cylinder");
  s.start(simulating());
  std::optional<ViewProcess> view(std::in_place, s.root.path());
  Page page(view->url(), s.root / "page.log");
  ASSERT_FALSE(wait_drawn(page, kArm, 1).is_null()) << page.driver_log();
  const Json cylinder = wait_drawn(page, "two_cylinder.gltf", 1);
  ASSERT_FALSE(cylinder.is_null()) << page.state().dump();
  expect_links_where_link_state_puts_them(s, page, cylinder, "two_cylinder.gltf");
  page.eval("window.rdtfView.select('two_cylinder.gltf')");
  page.screenshot("two_models_cylinder_selected.png");

  fs::remove(s.watch / "two_cylinder.gltf");
  Json st;
  ASSERT_TRUE(page.wait_state([&](const Json& state) {
    return model_in(state, "two_cylinder.gltf")["status"] == "removed";
  }, 10s, &st)) << st.dump();
  const Json removed = model_in(st, "two_cylinder.gltf");
  EXPECT_TRUE(removed["links"].empty());
  EXPECT_TRUE(removed["revision"].is_null());
  EXPECT_EQ(model_in(st, kArm)["status"], "live");
  page.screenshot("two_models_cylinder_removed.png");

  // The page outlives a restart of rdtf-view on the same port: it reconnects, and keeps only what
  // the new rdtf-view knows (before, a model the new one never heard of stayed listed for ever).
  const std::string url = view->url();
  const std::string port = url.substr(url.rfind(':') + 1, url.find('/', url.rfind(':')) - url.rfind(':') - 1);
  view.reset();
  fs::create_directories(s.root / "second");
  view.emplace(s.root / "second", std::vector<std::string>{"--port", port});
  ASSERT_TRUE(page.wait_state([&](const Json& state) {
    return model_in(state, "two_cylinder.gltf").is_null() && model_in(state, kArm)["status"] == "live";
  }, 20s, &st)) << st.dump();
  EXPECT_EQ(st["selected"], kArm);
}

// The encodings Blender and glTF tools write besides arm3's one buffer: a base colour texture (a
// PNG beside the model, served as its own blob) and a model whose accessors read from two
// buffers. Both are drawn with every link where LINK_STATE puts it, the texture with its image.
TEST(View, DrawsATexturedModelAndOneWithTwoBuffers) {
  Session s;
  copy_fixture(s.watch, "arm3", "textured");
  copy_fixture(s.watch, "arm3", "two_buffers");
  // A 2x2 RGBA checker.
  const std::string png(
      "\x89\x50\x4e\x47\x0d\x0a\x1a\x0a\x00\x00\x00\x0d\x49\x48\x44\x52\x00\x00\x00\x02\x00\x00\x00\x02\x08\x06"
      "\x00\x00\x00\x72\xb6\x0d\x24\x00\x00\x00\x12\x49\x44\x41\x54\x78\x9c\x63\xf8\xcf\xc0\xf0\x1f\x04\xa0\x24"
      "\xc3\x7f\x00\x6b\xa6\x0b\xf5\xc4\xb7\x3b\xa8\x00\x00\x00\x00\x49\x45\x4e\x44\xae\x42\x60\x82",
      75);
  write_in_place(s.watch / "checker.png", png);
  Json textured = Json::parse(read(s.watch / "textured.gltf"));
  textured["images"] = Json::array({Json{{"uri", "checker.png"}}});
  textured["textures"] = Json::array({Json{{"source", 0}}});
  textured["materials"] = Json::array({Json{{"name", "checker"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}}}}});
  for (auto& mesh : textured["meshes"]) {
    for (auto& primitive : mesh["primitives"]) primitive["material"] = 0;
  }
  // A joint named as modellers name them: rdtfd's URDF name for it (states, commands) differs.
  for (auto& node : textured["nodes"]) {
    if (node.value("name", "") == "elbow") node["name"] = "elbow joint";
  }
  write_in_place(s.watch / "textured.gltf", textured.dump());
  // Two buffers: the second holds arm3's bytes after 16 of its own, and every other buffer view
  // reads from it (at offsets 16 further on), so a view read from the wrong buffer is garbage.
  const std::string bin = read(s.watch / "arm3.bin");  // copy_fixture keeps the .bin's name
  // Named like a page, as anyone who can write into the folder may name a file.
  write_in_place(s.watch / "second.html", std::string(16, '\xee') + bin);
  Json two = Json::parse(read(s.watch / "two_buffers.gltf"));
  two["buffers"].push_back(Json{{"uri", "second.html"}, {"byteLength", bin.size() + 16}});
  for (std::size_t i = 1; i < two["bufferViews"].size(); i += 2) {
    two["bufferViews"][i]["buffer"] = 1;
    two["bufferViews"][i]["byteOffset"] = two["bufferViews"][i].value("byteOffset", 0) + 16;
  }
  write_in_place(s.watch / "two_buffers.gltf", two.dump());
  // A box under a plain mount empty that carries its own joint keys is its own pivot: the page
  // draws its node where LINK_STATE puts its frame (it put the frame at the mount, 0.1 m off).
  write_in_place(s.watch / "mount_empty.gltf", read(testing::data_dir() / "frames" / "mount_empty.gltf"));
  s.start(simulating());
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  std::map<std::string, Json> drawn;
  for (const char* name : {"textured.gltf", "two_buffers.gltf"}) {
    const std::string id = name;
    const Json m = wait_drawn(page, id, 1);
    ASSERT_FALSE(m.is_null()) << id << ": " << page.state().dump() << page.driver_log();
    EXPECT_EQ(m["links"].size(), 3u) << id;
    EXPECT_EQ(m["textures"], id == "textured.gltf" ? 1 : 0) << id;
    expect_links_where_link_state_puts_them(s, page, m, id);
    drawn[id] = m;
  }
  // rdtfd kept the two buffers, and the page drew from each what arm3 draws from its one.
  const Json written = Json::parse(read(s.output / "two_buffers.gltf" / "two_buffers.rdtf.gltf"));
  EXPECT_EQ(written["buffers"].size(), 2u) << written["buffers"].dump();
  // That buffer is served as bytes in a sandbox, never as a document of the viewer's origin (whose
  // script could open the viewer's WebSocket and command joints).
  const Json served = page.eval("fetch('/model/two_buffers.gltf/1/' + encodeURIComponent(" +
                                written["buffers"][1]["uri"].dump() +
                                ")).then((r) => [r.status, r.headers.get('content-type'), "
                                "r.headers.get('content-security-policy')])");
  EXPECT_EQ(served, Json::array({200, "application/octet-stream", "sandbox; default-src 'none'"})) << written["buffers"];
  for (const auto& link : drawn["textured.gltf"]["links"]) {
    const auto other = std::find_if(drawn["two_buffers.gltf"]["links"].begin(), drawn["two_buffers.gltf"]["links"].end(),
                                    [&](const Json& l) { return l["name"] == link["name"]; });
    ASSERT_NE(other, drawn["two_buffers.gltf"]["links"].end()) << link["name"];
    ASSERT_TRUE(link["bounds"].is_array()) << link.dump();
    ASSERT_TRUE((*other)["bounds"].is_array()) << other->dump();
    for (int corner = 0; corner < 2; ++corner) {
      for (int k = 0; k < 3; ++k) {
        EXPECT_NEAR((*other)["bounds"][corner][k].get<double>(), link["bounds"][corner][k].get<double>(), 1e-9)
            << link["name"] << " corner " << corner;
      }
    }
  }
  const Json mount = wait_drawn(page, "mount_empty.gltf", 1);
  ASSERT_FALSE(mount.is_null()) << page.state().dump();
  expect_links_where_link_state_puts_them(s, page, mount, "mount_empty.gltf");
  for (const auto& link : mount["links"]) {
    if (link["name"] != "arm") continue;
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(link["node_position"][k].get<double>(), link["position"][k].get<double>(), 1e-9) << link.dump();
    }
  }
  page.eval("window.rdtfView.select('textured.gltf')");
  // Each slider says both names where they differ (the hover and the diagnostics say the glTF one).
  Json labels;
  ASSERT_TRUE(page.wait_state([&](const Json& st) {
    labels = st["sliders"];
    return labels.size() == 2;
  })) << labels.dump();
  std::vector<std::string> named;  // Each label up to its readout.
  for (const auto& label : labels) named.push_back(label.get<std::string>().substr(0, label.get<std::string>().find(": ")));
  std::sort(named.begin(), named.end());
  EXPECT_EQ(named, (std::vector<std::string>{"elbow joint (URDF elbow_joint)", "shoulder"})) << labels.dump();
  page.screenshot("arm3_textured.png");
}

// Hostile pages: every message refused with a reason, none reaches the bus; a message over
// 4 KiB is refused with its size and one over 1 MiB closes that socket; a flood is answered 20 times a second and counted; clients that
// vanish mid-request or mid-frame, or come from another origin, leave the viewer serving.
TEST(View, RefusesHostileMessagesAndSurvivesClientsThatVanish) {
  Session s;
  copy_fixture(s.watch, "arm3");
  s.start(simulating());
  ViewProcess view(s.root.path());
  Page page(view.url(), s.root / "page.log");
  ASSERT_FALSE(wait_drawn(page, kArm, 1).is_null()) << page.driver_log();
  // A folder is no file (it opens, and read as one it was an empty 200).
  EXPECT_EQ(page.eval("Promise.all(['/app/node_modules', '/three/examples', '/app/'].map((u) => "
                      "fetch(u).then((r) => r.status)))"),
            Json::array({404, 404, 404}));

  // Page-side waits stretch like the test's own deadlines (RDTF_TEST_DEADLINE_SCALE: slower under a
  // sanitizer); each loop ends as soon as what it waits for has come.
  const auto with_scale = [](const std::string& js) {
    return "((scale) => " + js + ")(" + std::to_string(deadline_scale()) + ")";
  };
  const Json reasons = page.eval(with_scale(R"((async () => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    await new Promise((r) => { ws.onopen = r; });
    const answers = [];
    ws.onmessage = (e) => { const m = JSON.parse(e.data); if (m.type === 'refused') answers.push(m.reason); };
    const sent = ['not json', '[1, 2]', '{"type": 7}',
      '{"type":"set_joint","model":"nope.gltf","joint":"shoulder","value":0.1}',
      JSON.stringify({type: 'set_joint', model: 'arm3.gltf', joint: 'shoulder', value: NaN}),
      '{"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":1e999}',
      '{"type":"set_joint","model":"arm3.gltf","joint":"wrist","value":0.1}',
      '{"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":[0.1]}',
      JSON.stringify({type: 'set_joint', model: 'arm3.gltf', joint: 'shoulder', value: 0.1, more: new Array(3000).fill(1)}),
      '{"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":0.1,"kp":1e9}',
      '{"type":"set_joint","model":"arm3.gltf","joint":"shoulder","value":9}',
      '{"type":"launch"}'];
    for (const t of sent) ws.send(t);
    for (const end = performance.now() + 5000 * scale; performance.now() < end && answers.length < sent.length;) await new Promise((r) => setTimeout(r, 10));
    ws.close();
    return answers;
  })())"));
  const std::vector<std::string> expected = {
      "not JSON", "not a JSON object", "no \"type\" string", "unknown model 'nope.gltf'", "\"value\" must be a number, not null",
      "not JSON", "has no movable joint 'wrist'", "\"value\" must be a number, not array",
      "more than 4096", "unknown key 'kp'", "outside its limits", "unknown type 'launch'"};
  ASSERT_EQ(reasons.size(), expected.size()) << reasons.dump();
  for (std::size_t i = 0; i < expected.size(); ++i) {
    EXPECT_NE(reasons[i].get<std::string>().find(expected[i]), std::string::npos) << reasons[i] << " vs " << expected[i];
  }

  // A huge array: 100 KB refused with its size; 2 MB (over 1 MiB) closes that socket: 1009, or
  // 1006 when the reset of the unread rest reaches the browser before the close frame.
  const Json huge = page.eval(R"((async () => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    await new Promise((r) => { ws.onopen = r; });
    const refused = new Promise((r) => { ws.onmessage = (e) => { const m = JSON.parse(e.data); if (m.type === 'refused') r(m.reason); }; });
    ws.send('[' + '1,'.repeat(50000) + '1]');
    const reason = await refused;
    const code = new Promise((r) => { ws.onclose = (e) => r(e.code); });
    ws.send('[' + '1,'.repeat(1000000) + '1]');
    return {reason, code: await code};
  })())");
  EXPECT_EQ(huge["reason"], "message of 100003 bytes, more than 4096");
  EXPECT_TRUE(huge["code"] == 1009 || huge["code"] == 1006) << huge;

  // A flood of 1000: each refused (unknown model, then too many messages); 20 answers a second,
  // the unanswered ones counted in the next answer.
  const Json flood = page.eval(with_scale(R"((async () => {
    const ws = new WebSocket(`ws://${location.host}/ws`);
    await new Promise((r) => { ws.onopen = r; });
    const answers = [];
    ws.onmessage = (e) => { const m = JSON.parse(e.data); if (m.type === 'refused') answers.push(m); };
    const bad = '{"type":"set_joint","model":"flood.gltf","joint":"shoulder","value":0.1}';
    const start = performance.now();
    for (let i = 0; i < 1000; ++i) ws.send(bad);
    let sent = 1000;
    const unanswered = () => answers.reduce((n, m) => n + m.unanswered_before, 0);
    await new Promise((r) => setTimeout(r, 1500));
    // The server works through the flood at its own pace (slower under a sanitizer, on a loaded
    // machine): probe every 100 ms until an answer accounts for every message sent before it.
    for (const end = performance.now() + 30000 * scale; performance.now() < end && answers.length + unanswered() < sent;) {
      ws.send(bad);
      ++sent;
      await new Promise((r) => setTimeout(r, 100));
    }
    ws.close();
    return {sent, seconds: (performance.now() - start) / 1000, answered: answers.length, unanswered: unanswered(),
            too_many: answers.filter((m) => m.reason.startsWith('too many')).length};
  })())"));
  // (No probe is needed when an answer within the first 1.5 s already accounts for the whole
  // flood: the CI saw 31 answers and 969 counted unanswered of 1000 so. It asked for one before.)
  EXPECT_GE(flood["sent"].get<int>(), 1000) << flood.dump();
  EXPECT_EQ(flood["answered"].get<int>() + flood["unanswered"].get<int>(), flood["sent"].get<int>()) << flood.dump();
  // At most 20 answers in each second of the server's clock the flood spanned.
  EXPECT_LE(flood["answered"].get<int>(), 20 * (static_cast<int>(flood["seconds"].get<double>()) + 2)) << flood.dump();

  // Clients that vanish: half a request line, an upgrade then half a frame, another origin.
  const int port = std::stoi(view.url().substr(view.url().rfind(':') + 1));
  const auto connect_local = [&] {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(static_cast<std::uint16_t>(port));
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0) throw std::runtime_error("connect");
    return fd;
  };
  const auto send_text = [](int fd, const std::string& text) { return ::send(fd, text.data(), text.size(), MSG_NOSIGNAL); };
  const auto receive = [](int fd) {
    std::string in;
    char buffer[4096];
    pollfd p{fd, POLLIN, 0};
    while (in.find("\r\n\r\n") == std::string::npos && ::poll(&p, 1, 5000 * deadline_scale()) > 0) {
      const ssize_t n = ::recv(fd, buffer, sizeof buffer, 0);
      if (n <= 0) break;
      in.append(buffer, static_cast<std::size_t>(n));
    }
    return in;
  };
  const std::string host = "127.0.0.1:" + std::to_string(port);
  const std::string upgrade = "GET /ws HTTP/1.1\r\nHost: " + host +
                              "\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
                              "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n";
  {
    const int fd = connect_local();
    send_text(fd, "GET /app/app.js HTTP/1.1\r\nHost: 127.");
    ::close(fd);
  }
  {
    const int fd = connect_local();
    send_text(fd, upgrade + "Origin: http://" + host + "\r\n\r\n");
    EXPECT_NE(receive(fd).find("101 Switching Protocols"), std::string::npos);
    // A masked text frame announcing 1000 bytes, of which 10 come.
    const std::string frame = std::string("\x81\xfe\x03\xe8" "abcd", 8) + "0123456789";
    send_text(fd, frame);
    ::close(fd);
  }
  {
    const int fd = connect_local();
    send_text(fd, upgrade + "Origin: http://evil.example\r\n\r\n");
    EXPECT_NE(receive(fd).find("403 Forbidden"), std::string::npos);
    ::close(fd);
  }
  EXPECT_FALSE(view.process().wait_exit(0s)) << view.log();
  // Still serving: the page loads again and draws the model.
  page.request({{"open", view.url()}});
  ASSERT_FALSE(wait_drawn(page, kArm, 1).is_null()) << view.log();
  // None of it reached the bus.
  EXPECT_TRUE(on_kind(s.messages(), "JOINT_COMMAND").empty());
}

}  // namespace
}  // namespace rdtf::itest
