// The counts a Draco mesh bitstream declares in its header and connectivity header, read without
// libdraco: libdraco sizes its corner table and point arrays from them before anything can compare
// them with the glTF accessors, so they are checked first (decode_draco.cc).
#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace rdtf::internal {

struct DracoHeader {
  int major = 0, minor = 0;
  bool edgebreaker = false;         // Else the sequential method.
  std::uint64_t faces = 0;          // Triangles the connectivity declares.
  std::uint64_t vertices = 0;       // Sequential: points; edgebreaker: encoded (position) vertices.
  std::uint64_t split_symbols = 0;  // Edgebreaker: extra corner-table vertices for topology splits.
};

// The header of a triangle-mesh stream of bitstream version 2.0-2.2 (the versions libdraco 1.5.5
// writes and reads for meshes); nullopt with `error` set for anything else or a truncated stream.
std::optional<DracoHeader> read_draco_header(std::span<const std::uint8_t> bytes, std::string& error);

}  // namespace rdtf::internal
