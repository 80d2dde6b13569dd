// JSON text into ordered JSON in time linear in its size.
//
// nlohmann's ordered_json keeps an object's keys in a vector and looks a key up by walking it, so
// `Json::parse` of an object with n keys costs n^2/2 string comparisons: a 2.5 MB glTF whose
// primitive has 160,000 attributes took 32 s to parse, one of 600,000 keys would take minutes, and
// rdtfd converts whatever is saved into its folder. This parser builds the same value (the same
// keys in the same order; of a key written twice, the first place and the last value, as
// Json::parse does) and finds a key among the earlier ones of a large object through a hash index
// kept only while that object is being read.
#pragma once

#include <string_view>

#include "rdtf/gltf.h"

namespace rdtf {

// As Json::parse(text): the same value, and on bad text the same exceptions (Json::parse_error
// with its byte, Json::out_of_range for a number beyond double's range).
Json parse_json_text(std::string_view text);

}  // namespace rdtf
