#include "rdtf/glb.h"
#include "rdtf/diagnostic_codes.h"

#include <cctype>
#include <cstring>
#include <string>

namespace rdtf {
namespace {

constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
constexpr std::size_t kHeaderBytes = 12;
constexpr std::size_t kChunkHeaderBytes = 8;

std::uint32_t read_u32(std::span<const std::uint8_t> bytes, std::size_t offset) {
  return static_cast<std::uint32_t>(bytes[offset]) |
         static_cast<std::uint32_t>(bytes[offset + 1]) << 8 |
         static_cast<std::uint32_t>(bytes[offset + 2]) << 16 |
         static_cast<std::uint32_t>(bytes[offset + 3]) << 24;
}

void write_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(value >> (8 * i)));
}

}  // namespace

bool has_glb_extension(const std::filesystem::path& path) {
  std::string extension = path.extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return extension == ".glb";
}

std::optional<GlbChunks> parse_glb(std::span<const std::uint8_t> bytes, Diagnostics& diag) {
  if (bytes.size() < kHeaderBytes) {
    diag.error_at_offset(codes::GLB_UNEXPECTED_END_OF_HEADER, bytes.size(),
                         "file has " + std::to_string(bytes.size()) +
                             " bytes; a GLB header needs 12");
    return std::nullopt;
  }
  if (read_u32(bytes, 0) != kMagic) {
    diag.error_at_offset(codes::GLB_INVALID_MAGIC, 0, "not a GLB file: the first four bytes are not 'glTF'");
    return std::nullopt;
  }
  const std::uint32_t version = read_u32(bytes, 4);
  if (version != 2) {
    diag.error_at_offset(codes::GLB_INVALID_VERSION, 4,
                         "GLB version " + std::to_string(version) + " is not supported (need 2)");
    return std::nullopt;
  }
  const std::uint64_t declared = read_u32(bytes, 8);
  if (declared != bytes.size()) {
    diag.error_at_offset(codes::GLB_LENGTH_MISMATCH, 8,
                         "header says " + std::to_string(declared) + " bytes but the file has " +
                             std::to_string(bytes.size()));
    return std::nullopt;
  }

  GlbChunks chunks;
  bool have_json = false;
  std::size_t offset = kHeaderBytes;
  int index = 0;
  while (offset < bytes.size()) {
    if (bytes.size() - offset < kChunkHeaderBytes) {
      diag.error_at_offset(codes::GLB_UNEXPECTED_END_OF_CHUNK_HEADER, offset,
                           "chunk " + std::to_string(index) + " header is truncated");
      return std::nullopt;
    }
    const std::uint64_t length = read_u32(bytes, offset);
    const std::uint32_t type = read_u32(bytes, offset + 4);
    const std::size_t data = offset + kChunkHeaderBytes;
    if (length > bytes.size() - data) {
      diag.error_at_offset(codes::GLB_CHUNK_TOO_BIG, offset,
                           "chunk " + std::to_string(index) + " length " + std::to_string(length) +
                               " runs past the end of the file");
      return std::nullopt;
    }
    if (length % 4 != 0) {
      diag.error_at_offset(codes::GLB_CHUNK_LENGTH_UNALIGNED, offset,
                           "chunk " + std::to_string(index) + " length " + std::to_string(length) +
                               " is not a multiple of 4");
      return std::nullopt;
    }
    const auto payload = bytes.subspan(data, static_cast<std::size_t>(length));
    if (index == 0) {
      if (type != kChunkJson) {
        diag.error_at_offset(codes::GLB_UNEXPECTED_FIRST_CHUNK, offset, "the first chunk must be JSON");
        return std::nullopt;
      }
      if (length == 0) {
        diag.error_at_offset(codes::GLB_EMPTY_CHUNK, offset, "the JSON chunk is empty");
        return std::nullopt;
      }
      chunks.json = std::string_view(reinterpret_cast<const char*>(payload.data()), payload.size());
      have_json = true;
    } else if (type == kChunkJson) {
      diag.error_at_offset(codes::GLB_DUPLICATE_CHUNK, offset, "a second JSON chunk");
      return std::nullopt;
    } else if (type == kChunkBin) {
      if (index != 1) {
        diag.error_at_offset(codes::GLB_UNEXPECTED_BIN_CHUNK, offset,
                             "the BIN chunk must come right after the JSON chunk");
        return std::nullopt;
      }
      chunks.bin = payload;
    }
    // Chunks of other types are skipped, as the spec requires.
    offset = data + static_cast<std::size_t>(length);
    ++index;
  }
  if (!have_json) {
    diag.error_at_offset(codes::GLB_NO_JSON_CHUNK, kHeaderBytes, "the file has no JSON chunk");
    return std::nullopt;
  }
  return chunks;
}

std::vector<std::uint8_t> make_glb(std::string_view json, std::span<const std::uint8_t> bin) {
  const std::size_t json_padded = (json.size() + 3) & ~std::size_t{3};
  const std::size_t bin_padded = (bin.size() + 3) & ~std::size_t{3};
  const std::size_t total = kHeaderBytes + kChunkHeaderBytes + json_padded +
                            (bin.empty() ? 0 : kChunkHeaderBytes + bin_padded);
  std::vector<std::uint8_t> out;
  out.reserve(total);
  write_u32(out, kMagic);
  write_u32(out, 2);
  write_u32(out, static_cast<std::uint32_t>(total));
  write_u32(out, static_cast<std::uint32_t>(json_padded));
  write_u32(out, kChunkJson);
  out.insert(out.end(), json.begin(), json.end());
  out.resize(out.size() + (json_padded - json.size()), ' ');
  if (!bin.empty()) {
    write_u32(out, static_cast<std::uint32_t>(bin_padded));
    write_u32(out, kChunkBin);
    out.insert(out.end(), bin.begin(), bin.end());
    out.resize(out.size() + (bin_padded - bin.size()), 0);
  }
  return out;
}

}  // namespace rdtf
