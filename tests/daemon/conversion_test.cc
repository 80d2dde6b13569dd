// One read path in the daemon's conversion: each file a model names is read once, the content
// hash is of those bytes, and the outputs are made from the same bytes, even when the file on
// disk is rewritten right after it was read.
#include "conversion.h"

#include <gtest/gtest.h>

#include <openssl/evp.h>

#include <algorithm>
#include <map>

#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;

// SHA-256 over each part's 64-bit length and bytes (docs/daemon.md: the content hash), in hex.
std::string length_prefixed_sha256(const std::vector<std::string>& parts) {
  EVP_MD_CTX* context = EVP_MD_CTX_new();
  EVP_DigestInit_ex(context, EVP_sha256(), nullptr);
  for (const auto& part : parts) {
    const std::uint64_t size = part.size();
    EVP_DigestUpdate(context, &size, sizeof(size));
    EVP_DigestUpdate(context, part.data(), part.size());
  }
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestFinal_ex(context, digest, &length);
  EVP_MD_CTX_free(context);
  std::string hex;
  static const char* const kHex = "0123456789abcdef";
  for (unsigned int i = 0; i < length; ++i) {
    hex += kHex[digest[i] >> 4];
    hex += kHex[digest[i] & 15];
  }
  return hex;
}

std::string messages(const Diagnostics& diag) {
  std::string text;
  for (const Diagnostic& d : diag.all()) text += format(d) + "\n";
  return text;
}

struct Folders {
  testing::TempDir root;
  testing::TempDir out;
  fs::path watch() const { return fs::canonical(root.path()); }
};

ConversionJob job_for(const Folders& folders, const std::string& name) {
  ConversionJob job;
  job.model_id = name;
  job.root = folders.watch();
  job.source = folders.watch() / name;
  job.output_dir = folders.out.path();
  return job;
}

TEST(ConversionReads, EachFileOnceAndTheHashIsOfTheBytesConvertedEvenWhenRewrittenMeanwhile) {
  Folders folders;
  const std::string model = testing::read_file(testing::data_dir() / "blender" / "arm3.gltf");
  const std::string bin = testing::read_file(testing::data_dir() / "blender" / "arm3.bin");
  testing::write_file(folders.root / "arm.gltf", model);
  testing::write_file(folders.root / "arm3.bin", bin);
  std::string rewritten = bin;
  std::reverse(rewritten.begin(), rewritten.end());

  // Reads the file, then rewrites it at once: any second read of it would see other bytes.
  std::map<fs::path, int> reads;
  ConversionJob job = job_for(folders, "arm.gltf");
  job.read_file = [&](const fs::path&, const fs::path& path, std::uint64_t, std::vector<std::uint8_t>& out,
                      std::string&) -> std::optional<std::uint64_t> {
    ++reads[path];
    const std::string bytes = testing::read_file(path);
    out.assign(bytes.begin(), bytes.end());
    testing::write_file(path, rewritten);
    return bytes.size();
  };
  const ConversionOutcome outcome = run_conversion(job);
  ASSERT_EQ(outcome.kind, ConversionOutcome::Kind::kConverted) << messages(outcome.diagnostics);
  EXPECT_EQ(reads, (std::map<fs::path, int>{{folders.watch() / "arm3.bin", 1}}));
  EXPECT_EQ(outcome.content_hash, length_prefixed_sha256({model, bin}));
  EXPECT_EQ(testing::read_file(folders.root / "arm3.bin"), rewritten);

  // The buffer written beside the output is the one that was hashed, not the file as it is now.
  ASSERT_TRUE(outcome.converted);
  const Json written = Json::parse(outcome.converted->rdtf_json);
  const std::string uri = written["buffers"][0]["uri"].get<std::string>();
  EXPECT_EQ(testing::read_file(folders.out / uri), bin);

  // The next conversion sees the rewritten file: a new hash, of the new bytes.
  job.previous_hash = outcome.content_hash;
  const ConversionOutcome next = run_conversion(job);
  EXPECT_EQ(next.content_hash, length_prefixed_sha256({model, rewritten}));
  EXPECT_EQ(reads.at(folders.watch() / "arm3.bin"), 2);
}

TEST(ConversionReads, AFileNamedTwiceIsReadOnceAndHashedAsOftenAsNamed) {
  Folders folders;
  Json document = Json::parse(testing::read_file(testing::data_dir() / "blender" / "arm3.gltf"));
  document["buffers"].push_back(document["buffers"][0]);
  const std::string model = document.dump();
  const std::string bin = testing::read_file(testing::data_dir() / "blender" / "arm3.bin");
  testing::write_file(folders.root / "arm.gltf", model);
  testing::write_file(folders.root / "arm3.bin", bin);
  std::map<fs::path, int> reads;
  ConversionJob job = job_for(folders, "arm.gltf");
  job.read_file = [&](const fs::path&, const fs::path& path, std::uint64_t, std::vector<std::uint8_t>& out,
                      std::string&) -> std::optional<std::uint64_t> {
    ++reads[path];
    const std::string bytes = testing::read_file(path);
    out.assign(bytes.begin(), bytes.end());
    return bytes.size();
  };
  const ConversionOutcome outcome = run_conversion(job);
  EXPECT_EQ(reads, (std::map<fs::path, int>{{folders.watch() / "arm3.bin", 1}}));
  EXPECT_EQ(outcome.content_hash, length_prefixed_sha256({model, bin, bin}));
}

TEST(ConversionReads, AFileThatCannotBeReadIsHashedAsNoBytes) {
  Folders folders;
  const std::string model = testing::read_file(testing::data_dir() / "blender" / "arm3.gltf");
  testing::write_file(folders.root / "arm.gltf", model);  // No arm3.bin.
  const ConversionOutcome outcome = run_conversion(job_for(folders, "arm.gltf"));
  EXPECT_EQ(outcome.kind, ConversionOutcome::Kind::kRejected);
  EXPECT_EQ(outcome.content_hash, length_prefixed_sha256({model, ""}));
}

}  // namespace
}  // namespace rdtf::daemon
