// Writing an RDTF document as .gltf or .glb, complete where it is written.
#pragma once

#include <filesystem>
#include <string>

#include "rdtf/atomic_file.h"
#include "rdtf/diagnostics.h"
#include "rdtf/gltf.h"

namespace rdtf {

enum class OutputFormat { kGltf, kGlb };

struct WriteOptions {
  OutputFormat format = OutputFormat::kGltf;
  // How the files beside a .gltf are named (a .glb has none).
  // Empty (`rdtf convert`): buffers after the output, "<stem>.bin", "<stem>_1.bin", ... (so that
  // outputs of models whose buffers share a name do not collide in one folder); images under
  // their relative URIs. Either overwrites what is there.
  // Given (rdtfd): content-addressed, "<stem>.<16 hex digits of the digest>.<ext>" directly in the
  // output's folder (atomic_file.h), written before the JSON, whose rename commits them all. Once
  // the JSON is in place, every content-addressed file of the folder that neither it nor the JSON
  // it replaced refers to is removed: a reader that opened the previous JSON a moment ago still
  // finds its files. The folder is taken to hold this one output (the daemon's per-model folder).
  ContentDigest content_digest;
  // Set when `output` lies in a StagedOutput's folder whose commit will move it into this folder
  // (rdtfd, `rdtf convert`): every file is written with write_staged_file (commit syncs what it
  // moves), and a file beside the JSON that this folder already holds with the very same bytes is
  // not written at all, so a save that changed a colour does not write, sync and rename the
  // model's unchanged buffers again. The JSON (or .glb) is always written: its rename commits.
  std::filesystem::path staged_for;
};

// .gltf: the JSON, and every external buffer and image copied beside it (named as
// WriteOptions says; data: URIs stay embedded).
// .glb: every buffer merged into the binary chunk and every external image embedded through a
// buffer view. Each file is written atomically, the JSON last. False (and errors) if anything
// could not be written; files already written stay valid on their own, and with content-addressed
// names no file this call created is left behind.
// `written_json`, when given, receives the JSON text as written (for .glb, the JSON chunk).
bool write_rdtf(const GltfAsset& asset, const std::filesystem::path& output, const WriteOptions& options,
                Diagnostics& diag, std::string* written_json = nullptr);
bool write_rdtf(const GltfAsset& asset, const std::filesystem::path& output, OutputFormat format,
                Diagnostics& diag, std::string* written_json = nullptr);

// The JSON text of the document as rdtf writes it (2-space indent, keys in input order).
std::string document_text(const Json& document);

}  // namespace rdtf
