// Model ids (daemon/registry.h): the model's path below its watched folder, usable inside an LCM
// channel name of at most 63 characters; and the registry of known models.
#include "registry.h"

#include <gtest/gtest.h>

#include <regex>
#include <set>

namespace rdtf::daemon {
namespace {

// What daemon.cc allows for an id: "<prefix>/<id>/DESCRIPTION_CHUNK" in 63 characters.
std::size_t max_id_for(const std::string& prefix) {
  return 63 - prefix.size() - 1 - std::string("/DESCRIPTION_CHUNK").size();
}

const std::vector<std::filesystem::path> kOneRoot = {"/w/models"};

TEST(Registry, TopLevelModelIdIsItsFileName) {
  EXPECT_EQ(model_id_for("/w/models/arm3.gltf", kOneRoot, 40), "arm3.gltf");
  EXPECT_EQ(model_id_for("/w/models/robot.glb", kOneRoot, 40), "robot.glb");
}

TEST(Registry, NestedModelIdIsItsPathBelowTheRoot) {
  EXPECT_EQ(model_id_for("/w/models/sub/robot.gltf", kOneRoot, 40), "sub/robot.gltf");
  EXPECT_EQ(model_id_for("/w/models/a/b/c/d.glb", kOneRoot, 40), "a/b/c/d.glb");
}

TEST(Registry, SeveralRootsPrefixTheRootName) {
  const std::vector<std::filesystem::path> roots = {"/w/models", "/data/other"};
  EXPECT_EQ(model_id_for("/w/models/arm3.gltf", roots, 40), "models/arm3.gltf");
  EXPECT_EQ(model_id_for("/data/other/sub/x.glb", roots, 40), "other/sub/x.glb");
}

TEST(Registry, RootsSharingANameStillGiveDistinctIds) {
  // Two watched folders both called "models" (e.g. ~/models and /srv/models), each with an
  // arm.gltf: two models, so two ids; otherwise both publish on RDTF/models/arm.gltf/... and a
  // request by id reaches only one of them.
  const std::vector<std::filesystem::path> roots = {"/home/u/models", "/srv/models"};
  const auto a = model_id_for("/home/u/models/arm.gltf", roots, 40);
  const auto b = model_id_for("/srv/models/arm.gltf", roots, 40);
  EXPECT_NE(a, b) << "both models get the id " << a;
}

TEST(Registry, FileOutsideEveryRootUsesItsName) {
  EXPECT_EQ(model_id_for("/elsewhere/x.gltf", kOneRoot, 40), "x.gltf");
  // A sibling folder whose name starts like the root is not below it.
  EXPECT_EQ(model_id_for("/w/models2/y.gltf", kOneRoot, 40), "y.gltf");
}

TEST(Registry, CharactersOutsideTheChannelSetBecomeUnderscores) {
  EXPECT_EQ(model_id_for("/w/models/my robot (v2).gltf", kOneRoot, 40), "my_robot__v2_.gltf");
  EXPECT_EQ(model_id_for("/w/models/a+b=c,d;e.glb", kOneRoot, 40), "a_b_c_d_e.glb");
  EXPECT_EQ(model_id_for("/w/models/Sub-Dir_1/x.y.gltf", kOneRoot, 40), "Sub-Dir_1/x.y.gltf");
  // UTF-8: every byte outside the set becomes one '_'.
  EXPECT_EQ(model_id_for("/w/models/\xc3\xa4rm.gltf", kOneRoot, 40), "__rm.gltf");
  const std::regex allowed("[A-Za-z0-9._/-]+");
  for (const char* name : {"a b.gltf", "tab\there.gltf", "quote\"s.gltf", "star*.gltf", "q?.glb",
                           "back\\slash.gltf", "hash#.gltf", "dollar$.gltf"}) {
    const auto id = model_id_for(std::filesystem::path("/w/models") / name, kOneRoot, 40);
    EXPECT_TRUE(std::regex_match(id, allowed)) << name << " -> " << id;
  }
}

TEST(Registry, IdsThatFitAreNotShortened) {
  const std::string name = std::string(36, 'a') + ".glb";  // 40 characters: exactly the limit.
  EXPECT_EQ(model_id_for("/w/models/" + name, kOneRoot, 40), name);
}

TEST(Registry, LongIdsAreShortenedWithinTheChannelLimit) {
  for (const std::string prefix : {"RDTF", "P", "sixteen_chars_px"}) {
    const std::size_t max = max_id_for(prefix);
    std::set<std::string> ids;
    for (const char* top : {"first", "second", "third"}) {
      const std::filesystem::path source = std::filesystem::path("/w/models") / top /
                                           "a_rather_long_folder_name_for_a_project" /
                                           "another_level_of_nesting" / "robot_model_final.gltf";
      const std::string id = model_id_for(source, kOneRoot, max);
      const std::string channel = prefix + "/" + id + "/DESCRIPTION_CHUNK";
      EXPECT_LE(id.size(), max) << id;
      EXPECT_LE(channel.size(), 63u) << channel;
      // The end (the file name) is kept, so people still recognise the model.
      const std::string tail = "model_final.gltf";
      EXPECT_EQ(id.substr(id.size() - tail.size()), tail) << id;
      // Stable: the same file gets the same id every time (subscribers keep their regexes).
      EXPECT_EQ(model_id_for(source, kOneRoot, max), id);
      ids.insert(id);
    }
    // Paths that differ only in their start still give distinct ids.
    EXPECT_EQ(ids.size(), 3u) << prefix;
  }
}

TEST(Registry, IsModelFile) {
  for (const char* yes : {"a.gltf", "a.glb", "A.GLTF", "b.Glb", "x.rdtf.gltf", "/w/sub/y.gltf"}) {
    EXPECT_TRUE(is_model_file(yes)) << yes;
  }
  for (const char* no : {"a.bin", "a.png", "a.gltf.tmp", "gltf", "a.gltf~", "a.gltfx", "dir/"}) {
    EXPECT_FALSE(is_model_file(no)) << no;
  }
}

TEST(Registry, EnsureFindAndErase) {
  Registry registry;
  EXPECT_EQ(registry.find("/w/a.gltf"), nullptr);
  ModelRecord& a = registry.ensure("/w/a.gltf", "a.gltf");
  EXPECT_EQ(a.id, "a.gltf");
  EXPECT_EQ(a.source, std::filesystem::path("/w/a.gltf"));
  EXPECT_EQ(a.revisions, 0);
  EXPECT_FALSE(a.live.has_value());
  a.revisions = 3;
  // Ensuring again keeps the record (and its first id).
  ModelRecord& again = registry.ensure("/w/a.gltf", "other-id");
  EXPECT_EQ(&again, &a);
  EXPECT_EQ(again.id, "a.gltf");
  EXPECT_EQ(again.revisions, 3);
  registry.ensure("/w/sub/b.gltf", "sub/b.gltf");
  ASSERT_NE(registry.find_id("sub/b.gltf"), nullptr);
  EXPECT_EQ(registry.find_id("sub/b.gltf")->source, std::filesystem::path("/w/sub/b.gltf"));
  EXPECT_EQ(registry.find_id("nope"), nullptr);
  EXPECT_EQ(registry.all().size(), 2u);
  registry.erase("/w/a.gltf");
  EXPECT_EQ(registry.find("/w/a.gltf"), nullptr);
  EXPECT_EQ(registry.find_id("a.gltf"), nullptr);
  EXPECT_EQ(registry.all().size(), 1u);
}

TEST(Registry, DependentsAreTheModelsReferringToAFile) {
  Registry registry;
  registry.ensure("/w/a.gltf", "a.gltf").dependencies = {"/w/shared.bin", "/w/a.png"};
  registry.ensure("/w/b.gltf", "b.gltf").dependencies = {"/w/shared.bin"};
  registry.ensure("/w/c.glb", "c.glb");
  auto shared = registry.dependents("/w/shared.bin");
  std::sort(shared.begin(), shared.end());
  EXPECT_EQ(shared, (std::vector<std::filesystem::path>{"/w/a.gltf", "/w/b.gltf"}));
  EXPECT_EQ(registry.dependents("/w/a.png"), std::vector<std::filesystem::path>{"/w/a.gltf"});
  EXPECT_TRUE(registry.dependents("/w/other.bin").empty());
}

}  // namespace
}  // namespace rdtf::daemon
