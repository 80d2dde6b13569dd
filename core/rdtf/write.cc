#include "rdtf/write.h"

#include <algorithm>
#include <deque>
#include <optional>
#include <span>
#include <limits>
#include <set>
#include <system_error>

#include "../gltf/confined_files.h"
#include "rdtf/atomic_file.h"
#include "rdtf/glb.h"
#include "rdtf/diagnostic_codes.h"

namespace rdtf {
namespace {

std::string percent_encode(const std::string& text) {
  static const char* const kHex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

bool same_file(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code error;
  return std::filesystem::equivalent(a, b, error) && !error;
}

// Atomically and durably, or into a stage that its commit makes durable (WriteOptions::staged_for).
bool put_file(const std::filesystem::path& path, std::span<const std::span<const std::uint8_t>> pieces,
              const WriteOptions& options, std::string& why) {
  return options.staged_for.empty() ? write_file_atomically(path, pieces, why) : write_staged_file(path, pieces, why);
}

bool put_file(const std::filesystem::path& path, std::string_view text, const WriteOptions& options, std::string& why) {
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  return put_file(path, std::span<const std::span<const std::uint8_t>>(&bytes, 1), options, why);
}

bool write_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes,
                 const std::string& pointer, const WriteOptions& options, Diagnostics& diag) {
  std::error_code error;
  std::filesystem::create_directories(path.parent_path(), error);
  std::string why;
  if (!put_file(path, std::span<const std::span<const std::uint8_t>>(&bytes, 1), options, why)) {
    diag.error(codes::WRITE_FAILED, pointer, "cannot write " + path.string() + ": " + why);
    return false;
  }
  return true;
}

// The bytes of an image referenced by URI, as the loader read them with the model (never the
// file again: what is written is what was hashed and checked).
std::optional<std::vector<std::uint8_t>> read_image(const GltfAsset& asset, const std::string& uri,
                                                    std::filesystem::path& source) {
  std::string why;
  const auto path = internal::resolve_uri(asset.folder, uri, why);
  if (!path) return std::nullopt;
  const auto found = asset.images.find(*path);
  if (found == asset.images.end()) return std::nullopt;
  source = *path;
  return found->second;
}

// An image's media type from its first bytes (the formats glTF and its texture extensions take),
// as the Khronos validator reads it: not from its file name, which may have no extension,
// be percent-encoded, or lie (JPEG bytes in a .png), and a GLB's image must say what it holds.
std::optional<std::string> sniffed_mime_type(std::span<const std::uint8_t> bytes) {
  const auto starts = [&](std::initializer_list<std::uint8_t> magic, std::size_t at = 0) {
    if (bytes.size() < at + magic.size()) return false;
    return std::equal(magic.begin(), magic.end(), bytes.begin() + static_cast<std::ptrdiff_t>(at));
  };
  if (starts({0x89, 'P', 'N', 'G', 0x0D, 0x0A, 0x1A, 0x0A})) return "image/png";
  if (starts({0xFF, 0xD8, 0xFF})) return "image/jpeg";
  if (starts({'R', 'I', 'F', 'F'}) && starts({'W', 'E', 'B', 'P'}, 8)) return "image/webp";
  if (starts({0xAB, 'K', 'T', 'X', ' ', '2', '0', 0xBB, 0x0D, 0x0A, 0x1A, 0x0A})) return "image/ktx2";
  return std::nullopt;
}

// A file beside a .gltf's JSON.
struct Resource {
  std::string pointer;                  // "/buffers/0", "/images/2"
  std::filesystem::path name;           // Relative to the output's folder.
  std::filesystem::path source;         // The file it was read from, never overwritten with itself.
  std::span<const std::uint8_t> bytes;
};

// With a digest, `relative` becomes a content-addressed name directly in the output's folder.
std::filesystem::path resource_name(const std::filesystem::path& relative, std::span<const std::uint8_t> bytes,
                                    const WriteOptions& options) {
  if (!options.content_digest) return relative;
  return content_addressed_name(relative.stem().string(), relative.extension().string(), bytes,
                                options.content_digest);
}

// The external buffers of `document` (data: URIs stay embedded); their URIs are set to where they
// go when that is a new name.
void external_buffers(const GltfAsset& asset, Json& document, const std::filesystem::path& output,
                      const WriteOptions& options, std::vector<Resource>& resources) {
  if (!document.contains("buffers")) return;
  Json& buffers = document["buffers"];
  for (std::size_t i = 0; i < buffers.size(); ++i) {
    Resource resource{json_pointer("/buffers", i), {}, {}, asset.buffers[i]};
    const bool has_uri = buffers[i].contains("uri");
    // Named after the output, not the input: two models whose buffers are both "model.bin",
    // converted into one folder, must not overwrite each other's. (Content-addressed names, in
    // a folder of their own, keep the input's stem, which says where they came from.)
    resource.name = output.stem().string() + (i == 0 ? "" : "_" + std::to_string(i)) + ".bin";
    if (has_uri) {
      const std::string uri = buffers[i]["uri"].get<std::string>();
      if (internal::is_data_uri(uri)) continue;
      std::string why;
      const auto source = internal::resolve_uri(asset.folder, uri, why);
      const auto relative = internal::resolve_uri(std::filesystem::path("/"), uri, why);
      if (!source || !relative) continue;  // The loader refused these already.
      if (options.content_digest) resource.name = relative->relative_path();
      resource.source = *source;
    }
    resource.name = resource_name(resource.name, resource.bytes, options);
    buffers[i]["uri"] = percent_encode(resource.name.string());
    resources.push_back(std::move(resource));
  }
}

// The external images of `document`, read again from the model's folder into `read`.
void external_images(const GltfAsset& asset, Json& document, const WriteOptions& options,
                     std::deque<std::vector<std::uint8_t>>& read, std::vector<Resource>& resources,
                     Diagnostics& diag) {
  if (!document.contains("images")) return;
  Json& images = document["images"];
  for (std::size_t i = 0; i < images.size(); ++i) {
    if (!images[i].contains("uri")) continue;
    const std::string uri = images[i]["uri"].get<std::string>();
    if (internal::is_data_uri(uri)) continue;
    Resource resource{json_pointer("/images", i), {}, {}, {}};
    auto bytes = read_image(asset, uri, resource.source);
    std::string why;
    const auto relative = internal::resolve_uri(std::filesystem::path("/"), uri, why);
    if (!bytes || !relative) {
      diag.warning(codes::IMAGE_NOT_COPIED, json_pointer("/images", i) + "/uri",
                   "image '" + uri + "' could not be read, so it is missing beside the output");
      continue;
    }
    resource.bytes = read.emplace_back(std::move(*bytes));
    resource.name = resource_name(relative->relative_path(), resource.bytes, options);
    if (options.content_digest) images[i]["uri"] = percent_encode(resource.name.string());
    resources.push_back(std::move(resource));
  }
}

// Writes each resource into `folder`; `created` receives those that were not there before.
bool write_resources(const std::vector<Resource>& resources, const std::filesystem::path& folder,
                     const WriteOptions& options, Diagnostics& diag, std::vector<std::filesystem::path>& created) {
  bool ok = true;
  for (const Resource& resource : resources) {
    const auto target = folder / resource.name;
    if (!resource.source.empty() && same_file(resource.source, target)) continue;
    // Staged beside its own source (rdtf convert's output next to the model): the destination is
    // the source itself, perhaps through a link of the modeller's, which moving a copy over it
    // would replace. Not for content-addressed outputs (rdtfd), which follow no link they find.
    if (!resource.source.empty() && !options.staged_for.empty() && !options.content_digest &&
        same_file(resource.source, options.staged_for / resource.name)) {
      continue;
    }
    // Already where the stage's commit would put it, byte for byte: nothing to write, sync or move.
    if (!options.staged_for.empty() &&
        file_holds(options.staged_for / resource.name, std::span<const std::span<const std::uint8_t>>(&resource.bytes, 1))) {
      continue;
    }
    std::error_code error;
    const bool existed = std::filesystem::exists(target, error);
    if (!write_bytes(target, resource.bytes, resource.pointer, options, diag)) {
      ok = false;
    } else if (!existed) {
      created.push_back(target);
    }
  }
  return ok;
}

// The names of the files the .gltf at `path` refers to (none when there is no such file).
std::set<std::string> names_referenced_by(const std::filesystem::path& path) {
  std::set<std::string> names;
  std::vector<std::uint8_t> bytes;
  std::string why;
  if (!internal::read_regular_file(path, std::numeric_limits<std::uint64_t>::max(), bytes, why)) return names;
  std::error_code error;
  const auto folder = std::filesystem::canonical(path.has_parent_path() ? path.parent_path() : ".", error);
  if (error) return names;
  for (const auto& file : referenced_files(bytes, folder)) names.insert(file.filename().string());
  return names;
}

// After the JSON's rename: files that neither it nor the JSON it replaced refers to go. After a
// failure: the files this write created go, since no JSON refers to them.
void tidy_content_addressed(const std::filesystem::path& folder, bool committed, const std::vector<Resource>& resources,
                            std::set<std::string> keep, const std::vector<std::filesystem::path>& created) {
  if (!committed) {
    remove_created(created);
    return;
  }
  for (const Resource& resource : resources) keep.insert(resource.name.filename().string());
  remove_unreferenced(folder, keep);
}

bool write_gltf(const GltfAsset& asset, const std::filesystem::path& output, const WriteOptions& options,
                Diagnostics& diag, std::string* written_json) {
  Json document = asset.document;
  const std::filesystem::path folder = output.has_parent_path() ? output.parent_path() : ".";
  std::vector<Resource> resources;
  std::deque<std::vector<std::uint8_t>> images;
  external_buffers(asset, document, output, options, resources);
  external_images(asset, document, options, images, resources, diag);
  std::vector<std::filesystem::path> created;
  bool ok = write_resources(resources, folder, options, diag, created);
  const bool addressed = static_cast<bool>(options.content_digest);
  // Read before the JSON is replaced: its files stay for a reader that has just opened it.
  const auto previous = addressed ? names_referenced_by(output) : std::set<std::string>{};
  // The JSON last: whoever sees it finds its resources already in place.
  const std::string text = document_text(document);
  if (written_json != nullptr) *written_json = text;
  std::string why;
  if (ok && !put_file(output, text, options, why)) {
    diag.error(codes::WRITE_FAILED, "", "cannot write " + output.string() + ": " + why);
    ok = false;
  }
  if (addressed) tidy_content_addressed(folder, ok, resources, previous, created);
  return ok;
}

// The BIN chunk of a GLB as pieces in file order: the asset's buffers and embedded images where
// they already lie, each started on a 4-byte boundary (zero bytes between), as glTF requires of
// accessor data. Nothing is copied: a 24 MB model is written without two fresh 24 MB copies
// (the concatenated chunk, then the whole container), whose page faults and copying were a third
// of a whole `rdtf convert --glb` process.
class BinChunk {
 public:
  // Appends bytes (which must outlive this object) and returns their offset in the chunk.
  std::size_t append(std::span<const std::uint8_t> bytes) {
    pad_to(4);
    const std::size_t offset = size_;
    pieces_.push_back(bytes);
    size_ += bytes.size();
    return offset;
  }
  // The chunk's padding to its 4-byte end (GLB section 4.4.3).
  void pad_to(std::size_t alignment) {
    const std::size_t padding = (alignment - size_ % alignment) % alignment;
    if (padding == 0) return;
    pieces_.emplace_back(kZeros, padding);
    size_ += padding;
  }
  std::size_t size() const { return size_; }
  const std::vector<std::span<const std::uint8_t>>& pieces() const { return pieces_; }

 private:
  static constexpr std::uint8_t kZeros[4] = {};
  std::vector<std::span<const std::uint8_t>> pieces_;
  std::size_t size_ = 0;
};

void append_u32(std::vector<std::uint8_t>& out, std::uint32_t value) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<std::uint8_t>(value >> shift));
}

// The GLB header and JSON chunk, and the BIN chunk's header when there is one: what make_glb(json,
// bin) writes before the bin bytes, for a bin of bin_size bytes (a multiple of 4).
std::vector<std::uint8_t> glb_head(std::string_view json, std::size_t bin_size) {
  constexpr std::uint32_t kMagic = 0x46546C67;      // "glTF"
  constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
  constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
  const std::size_t json_padded = (json.size() + 3) & ~std::size_t{3};
  const std::size_t total = 12 + 8 + json_padded + (bin_size == 0 ? 0 : 8 + bin_size);
  std::vector<std::uint8_t> head;
  head.reserve(12 + 8 + json_padded + 8);
  append_u32(head, kMagic);
  append_u32(head, 2);
  append_u32(head, static_cast<std::uint32_t>(total));
  append_u32(head, static_cast<std::uint32_t>(json_padded));
  append_u32(head, kChunkJson);
  head.insert(head.end(), json.begin(), json.end());
  head.resize(head.size() + (json_padded - json.size()), ' ');
  if (bin_size != 0) {
    append_u32(head, static_cast<std::uint32_t>(bin_size));
    append_u32(head, kChunkBin);
  }
  return head;
}

bool write_glb(const GltfAsset& asset, const std::filesystem::path& output, const WriteOptions& options, Diagnostics& diag,
               std::string* written_json) {
  Json document = asset.document;
  BinChunk bin;
  std::vector<std::size_t> offsets;
  for (const auto& buffer : asset.buffers) offsets.push_back(bin.append(buffer));
  if (document.contains("bufferViews")) {
    for (Json& view : document["bufferViews"]) {
      const auto buffer = view["buffer"].get<std::size_t>();
      view["byteOffset"] = view.value("byteOffset", std::uint64_t{0}) + offsets[buffer];
      view["buffer"] = 0;
    }
  }
  std::deque<std::vector<std::uint8_t>> image_bytes;  // A deque: appending never moves the others.
  if (document.contains("images")) {
    Json& images = document["images"];
    for (std::size_t i = 0; i < images.size(); ++i) {
      if (!images[i].contains("uri")) continue;
      const std::string uri = images[i]["uri"].get<std::string>();
      if (internal::is_data_uri(uri)) continue;
      std::filesystem::path source;
      auto bytes = read_image(asset, uri, source);
      if (!bytes) {
        diag.warning(codes::IMAGE_NOT_EMBEDDED, json_pointer("/images", i) + "/uri",
                     "image '" + uri + "' could not be read; the output keeps its URI");
        continue;
      }
      const auto sniffed = sniffed_mime_type(*bytes);
      const std::string declared = images[i].contains("mimeType") && images[i]["mimeType"].is_string()
                                       ? images[i]["mimeType"].get<std::string>()
                                       : std::string();
      if (!sniffed && declared.empty()) {
        diag.warning(codes::IMAGE_NOT_EMBEDDED, json_pointer("/images", i) + "/uri",
                     "image '" + uri + "' is no PNG, JPEG, WebP or KTX2 by its bytes, and declares no mimeType; an "
                     "image in a GLB must say what it holds, so the output keeps its URI");
        continue;
      }
      const std::vector<std::uint8_t>& kept = image_bytes.emplace_back(std::move(*bytes));
      const std::size_t offset = bin.append(kept);
      document["bufferViews"].push_back(Json{{"buffer", 0}, {"byteOffset", offset}, {"byteLength", kept.size()}});
      images[i].erase("uri");
      images[i]["bufferView"] = document["bufferViews"].size() - 1;
      // A declared type is the author's (a wrong one the validator already refuses in the input).
      if (declared.empty()) images[i]["mimeType"] = *sniffed;
    }
  }
  const std::size_t bin_bytes = bin.size();  // The buffer's byteLength: before the chunk's padding.
  if (bin_bytes == 0) {
    document.erase("buffers");
  } else {
    document["buffers"] = Json::array({Json{{"byteLength", bin_bytes}}});
  }
  bin.pad_to(4);
  const std::string json = document.dump();
  if (written_json != nullptr) *written_json = json;
  const auto head = glb_head(json, bin.size());
  std::vector<std::span<const std::uint8_t>> pieces{head};
  pieces.insert(pieces.end(), bin.pieces().begin(), bin.pieces().end());
  std::string why;
  if (!put_file(output, pieces, options, why)) {
    diag.error(codes::WRITE_FAILED, "", "cannot write " + output.string() + ": " + why);
    return false;
  }
  return true;
}

}  // namespace

std::string document_text(const Json& document) { return document.dump(2) + "\n"; }

bool write_rdtf(const GltfAsset& asset, const std::filesystem::path& output, const WriteOptions& options,
                Diagnostics& diag, std::string* written_json) {
  diag.set_file(output.string());
  return options.format == OutputFormat::kGlb ? write_glb(asset, output, options, diag, written_json)
                                              : write_gltf(asset, output, options, diag, written_json);
}

bool write_rdtf(const GltfAsset& asset, const std::filesystem::path& output, OutputFormat format,
                Diagnostics& diag, std::string* written_json) {
  WriteOptions options;
  options.format = format;
  return write_rdtf(asset, output, options, diag, written_json);
}

}  // namespace rdtf
