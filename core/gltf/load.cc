#include <tiny_gltf.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstring>
#include <map>
#include <span>

#include "../geometry/big_arrays.h"
#include "confined_files.h"
#include "decode.h"
#include "rdtf/glb.h"
#include "rdtf/gltf.h"
#include "rdtf/json_text.h"
#include "rdtf/validate.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

constexpr int kMaxJsonDepth = 64;

// nlohmann's parser recurses once per nesting level: bound the depth before parsing so that a
// hostile "[[[[..." cannot overflow the stack.
bool json_depth_within(std::string_view text, int max_depth, std::size_t& offset) {
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') {
        ++i;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        offset = i;
        return false;
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
  return true;
}

// "line L, column C (byte B)" of the B-th byte (1-based) of `text`: what an editor shows.
std::string place_in(std::string_view text, std::size_t byte) {
  std::size_t line = 1;
  std::size_t column = 1;
  const std::size_t end = std::min<std::size_t>(byte == 0 ? 0 : byte - 1, text.size());
  for (std::size_t i = 0; i < end; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(column) + " (byte " +
         std::to_string(byte) + ")";
}

// Where nlohmann's parser stopped: its SAX interface is told the position, which the exception
// for a number beyond double's range (out_of_range 406) does not carry. Builds nothing.
class ErrorPosition final : public nlohmann::json_sax<Json> {
 public:
  std::size_t byte = 0;  // 1-based, the first byte of the token at fault.
  bool null() override { return true; }
  bool boolean(bool) override { return true; }
  bool number_integer(number_integer_t) override { return true; }
  bool number_unsigned(number_unsigned_t) override { return true; }
  bool number_float(number_float_t, const string_t&) override { return true; }
  bool string(string_t&) override { return true; }
  bool binary(binary_t&) override { return true; }
  bool start_object(std::size_t) override { return true; }
  bool key(string_t&) override { return true; }
  bool end_object() override { return true; }
  bool start_array(std::size_t) override { return true; }
  bool end_array() override { return true; }
  bool parse_error(std::size_t position, const std::string& token, const nlohmann::detail::exception&) override {
    // `position` counts the bytes read, up to the token's last.
    byte = position >= token.size() ? position - token.size() + 1 : position;
    return false;
  }
};

// nlohmann's messages quote the bytes they stopped at ("last read: '...'"): a file that is no
// glTF (a secret linked in, a log) would have its first bytes copied into an ERROR on the bus and
// into the log. The place (line, column, byte) tells the user enough.
std::string without_bytes_read(std::string message) {
  const std::string marker = "; last read: '";
  const auto start = message.find(marker);
  if (start == std::string::npos) return message;
  const std::string expected = "'; expected ";
  const auto end = message.rfind(expected);
  if (end != std::string::npos && end >= start + marker.size()) {
    return message.substr(0, start) + message.substr(end + 1);
  }
  return message.substr(0, start);
}

// `chunk_offset`: where the text starts in its file, for a GLB's JSON chunk: a place is then said
// in both (a chunk's "byte 9" alone read as the file's and pointed into the GLB header; s100err D6).
// XML where glTF was expected: most likely a URDF given to a command that reads glTF (`rdtf
// validate robot.urdf`), which a bare parse error at line 1 does not tell (s100err D5). A URDF's
// root element is <robot> (an SDF's is <sdf>, whose plugins may hold <robotNamespace>).
std::string not_json_hint(std::string_view text) {
  const std::size_t first = text.find_first_not_of(" \t\r\n");
  if (first == std::string_view::npos || text[first] != '<') return "";
  std::size_t at = first;
  // The root: the first element that is no declaration, comment or doctype.
  while ((at = text.find('<', at)) != std::string_view::npos && at + 1 < text.size() &&
         (text[at + 1] == '?' || text[at + 1] == '!')) {
    ++at;
  }
  const auto root_is = [&](std::string_view name) {
    return at != std::string_view::npos && text.substr(at + 1, name.size()) == name &&
           at + 1 + name.size() < text.size() && std::string_view(" \t\r\n>/").find(text[at + 1 + name.size()]) != std::string_view::npos;
  };
  if (root_is("robot")) {
    return ". This is a URDF (XML), not glTF: convert it with `rdtf import <this file> -o model.gltf`, then give "
           "model.gltf to this command";
  }
  if (root_is("sdf")) return ". This is an SDF (XML), not glTF; rdtf reads glTF, and URDF through `rdtf import`";
  return ". This is XML, not glTF JSON";
}

std::optional<Json> parse_json(std::string_view text, Diagnostics& diag,
                               std::optional<std::size_t> chunk_offset = std::nullopt) {
  const auto place_in = [&](std::string_view in, std::size_t byte) {
    std::string place = ::rdtf::place_in(in, byte);
    if (chunk_offset && !place.empty() && place.back() == ')') {
      place.pop_back();
      place += " of the JSON chunk, at offset " + std::to_string(*chunk_offset + (byte == 0 ? 0 : byte - 1)) + " of the file)";
    }
    return place;
  };
  if (text.substr(0, 3) == "\xEF\xBB\xBF") {
    const std::string hint = not_json_hint(text.substr(3));
    diag.error(codes::JSON_BOM, "",
               hint.empty() ? std::string("the JSON starts with a UTF-8 byte order mark, which glTF forbids")
                            : "the file starts with a UTF-8 byte order mark" + hint);
    return std::nullopt;
  }
  // nlohmann's parser takes a NUL byte for the end of its input, so "{...}\0anything" would parse
  // as if the rest were not there. JSON text has no NUL: not even a string may hold one unescaped.
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos) {
    diag.error(codes::INVALID_JSON, "",
               "invalid JSON at " + place_in(text, nul + 1) +
                   ": a NUL byte (0x00), which JSON text never holds (a GLB's JSON chunk is padded with "
                   "spaces, 0x20)");
    return std::nullopt;
  }
  std::size_t offset = 0;
  if (!json_depth_within(text, kMaxJsonDepth, offset)) {
    diag.error(codes::JSON_TOO_DEEP, "",
               "JSON nesting deeper than " + std::to_string(kMaxJsonDepth) + " levels at byte " +
                   std::to_string(offset));
    return std::nullopt;
  }
  try {
    Json document = parse_json_text(text);
    if (!document.is_object()) {
      diag.error(codes::TYPE_MISMATCH, "", "the glTF JSON must be an object");
      return std::nullopt;
    }
    return document;
  } catch (const Json::out_of_range& error) {
    // E.g. a number beyond double's range ("1e309"): valid JSON syntax, not a usable value. The
    // exception has no position: the text again through the SAX parser finds it.
    ErrorPosition position;
    const bool parsed = Json::sax_parse(text.begin(), text.end(), &position);
    const std::string at = parsed ? "" : " at " + place_in(text, position.byte);
    diag.error(codes::INVALID_JSON, "", "unusable JSON value" + at + ": " + error.what());
    return std::nullopt;
  } catch (const Json::parse_error& error) {
    // XML where glTF was expected: most likely a URDF given to a command that reads glTF
    // (`rdtf validate robot.urdf`), which a bare parse error at line 1 does not tell (s100err D5).
    diag.error(codes::INVALID_JSON, "",
               "invalid JSON at " + place_in(text, error.byte) + ": " + without_bytes_read(error.what()) +
                   not_json_hint(text));
    return std::nullopt;
  } catch (const Json::exception& error) {
    diag.error(codes::INVALID_JSON, "", "invalid JSON: " + without_bytes_read(error.what()));
    return std::nullopt;
  }
}

// The files a document names (external buffers and images) inside `folder`, as resolve_uri maps
// them; unusable URIs are left out.
std::vector<std::filesystem::path> files_named_by(const Json& document, const std::filesystem::path& folder) {
  std::vector<std::filesystem::path> files;
  for (const char* array : {"buffers", "images"}) {
    if (!document.contains(array) || !document[array].is_array()) continue;
    for (const Json& item : document[array]) {
      if (!item.is_object() || !item.contains("uri") || !item["uri"].is_string()) continue;
      const std::string uri = item["uri"].get<std::string>();
      if (internal::is_data_uri(uri)) continue;
      std::string why;
      if (auto path = internal::resolve_uri(folder, uri, why)) files.push_back(std::move(*path));
    }
  }
  return files;
}

// The files the model names, read once before the load (read_source_files), and the external
// buffers that passed our checks by the token tinygltf is given instead of the model's URI.
// tinygltf reads nothing from disk: its filesystem callbacks serve these bytes.
struct ConfinedReads {
  SourceFiles* source = nullptr;
  std::map<std::string, std::filesystem::path> files;
  std::map<std::string, std::uint64_t> lengths;  // Each buffer's byteLength, by its token.
  std::map<std::filesystem::path, int> uses;  // Buffers not yet loaded that name each file.
  std::vector<std::size_t> fallbacks;  // Buffers that EXT_meshopt_compression decodes into.
};

// The file read for `path`, or nothing and `why` (refused, unreadable, or never read).
const SourceFile* source_file(const ConfinedReads& reads, const std::filesystem::path& path, std::string& why) {
  const auto found = reads.source->find(path);
  if (found == reads.source->end()) {
    why = "was not read with the model";
    return nullptr;
  }
  if (!found->second.size) {
    why = found->second.why;
    return nullptr;
  }
  return &found->second;
}

bool fs_file_exists(const std::string& name, void* user) {
  const auto* reads = static_cast<const ConfinedReads*>(user);
  return reads->files.count(name) > 0;
}

std::string fs_expand(const std::string& name, void*) { return name; }

bool fs_read(std::vector<unsigned char>* out, std::string* err, const std::string& name,
             void* user) {
  auto* reads = static_cast<ConfinedReads*>(user);
  const auto found = reads->files.find(name);
  if (found == reads->files.end()) {
    if (err) *err = "refused: not a file of this model";
    return false;
  }
  const auto source = reads->source->find(found->second);
  if (source == reads->source->end() || !source->second.size) {
    if (err) *err = "was not read with the model";
    return false;
  }
  // tinygltf keeps this vector as the buffer (it swaps it in): the last buffer naming a file takes
  // its bytes (in huge pages when large, read_confined_file_within), the others a copy.
  if (--reads->uses[found->second] == 0) {
    *out = std::move(source->second.bytes);
  } else {
    internal::reserve_huge(*out, source->second.bytes.size());
    out->assign(source->second.bytes.begin(), source->second.bytes.end());
  }
  // A file longer than its buffer's byteLength holds the buffer in its first bytes (the validator
  // accepts it, and a GLB's BIN chunk may be longer too); tinygltf wants the exact length.
  if (const auto length = reads->lengths.find(name); length != reads->lengths.end() && out->size() > length->second) {
    out->resize(static_cast<std::size_t>(length->second));
  }
  return true;
}

bool fs_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err = "writing through tinygltf is disabled";
  return false;
}

bool skip_image(tinygltf::Image*, const int, std::string*, std::string*, int, int,
                const unsigned char*, int, void*) {
  return true;  // Images are never decoded: the converter needs none, and decoding is slow.
}

// Caps each embedded buffer before anything decodes it: a data URI's payload (base64, 3 bytes per
// 4 characters) may not hold more than max_buffer_bytes, whatever byteLength claims.
bool data_uris_within_cap(const Json& document, const LoadLimits& limits, Diagnostics& diag) {
  if (!document.contains("buffers") || !document["buffers"].is_array()) return true;
  const Json& buffers = document["buffers"];
  bool ok = true;
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    if (!buffers[i].is_object() || !buffers[i].contains("uri") || !buffers[i]["uri"].is_string()) continue;
    const std::string& uri = buffers[i]["uri"].get_ref<const std::string&>();
    if (!internal::is_data_uri(uri)) continue;
    const auto comma = uri.find(',');
    const std::uint64_t payload = comma == std::string::npos ? 0 : uri.size() - comma - 1;
    const std::uint64_t decoded = payload / 4 * 3;
    if (decoded > limits.max_buffer_bytes) {
      diag.error(codes::LIMIT_EXCEEDED, json_pointer("/buffers", i) + "/uri",
                 "the data URI holds about " + std::to_string(decoded) + " bytes, over the limit of " +
                     std::to_string(limits.max_buffer_bytes) + " bytes (max_buffer_bytes)");
      ok = false;
    }
  }
  return ok;
}

// Checks every external URI (buffers and images) and prepares the document tinygltf loads: only
// the buffers, each external one renamed to a token that maps to a checked path.
std::optional<Json> prepare_buffers(const Json& document, bool binary, const LoadLimits& limits,
                                    const std::filesystem::path& folder, ConfinedReads& reads,
                                    Diagnostics& diag) {
  Json loader_document = {{"asset", {{"version", "2.0"}}}, {"buffers", Json::array()}};
  if (!document.contains("buffers")) return loader_document;
  const Json& buffers = document["buffers"];
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    const Json& buffer = buffers[i];
    const std::string pointer = json_pointer("/buffers", i);
    Json entry = {{"byteLength", buffer["byteLength"]}};
    if (!buffer.contains("uri")) {
      if (internal::is_meshopt_fallback(buffer)) {
        reads.fallbacks.push_back(i);  // No bytes to load: decoding fills it.
        continue;
      }
      if (!binary || i != 0) {
        diag.error(codes::BUFFER_MISSING_URI, pointer,
                   "buffer has no uri; only the first buffer of a GLB may use the BIN chunk");
        continue;
      }
      loader_document["buffers"].push_back(entry);
      continue;
    }
    const std::string uri = buffer["uri"].get<std::string>();
    if (internal::is_data_uri(uri)) {
      entry["uri"] = uri;
      loader_document["buffers"].push_back(entry);
      continue;
    }
    std::string why;
    const auto path = internal::resolve_uri(folder, uri, why);
    if (!path) {
      diag.error(codes::URI_REFUSED, pointer + "/uri", "'" + uri + "': " + why);
      continue;
    }
    const SourceFile* file = source_file(reads, *path, why);
    const auto size = file != nullptr ? file->size : std::nullopt;
    if (!size) {
      diag.error(codes::IO_ERROR, pointer + "/uri", "'" + uri + "' (" + path->string() + ") " + why);
      continue;
    }
    const std::uint64_t declared = buffer["byteLength"].get<std::uint64_t>();
    if (*size > limits.max_file_bytes) {
      diag.error(codes::LIMIT_EXCEEDED, pointer + "/uri",
                 "'" + uri + "' is " + std::to_string(*size) + " bytes, over the limit of " +
                     std::to_string(limits.max_file_bytes));
      continue;
    }
    if (*size < declared) {
      diag.error(codes::BUFFER_EXTERNAL_BYTELENGTH_MISMATCH, pointer + "/byteLength",
                 "'" + uri + "' has " + std::to_string(*size) + " bytes but byteLength is " +
                     std::to_string(declared) + ": the file is shorter than the buffer it holds");
      continue;
    }
    const std::string token = "rdtf-confined-buffer-" + std::to_string(i);
    reads.files[token] = *path;
    reads.lengths[token] = declared;
    ++reads.uses[*path];
    entry["uri"] = token;
    loader_document["buffers"].push_back(entry);
  }
  if (document.contains("images")) {
    const Json& images = document["images"];
    for (std::size_t i = 0; i < images.size(); ++i) {
      if (!images[i].is_object() || !images[i].contains("uri") || !images[i]["uri"].is_string())
        continue;
      const std::string uri = images[i]["uri"].get<std::string>();
      if (internal::is_data_uri(uri)) continue;
      std::string why;
      const std::string pointer = json_pointer("/images", i) + "/uri";
      const auto path = internal::resolve_uri(folder, uri, why);
      if (!path) {
        diag.error(codes::URI_REFUSED, pointer, "'" + uri + "': " + why);
      } else if (source_file(reads, *path, why) == nullptr) {
        // A texture not there (moved away since the export) costs only its look: a warning. One
        // that is there but refused (a symbolic link out of the folder, a hard link, a device,
        // over max_file_bytes) is refused as a buffer would be (docs/daemon.md, "Confinement").
        // (A symbolic link whose target is gone is not there either: status() follows it.)
        std::error_code error;
        if (std::filesystem::status(*path, error).type() == std::filesystem::file_type::not_found) {
          diag.warning(codes::IO_ERROR, pointer, "image '" + uri + "' " + why + "; it will be missing from the output");
        } else {
          diag.error(codes::URI_REFUSED, pointer, "image '" + uri + "': " + why);
        }
      }
    }
  }
  if (diag.has_errors()) return std::nullopt;
  return loader_document;
}

}  // namespace

bool looks_like_glb(const std::vector<std::uint8_t>& bytes) {
  return bytes.size() >= 4 && bytes[0] == 'g' && bytes[1] == 'l' && bytes[2] == 'T' &&
         bytes[3] == 'F';
}

namespace {

// A file meant as a GLB without GLB's magic: named .glb, or not JSON (no '{' or byte order mark
// first) with GLB's version 2 where the header has it. Reported as a damaged GLB, not as JSON
// that fails at its first byte.
bool glb_by_name_or_header(const std::filesystem::path& display_path, const std::vector<std::uint8_t>& bytes) {
  const bool json_start = bytes[0] == '{' || bytes[0] == 0xEF || std::isspace(bytes[0]) != 0;
  if (json_start) return false;  // JSON, whatever its name: read as JSON.
  if (has_glb_extension(display_path)) return true;
  return bytes.size() >= 8 && bytes[4] == 2 && bytes[5] == 0 && bytes[6] == 0 && bytes[7] == 0;
}

// The GLB's BIN chunk when it is the only buffer and tinygltf would load it without complaint
// (it copies the chunk's first byteLength bytes after checks that all pass here): that buffer is
// taken straight from the file's bytes, which spares rebuilding an 18 MB GLB for tinygltf and
// tinygltf's own copy of it (issue 6). Anything else - external files, data URIs, a byteLength
// tinygltf would refuse - goes through tinygltf as before, with its diagnostics.
std::optional<std::span<const std::uint8_t>> lone_bin_chunk(const Json& loader_document,
                                                           bool binary,
                                                           std::span<const std::uint8_t> bin) {
  const Json& buffers = loader_document["buffers"];
  if (!binary || buffers.size() != 1 || buffers[0].contains("uri")) return std::nullopt;
  const Json& length = buffers[0]["byteLength"];
  if (!length.is_number_unsigned()) return std::nullopt;
  const auto byte_length = length.get<std::uint64_t>();
  // tinygltf refuses a BIN chunk under 4 bytes and a byteLength beyond it, and cannot copy none.
  if (bin.size() < 4 || byte_length == 0 || byte_length > bin.size()) return std::nullopt;
  return bin.first(static_cast<std::size_t>(byte_length));
}

// The buffer holding `chunk`: the file's own bytes with the chunk moved to their front when the
// caller hands them over (`owned`, which holds the chunk), so that no new memory is faulted in;
// else a copy, in huge pages.
std::vector<std::uint8_t> bin_chunk_buffer(std::span<const std::uint8_t> chunk,
                                           std::vector<std::uint8_t>* owned) {
  std::vector<std::uint8_t> buffer;
  if (owned != nullptr) {
    const auto offset = static_cast<std::size_t>(chunk.data() - owned->data());
    std::memmove(owned->data(), owned->data() + offset, chunk.size());
    owned->resize(chunk.size());
    buffer = std::move(*owned);
  } else {
    internal::reserve_huge(buffer, chunk.size());
    buffer.assign(chunk.begin(), chunk.end());
  }
  return buffer;
}

// A GLB's first buffer without a uri is its BIN chunk, which must be there and hold byteLength
// bytes (it may hold up to 3 more, its padding). Said here with the sizes, in the validator's
// codes, rather than by tinygltf's message about the whole buffers array.
void check_bin_chunk(const Json& document, std::span<const std::uint8_t> file, std::span<const std::uint8_t> bin,
                     Diagnostics& diag) {
  // Run on a document validate_document passed; still, nothing is assumed of its shape here.
  const auto buffers = document.find("buffers");
  if (buffers == document.end() || !buffers->is_array() || buffers->empty()) return;
  const Json& buffer = (*buffers)[0];
  if (!buffer.is_object() || buffer.contains("uri") || internal::is_meshopt_fallback(buffer)) return;
  const auto length = buffer.find("byteLength");
  if (length == buffer.end() || !length->is_number_unsigned()) return;
  const std::uint64_t declared = length->get<std::uint64_t>();
  if (bin.data() == nullptr) {
    diag.error(codes::BUFFER_MISSING_GLB_DATA, "/buffers/0",
               "buffer 0 has no uri, so its " + std::to_string(declared) +
                   " bytes are the GLB's BIN chunk, but the file has no BIN chunk");
  } else if (bin.size() < declared) {
    diag.error(codes::BUFFER_BYTE_LENGTH_MISMATCH, "/buffers/0",
               "buffer 0 has byteLength " + std::to_string(declared) + ", but the GLB's BIN chunk (its data at byte " +
                   std::to_string(bin.data() - file.data()) + ") holds only " + std::to_string(bin.size()) + " bytes");
  }
}

// Every buffer of `loader_document` (prepare_buffers) through tinygltf, into asset.buffers.
bool load_buffers(const Json& loader_document, bool binary, std::span<const std::uint8_t> bin,
                  ConfinedReads& reads, GltfAsset& asset, Diagnostics& diag) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&skip_image, nullptr);
  tinygltf::FsCallbacks callbacks{&fs_file_exists, &fs_expand, &fs_read, &fs_write, &reads};
  loader.SetFsCallbacks(callbacks);
  tinygltf::Model model;
  std::string error;
  std::string warning;
  const std::string loader_json = loader_document.dump();
  bool loaded = false;
  if (binary) {
    const auto glb = make_glb(loader_json, bin);
    loaded = loader.LoadBinaryFromMemory(&model, &error, &warning, glb.data(),
                                         static_cast<unsigned int>(glb.size()), "");
  } else {
    loaded = loader.LoadASCIIFromString(&model, &error, &warning, loader_json.data(),
                                        static_cast<unsigned int>(loader_json.size()), "");
  }
  if (!loaded || model.buffers.size() != loader_document.at("buffers").size()) {
    // tinygltf names our tokens; map them back to the pointers the user knows.
    std::string message = error.empty() ? std::string("tinygltf could not load the buffers") : error;
    while (!message.empty() && message.back() == '\n') message.pop_back();
    diag.error(codes::BUFFER_LOAD_FAILED, "/buffers", message);
    return false;
  }
  asset.buffers.reserve(model.buffers.size());
  for (auto& buffer : model.buffers) asset.buffers.push_back(std::move(buffer.data));
  return true;
}

// The external images' bytes, kept in the asset for its writers (a file a buffer names too is
// copied: the buffer takes its bytes).
void keep_images(const Json& document, const std::filesystem::path& folder, ConfinedReads& reads,
                 GltfAsset& asset) {
  if (!document.contains("images")) return;
  for (const Json& image : document["images"]) {
    if (!image.is_object() || !image.contains("uri") || !image["uri"].is_string()) continue;
    const std::string& uri = image["uri"].get_ref<const std::string&>();
    if (internal::is_data_uri(uri)) continue;
    std::string why;
    const auto path = internal::resolve_uri(folder, uri, why);
    if (!path || asset.images.count(*path) > 0) continue;
    const auto found = reads.source->find(*path);
    if (found == reads.source->end() || !found->second.size || *found->second.size > asset.limits.max_file_bytes) {
      continue;
    }
    if (reads.uses[*path] > 0) {
      asset.images[*path] = found->second.bytes;
    } else {
      asset.images[*path] = std::move(found->second.bytes);
    }
  }
}

// load_gltf_from_memory; `owned`, when given, holds `bytes` and may be consumed (load_gltf
// hands over the file it read, whose BIN chunk then becomes the buffer in place).
std::optional<GltfAsset> load_from_bytes(const std::vector<std::uint8_t>& bytes,
                                         std::vector<std::uint8_t>* owned,
                                         const std::filesystem::path& display_path,
                                         const std::filesystem::path& folder,
                                         const LoadLimits& limits,
                                         std::optional<SourceFiles> files, Diagnostics& diag) {
  diag.set_file(display_path.string());
  if (bytes.empty()) {
    diag.error(codes::EMPTY_FILE, "", "the file is empty");
    return std::nullopt;
  }
  GltfAsset asset;
  asset.path = display_path;
  asset.folder = folder;
  asset.limits = limits;
  asset.binary = looks_like_glb(bytes);
  if (!asset.binary && glb_by_name_or_header(display_path, bytes)) {
    char shown[64];
    std::snprintf(shown, sizeof(shown), "%02x %02x %02x %02x", bytes[0], bytes.size() > 1 ? bytes[1] : 0,
                  bytes.size() > 2 ? bytes[2] : 0, bytes.size() > 3 ? bytes[3] : 0);
    diag.error_at_offset(codes::GLB_INVALID_MAGIC, 0,
                         std::string("a GLB (by its name or its version field) whose first four bytes are ") + shown +
                             ", not 'glTF' (67 6c 54 46): the file is damaged, or is no GLB");
    return std::nullopt;
  }

  std::string_view json_text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  std::span<const std::uint8_t> bin;
  if (asset.binary) {
    const auto chunks = parse_glb(bytes, diag);
    if (!chunks) return std::nullopt;
    json_text = chunks->json;
    if (chunks->bin) bin = *chunks->bin;
  }
  auto document = parse_json(json_text, diag,
                             asset.binary ? std::optional<std::size_t>(static_cast<std::size_t>(
                                                reinterpret_cast<const std::uint8_t*>(json_text.data()) - bytes.data()))
                                          : std::nullopt);
  if (!document) return std::nullopt;
  if (!data_uris_within_cap(*document, limits, diag)) return std::nullopt;
  validate_document(*document, limits, diag);
  if (asset.binary && !diag.has_errors()) check_bin_chunk(*document, bytes, bin, diag);
  if (diag.has_errors()) return std::nullopt;

  // Every file the model names, read once (unless the caller already did, to hash them).
  if (!files) files = read_source_files(files_named_by(*document, folder), folder, limits);
  ConfinedReads reads;
  reads.source = &*files;
  const auto loader_document =
      prepare_buffers(*document, asset.binary, limits, folder, reads, diag);
  if (!loader_document) return std::nullopt;
  keep_images(*document, folder, reads, asset);

  if (const auto chunk = lone_bin_chunk(*loader_document, asset.binary, bin)) {
    asset.buffers.push_back(bin_chunk_buffer(*chunk, owned));
  } else if (!load_buffers(*loader_document, asset.binary, bin, reads, asset, diag)) {
    return std::nullopt;
  }
  for (const std::size_t i : reads.fallbacks) {
    asset.buffers.insert(asset.buffers.begin() + static_cast<std::ptrdiff_t>(i), std::vector<std::uint8_t>());
  }
  asset.document = std::move(*document);

  // Compressed geometry becomes plain accessors, checked again as plain glTF.
  bool decoded = false;
  if (!internal::decode_compressed(asset, decoded, diag)) return std::nullopt;
  if (decoded) validate_document(asset.document, limits, diag);
  if (diag.has_errors()) return std::nullopt;

  validate_data(asset, diag);
  if (diag.has_errors()) return std::nullopt;
  return asset;
}

}  // namespace

std::optional<GltfAsset> load_gltf_from_memory(const std::vector<std::uint8_t>& bytes,
                                               const std::filesystem::path& display_path,
                                               const std::filesystem::path& folder,
                                               const LoadLimits& limits, Diagnostics& diag) {
  return load_from_bytes(bytes, nullptr, display_path, folder, limits, std::nullopt, diag);
}

std::optional<GltfAsset> load_gltf_from_memory(const std::vector<std::uint8_t>& bytes,
                                               const std::filesystem::path& display_path,
                                               const std::filesystem::path& folder,
                                               const LoadLimits& limits, SourceFiles files,
                                               Diagnostics& diag) {
  return load_from_bytes(bytes, nullptr, display_path, folder, limits, std::move(files), diag);
}

std::vector<std::filesystem::path> referenced_files(const std::vector<std::uint8_t>& bytes,
                                                    const std::filesystem::path& folder) {
  Diagnostics ignored;
  std::string_view text(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  if (looks_like_glb(bytes)) {
    const auto chunks = parse_glb(bytes, ignored);
    if (!chunks) return {};
    text = chunks->json;
  }
  const auto document = parse_json(text, ignored);
  if (!document) return {};
  return files_named_by(*document, folder);
}

std::optional<GltfAsset> load_gltf(const std::filesystem::path& path, const LoadLimits& limits,
                                   Diagnostics& diag) {
  diag.set_file(path.string());
  std::vector<std::uint8_t> bytes;
  std::string why;
  // Room for the file in huge pages before it is read (big_arrays.h). The size is only a hint:
  // read_regular_file checks the file itself and grows the vector if it must.
  std::error_code size_error;
  const auto size = std::filesystem::file_size(path, size_error);
  if (!size_error && size <= limits.max_file_bytes) {
    internal::reserve_huge(bytes, static_cast<std::size_t>(size));
  }
  if (!internal::read_regular_file(path, limits.max_file_bytes, bytes, why)) {
    diag.error(codes::IO_ERROR, "", "cannot read the model: " + why);
    return std::nullopt;
  }
  std::error_code error;
  auto folder = std::filesystem::canonical(std::filesystem::absolute(path, error).parent_path(), error);
  if (error) {
    diag.error(codes::IO_ERROR, "", "cannot resolve the model's folder: " + error.message());
    return std::nullopt;
  }
  return load_from_bytes(bytes, &bytes, path, folder, limits, std::nullopt, diag);
}

}  // namespace rdtf
