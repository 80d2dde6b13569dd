// Writing an RDTF document as .gltf or .glb, complete where it is written.
#pragma once

#include <filesystem>

#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf {

enum class OutputFormat { kGltf, kGlb };

// .gltf: the JSON, and every external buffer and image copied beside it under the same relative
// URI (a GLB's binary chunk becomes "<name>.bin"); data: URIs stay embedded.
// .glb: every buffer merged into the binary chunk and every external image embedded through a
// buffer view. Each file is written atomically. False (and errors) if anything could not be
// written; files already written stay valid on their own.
// `written_json`, when given, receives the JSON text as written (for .glb, the JSON chunk).
bool write_rdtf(const GltfAsset& asset, const std::filesystem::path& output, OutputFormat format,
                Diagnostics& diag, std::string* written_json = nullptr);

// The JSON text of the document as rdtf writes it (2-space indent, keys in input order).
std::string document_text(const Json& document);

}  // namespace rdtf
