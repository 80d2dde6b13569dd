// One read path: the files a model names are read once (read_source_files) and the loader
// converts those bytes, reading nothing from disk itself; refusals are the loader's, word for word.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <map>

#include "rdtf/diagnostic_codes.h"
#include "rdtf/gltf.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

namespace fs = std::filesystem;

std::vector<std::uint8_t> bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

std::string arm3_bin() { return testing::read_file(testing::data_dir() / "blender" / "arm3.bin"); }

// arm3.gltf as model.gltf in `folder` (after `edit`), beside a copy of arm3.bin.
fs::path write_arm3(const fs::path& folder, const std::function<void(Json&)>& edit = {}) {
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  if (edit) edit(document);
  testing::write_file(folder / "arm3.bin", arm3_bin());
  testing::write_file(folder / "model.gltf", document.dump());
  return folder / "model.gltf";
}

// A reader that counts the reads of each file and reads it as a plain file (the files here are).
struct CountingReader {
  std::map<fs::path, int> reads;
  ConfinedReader reader() {
    return [this](const fs::path&, const fs::path& path, std::uint64_t max_bytes, SourceFile& file) {
      ++reads[path];
      if (!fs::exists(path)) {
        file.why = "missing";
        return;
      }
      const std::string text = testing::read_file(path);
      if (text.size() <= max_bytes) file.bytes = bytes_of(text);
      file.size = text.size();
    };
  }
};

// Only the error diagnostics, as "CODE pointer: message".
std::vector<std::string> errors(const Diagnostics& diag) {
  std::vector<std::string> out;
  for (const Diagnostic& d : diag.all()) {
    if (d.severity == Severity::kError) out.push_back(d.code + " " + d.pointer + ": " + d.message);
  }
  return out;
}

TEST(SourceFiles, EachFileIsReadOnceAndTheLoaderConvertsThoseBytesNotTheFileOnDisk) {
  testing::TempDir folder;
  const fs::path model = write_arm3(folder.path(), [](Json& d) {
    // A second buffer naming the same file, and an image: three names, two files.
    d["buffers"].push_back(d["buffers"][0]);
    d["images"] = Json::array({Json{{"uri", "tex.png"}}});
  });
  testing::write_file(folder / "tex.png", "not really a PNG");
  const std::string bin = arm3_bin();
  const auto model_bytes = bytes_of(testing::read_file(model));
  const fs::path dir = fs::canonical(folder.path());
  const auto named = referenced_files(model_bytes, dir);
  ASSERT_EQ(named, (std::vector<fs::path>{dir / "arm3.bin", dir / "arm3.bin", dir / "tex.png"}));

  CountingReader counter;
  SourceFiles files = read_source_files(named, dir, LoadLimits{}, counter.reader());
  EXPECT_EQ(counter.reads, (std::map<fs::path, int>{{dir / "arm3.bin", 1}, {dir / "tex.png", 1}}));

  // Rewritten after the read (as an editor saving again would): the load must not see it.
  std::string rewritten = bin;
  std::reverse(rewritten.begin(), rewritten.end());
  testing::write_file(folder / "arm3.bin", rewritten);
  fs::remove(folder / "tex.png");

  Diagnostics diag;
  const auto asset = load_gltf_from_memory(model_bytes, model, dir, LoadLimits{}, std::move(files), diag);
  ASSERT_TRUE(asset) << ::testing::PrintToString(errors(diag));
  ASSERT_EQ(asset->buffers.size(), 2u);
  EXPECT_EQ(asset->buffers[0], bytes_of(bin));
  EXPECT_EQ(asset->buffers[1], bytes_of(bin));
  EXPECT_EQ(asset->images.at(dir / "tex.png"), bytes_of("not really a PNG"));
  EXPECT_EQ(counter.reads, (std::map<fs::path, int>{{dir / "arm3.bin", 1}, {dir / "tex.png", 1}}));
}

TEST(SourceFiles, AFileThatCouldNotBeReadIsTheLoadersIoError) {
  testing::TempDir folder;
  const fs::path model = write_arm3(folder.path());
  const fs::path dir = fs::canonical(folder.path());
  const auto model_bytes = bytes_of(testing::read_file(model));
  CountingReader counter;
  fs::remove(folder / "arm3.bin");
  Diagnostics diag;
  EXPECT_FALSE(load_gltf_from_memory(model_bytes, model, dir, LoadLimits{},
                                     read_source_files(referenced_files(model_bytes, dir), dir, LoadLimits{},
                                                       counter.reader()),
                                     diag));
  EXPECT_EQ(errors(diag), std::vector<std::string>{std::string(codes::IO_ERROR) + " /buffers/0/uri: 'arm3.bin' (" +
                                                   (dir / "arm3.bin").string() + ") missing"});
}

// A .bin longer than its buffer's byteLength holds the buffer in its first bytes, as the Khronos
// validator reads it (and as a GLB's longer BIN chunk is read); a shorter one cannot hold it. Two
// buffers naming the same file with other lengths each get theirs.
TEST(SourceFiles, AFileLongerThanItsBufferHoldsItAndAShorterOneIsRefused) {
  testing::TempDir folder;
  const std::string bin = arm3_bin();
  const fs::path model = write_arm3(folder.path(), [&](Json& d) {
    d["buffers"].push_back(Json{{"uri", "arm3.bin"}, {"byteLength", 8}});
  });
  testing::write_file(folder / "arm3.bin", bin + "tail");
  Diagnostics diag;
  const auto asset = load_gltf(model, LoadLimits{}, diag);
  ASSERT_TRUE(asset) << ::testing::PrintToString(errors(diag));
  EXPECT_TRUE(diag.all().empty()) << format(diag.all().front());
  ASSERT_EQ(asset->buffers.size(), 2u);
  EXPECT_EQ(asset->buffers[0], bytes_of(bin));
  EXPECT_EQ(asset->buffers[1], bytes_of(bin.substr(0, 8)));

  testing::write_file(folder / "arm3.bin", bin.substr(0, bin.size() - 4));
  Diagnostics short_diag;
  EXPECT_FALSE(load_gltf(model, LoadLimits{}, short_diag));
  EXPECT_EQ(errors(short_diag),
            std::vector<std::string>{std::string(codes::BUFFER_EXTERNAL_BYTELENGTH_MISMATCH) +
                                     " /buffers/0/byteLength: 'arm3.bin' has " + std::to_string(bin.size() - 4) +
                                     " bytes but byteLength is " + std::to_string(bin.size()) +
                                     ": the file is shorter than the buffer it holds"});
}

// The refusals of the confined read, as load_gltf (the CLI's path) reports them.
TEST(SourceFiles, ConfinementRefusalsNameTheUriThePathAndWhy) {
  testing::TempDir root;
  const fs::path outside = fs::canonical(root.path());
  fs::create_directories(root / "model");
  const fs::path dir = fs::canonical(root / "model");
  const std::string bin = arm3_bin();

  // A symbolic link out of the folder.
  write_arm3(dir);
  fs::remove(dir / "arm3.bin");
  testing::write_file(outside / "outside.bin", bin);
  fs::create_symlink(outside / "outside.bin", dir / "arm3.bin");
  Diagnostics symlink_diag;
  EXPECT_FALSE(load_gltf(dir / "model.gltf", LoadLimits{}, symlink_diag));
  EXPECT_EQ(errors(symlink_diag),
            std::vector<std::string>{std::string(codes::IO_ERROR) + " /buffers/0/uri: 'arm3.bin' (" +
                                     (dir / "arm3.bin").string() + ") leads outside the model's folder " +
                                     dir.string() + " through a symbolic link"});

  // A second hard link.
  fs::remove(dir / "arm3.bin");
  testing::write_file(dir / "arm3.bin", bin);
  fs::create_hard_link(dir / "arm3.bin", outside / "another name.bin");
  Diagnostics link_diag;
  EXPECT_FALSE(load_gltf(dir / "model.gltf", LoadLimits{}, link_diag));
  EXPECT_EQ(errors(link_diag),
            std::vector<std::string>{std::string(codes::IO_ERROR) + " /buffers/0/uri: 'arm3.bin' (" +
                                     (dir / "arm3.bin").string() +
                                     ") has 2 hard links: a file with several names may be a file from outside "
                                     "the model's folder, so it is refused (copy it instead)"});

  // Over the size limit: sized, not read.
  fs::remove(outside / "another name.bin");
  LoadLimits small;
  small.max_file_bytes = bin.size() - 1;
  ASSERT_LT(fs::file_size(dir / "model.gltf"), small.max_file_bytes);
  Diagnostics size_diag;
  EXPECT_FALSE(load_gltf(dir / "model.gltf", small, size_diag));
  EXPECT_EQ(errors(size_diag),
            std::vector<std::string>{std::string(codes::LIMIT_EXCEEDED) + " /buffers/0/uri: 'arm3.bin' is " +
                                     std::to_string(bin.size()) + " bytes, over the limit of " +
                                     std::to_string(small.max_file_bytes)});
  const auto sized = read_source_files({dir / "arm3.bin"}, dir, small);
  EXPECT_EQ(sized.at(dir / "arm3.bin").size, bin.size());
  EXPECT_TRUE(sized.at(dir / "arm3.bin").bytes.empty());
}

}  // namespace
}  // namespace rdtf
