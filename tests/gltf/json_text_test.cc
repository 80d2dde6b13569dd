// rdtf::parse_json_text (core/gltf/json_text.cc) builds what Json::parse builds - the same values,
// keys in the same order, a repeated key at its first place with its last value - and throws what
// Json::parse throws, at the same byte; only the time to find a key among an object's earlier
// ones differs (docs/benchmarks.md, "Parsing JSON").
#include <gtest/gtest.h>

#include <filesystem>
#include <string>
#include <vector>

#include "rdtf/json_text.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

namespace fs = std::filesystem;

void expect_same(const std::string& text) {
  const Json expected = Json::parse(text);
  const Json parsed = parse_json_text(text);
  EXPECT_EQ(parsed, expected);
  EXPECT_EQ(parsed.dump(), expected.dump());  // Key order too, at every level.
}

TEST(JsonText, EveryGltfOfTheTestDataParsesAsJsonParseParsesIt) {
  std::size_t files = 0;
  for (const auto& entry : fs::recursive_directory_iterator(testing::data_dir())) {
    if (entry.path().extension() != ".gltf") continue;
    const std::string text = testing::read_file(entry.path());
    if (!Json::accept(text)) continue;  // The broken ones: see ThrowsWhatJsonParseThrows.
    SCOPED_TRACE(entry.path().string());
    expect_same(text);
    ++files;
  }
  EXPECT_GE(files, 300u);
}

// An object of `keys` keys k0, k1, ... with the keys at `repeats` written again (value -i).
std::string object_with_repeats(int keys, const std::vector<int>& repeats) {
  std::string text = "{";
  for (int i = 0; i < keys; ++i) text += (i == 0 ? "\"k" : ",\"k") + std::to_string(i) + "\":" + std::to_string(i);
  for (int r : repeats) text += ",\"k" + std::to_string(r) + "\":{\"again\":" + std::to_string(-r) + "}";
  return text + "}";
}

TEST(JsonText, ARepeatedKeyKeepsItsFirstPlaceAndTakesTheLastValue) {
  // Objects below, at and above the size from which keys are found through an index (16), with
  // repeats of the first, a middle and the last key, before and after the index exists.
  for (int keys : {1, 2, 15, 16, 17, 40, 1000}) {
    SCOPED_TRACE(keys);
    expect_same(object_with_repeats(keys, {}));
    expect_same(object_with_repeats(keys, {0}));
    expect_same(object_with_repeats(keys, {keys - 1, 0, keys / 2, keys - 1}));
  }
  const Json parsed = parse_json_text(R"({"a":1,"b":2,"a":3})");
  ASSERT_EQ(parsed.size(), 2u);
  EXPECT_EQ(parsed.begin().key(), "a");
  EXPECT_EQ(parsed["a"], 3);
  // Nested: repeats inside arrays of objects inside an object that itself repeats a key.
  std::string nested = "{\"list\":[" + object_with_repeats(20, {3, 19}) + "," + object_with_repeats(3, {1}) +
                       "],\"x\":[[],{}],\"list\":[" + object_with_repeats(30, {29}) + "],\"y\":null}";
  expect_same(nested);
  expect_same(R"([1,-2,3.5,1e-300,18446744073709551615,-9223372036854775808,"\u00e9\ud83d\ude00",true,false,null])");
  expect_same(R"("just a string")");
}

TEST(JsonText, ThrowsWhatJsonParseThrows) {
  for (const std::string& text :
       {std::string("{\"a\":}"), std::string("[1,2"), std::string("{} x"), std::string(""),
        std::string("{\"a\":1,}"), std::string("{\"a\" 1}"), std::string("\"\\x\""),
        object_with_repeats(40, {2}) + "]", std::string("{\"k\":[1,2,{\"z\":tru}]}")}) {
    SCOPED_TRACE(text);
    std::size_t expected_byte = 0;
    std::string expected_what;
    try {
      const Json accepted = Json::parse(text);
      ADD_FAILURE() << "Json::parse accepted it: " << accepted.dump();
    } catch (const Json::parse_error& error) {
      expected_byte = error.byte;
      expected_what = error.what();
    }
    try {
      const Json accepted = parse_json_text(text);
      ADD_FAILURE() << "parse_json_text accepted it: " << accepted.dump();
    } catch (const Json::parse_error& error) {
      EXPECT_EQ(error.byte, expected_byte);
      EXPECT_EQ(std::string(error.what()), expected_what);
    }
  }
  // A number beyond double's range is syntax Json::parse accepts and a value it refuses.
  EXPECT_THROW((void)parse_json_text(R"({"a":[1e309]})"), Json::out_of_range);
}

// The case that made it: a primitive of 160,000 attributes, loaded whole. Its keys are all there,
// in order (how long it takes is measured in bench/convert_bench.cc, not asserted here).
TEST(JsonText, AnObjectOfManyKeysKeepsThemAllInOrder) {
  constexpr int kKeys = 160'000;
  std::string text = "{";
  for (int i = 0; i < kKeys; ++i) text += (i == 0 ? "\"TEXCOORD_" : ",\"TEXCOORD_") + std::to_string(i) + "\":" + std::to_string(i);
  text += ",\"TEXCOORD_7\":-7}";
  const Json parsed = parse_json_text(text);
  ASSERT_EQ(parsed.size(), static_cast<std::size_t>(kKeys));
  int i = 0;
  for (const auto& [key, value] : parsed.items()) {
    ASSERT_EQ(key, "TEXCOORD_" + std::to_string(i));
    ASSERT_EQ(value.get<int>(), i == 7 ? -7 : i);
    ++i;
  }
}

}  // namespace
}  // namespace rdtf
