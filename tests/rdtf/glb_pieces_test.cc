// A .glb output is written from the asset's buffers where they lie (write.cc, BinChunk), not from
// an assembled copy: its bytes must be exactly what the container builder make_glb gives for the
// same JSON and the buffers concatenated on 4-byte boundaries, for buffers of every length modulo
// 4 and for none at all.
#include <gtest/gtest.h>

#include "rdtf/glb.h"
#include "rdtf/write.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

std::vector<std::uint8_t> bytes_of(const std::string& text) { return {text.begin(), text.end()}; }

// The BIN chunk as the earlier writer assembled it: each buffer from a 4-byte boundary.
std::vector<std::uint8_t> concatenated(const std::vector<std::vector<std::uint8_t>>& buffers) {
  std::vector<std::uint8_t> bin;
  for (const auto& buffer : buffers) {
    bin.resize((bin.size() + 3) & ~std::size_t{3}, 0);
    bin.insert(bin.end(), buffer.begin(), buffer.end());
  }
  return bin;
}

GltfAsset asset_with_buffers(const std::vector<std::size_t>& sizes) {
  GltfAsset asset;
  asset.binary = true;
  asset.document = Json{{"asset", {{"version", "2.0"}}}};
  std::uint8_t next = 1;
  for (std::size_t i = 0; i < sizes.size(); ++i) {
    std::vector<std::uint8_t> buffer(sizes[i]);
    for (auto& byte : buffer) byte = next++;
    asset.buffers.push_back(buffer);
    asset.document["buffers"].push_back(Json{{"byteLength", sizes[i]}});
    asset.document["bufferViews"].push_back(Json{{"buffer", i}, {"byteOffset", 0}, {"byteLength", sizes[i]}});
  }
  return asset;
}

TEST(GlbPieces, SameBytesAsTheAssembledContainer) {
  for (const auto& sizes : std::vector<std::vector<std::size_t>>{
           {}, {4}, {5}, {5, 7, 2, 1}, {1, 1, 1}, {8, 3}, {0, 6}, {100003, 13}}) {
    const GltfAsset asset = asset_with_buffers(sizes);
    testing::TempDir out;
    Diagnostics diag;
    std::string json;
    ASSERT_TRUE(write_rdtf(asset, out / "model.glb", OutputFormat::kGlb, diag, &json));
    const auto written = bytes_of(testing::read_file(out / "model.glb"));
    const auto bin = concatenated(asset.buffers);
    EXPECT_EQ(written, make_glb(json, bin)) << "buffer sizes " << ::testing::PrintToString(sizes);

    // The document points each view at its buffer's place in the one BIN chunk.
    const Json document = Json::parse(json);
    std::size_t offset = 0;
    for (std::size_t i = 0; i < sizes.size(); ++i) {
      offset = (offset + 3) & ~std::size_t{3};
      EXPECT_EQ(document["bufferViews"][i]["byteOffset"].get<std::size_t>(), offset);
      EXPECT_EQ(document["bufferViews"][i]["buffer"].get<int>(), 0);
      offset += sizes[i];
    }
    if (bin.empty()) {
      EXPECT_FALSE(document.contains("buffers"));
    } else {
      EXPECT_EQ(document["buffers"][0]["byteLength"].get<std::size_t>(), bin.size());
    }
  }
}

}  // namespace
}  // namespace rdtf
