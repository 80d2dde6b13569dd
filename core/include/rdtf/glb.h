// The GLB container (glTF 2.0 section 4.4): a 12-byte header, a JSON chunk, an optional BIN chunk.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "rdtf/diagnostics.h"

namespace rdtf {

struct GlbChunks {
  std::string_view json;                     // Points into the input bytes.
  std::optional<std::span<const std::uint8_t>> bin;  // Points into the input bytes.
};

// Splits a GLB into its chunks; every malformation is an error with the byte offset it is at.
std::optional<GlbChunks> parse_glb(std::span<const std::uint8_t> bytes, Diagnostics& diagnostics);

// Whether a file name ends in .glb, in any case (ARM.GLB): what the CLI writes as a GLB and the
// loader and rdtfd read as one.
bool has_glb_extension(const std::filesystem::path& path);

// Builds a GLB from a JSON text and an optional binary chunk, padding both as the spec requires.
std::vector<std::uint8_t> make_glb(std::string_view json, std::span<const std::uint8_t> bin);

}  // namespace rdtf
