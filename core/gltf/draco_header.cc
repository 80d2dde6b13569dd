// Field order from libdraco 1.5.5 (PointCloudDecoder::DecodeHeader, MetadataDecoder,
// MeshSequentialDecoder and MeshEdgebreakerDecoderImpl::DecodeConnectivity) and the Draco
// bitstream specification.
#include "draco_header.h"

namespace rdtf::internal {
namespace {

class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> bytes) : bytes_(bytes) {}

  bool u8(std::uint64_t& value) {
    if (at_ >= bytes_.size()) return false;
    value = bytes_[at_++];
    return true;
  }
  bool u16(std::uint64_t& value) { return little_endian(2, value); }
  bool u32(std::uint64_t& value) { return little_endian(4, value); }
  // libdraco's DecodeVarint<uint32_t>: 7 bits a byte, low first, at most 5 bytes.
  bool varint(std::uint64_t& value) {
    value = 0;
    for (int k = 0; k < 5; ++k) {
      std::uint64_t byte = 0;
      if (!u8(byte)) return false;
      value |= (byte & 0x7f) << (7 * k);
      if ((byte & 0x80) == 0) return value <= 0xffffffffu;
    }
    return false;
  }
  bool skip(std::uint64_t n) {
    if (n > bytes_.size() - at_) return false;
    at_ += static_cast<std::size_t>(n);
    return true;
  }

 private:
  bool little_endian(int size, std::uint64_t& value) {
    if (static_cast<std::size_t>(size) > bytes_.size() - at_) return false;
    value = 0;
    for (int k = size - 1; k >= 0; --k) value = value << 8 | bytes_[at_ + static_cast<std::size_t>(k)];
    at_ += static_cast<std::size_t>(size);
    return true;
  }

  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 0;
};

// A name or value: a one-byte length, then the bytes.
bool skip_string(Reader& in) {
  std::uint64_t size = 0;
  return in.u8(size) && in.skip(size);
}

// One metadata block: entries, then named sub-blocks. Each level costs bytes, so the depth is at
// most the stream's length; it is capped lower to bound this reader's stack.
bool skip_metadata(Reader& in, int depth) {
  std::uint64_t entries = 0, children = 0;
  if (depth > 32 || !in.varint(entries)) return false;
  for (std::uint64_t k = 0; k < entries; ++k) {
    if (!skip_string(in) || !skip_string(in)) return false;
  }
  if (!in.varint(children)) return false;
  for (std::uint64_t k = 0; k < children; ++k) {
    if (!skip_string(in) || !skip_metadata(in, depth + 1)) return false;
  }
  return true;
}

bool skip_geometry_metadata(Reader& in) {
  std::uint64_t attributes = 0, id = 0;
  if (!in.varint(attributes)) return false;
  for (std::uint64_t k = 0; k < attributes; ++k) {
    if (!in.varint(id) || !skip_metadata(in, 0)) return false;
  }
  return skip_metadata(in, 0);
}

}  // namespace

std::optional<DracoHeader> read_draco_header(std::span<const std::uint8_t> bytes, std::string& error) {
  Reader in(bytes);
  static constexpr std::uint8_t kMagic[5] = {'D', 'R', 'A', 'C', 'O'};
  std::uint64_t value = 0;
  for (std::uint8_t expected : kMagic) {
    if (!in.u8(value) || value != expected) {
      error = "the bytes do not start with the Draco magic 'DRACO'";
      return std::nullopt;
    }
  }
  std::uint64_t major = 0, minor = 0, type = 0, method = 0, flags = 0;
  if (!in.u8(major) || !in.u8(minor) || !in.u8(type) || !in.u8(method) || !in.u16(flags)) {
    error = "the Draco header is truncated";
    return std::nullopt;
  }
  DracoHeader header;
  header.major = static_cast<int>(major);
  header.minor = static_cast<int>(minor);
  const std::string version = std::to_string(major) + "." + std::to_string(minor);
  if (major != 2 || minor > 2) {
    error = "Draco bitstream version " + version + " is not read (rdtf reads mesh versions 2.0 to 2.2)";
    return std::nullopt;
  }
  if (type != 1) {
    error = "the Draco stream holds no triangle mesh (encoder type " + std::to_string(type) + ")";
    return std::nullopt;
  }
  if (method > 1) {
    error = "unknown Draco mesh method " + std::to_string(method) + " (0 sequential, 1 edgebreaker)";
    return std::nullopt;
  }
  header.edgebreaker = method == 1;
  if ((flags & 0x8000) != 0 && !skip_geometry_metadata(in)) {
    error = "the Draco metadata is truncated or nested deeper than 32 levels";
    return std::nullopt;
  }
  const bool varints = minor >= 2;  // Version 2.2 writes the counts as varints, 2.0-2.1 as u32.
  bool ok = true;
  if (!header.edgebreaker) {
    ok = varints ? in.varint(header.faces) && in.varint(header.vertices)
                 : in.u32(header.faces) && in.u32(header.vertices);
  } else {
    // Traversal type; 2.0-2.1 then give the vertices added for non-manifold parts.
    std::uint64_t traversal = 0, new_vertices = 0, attribute_data = 0, symbols = 0;
    ok = in.u8(traversal) && (minor >= 2 || in.varint(new_vertices)) && in.varint(header.vertices) &&
         in.varint(header.faces) && in.u8(attribute_data) && in.varint(symbols) && in.varint(header.split_symbols);
    header.vertices += new_vertices;
  }
  if (!ok) {
    error = "the Draco connectivity header is truncated";
    return std::nullopt;
  }
  return header;
}

}  // namespace rdtf::internal
