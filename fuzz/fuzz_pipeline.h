// The entry points the fuzz targets drive, header-only so that the regression tests
// (tests/fuzz_regressions/) feed their reproducers through exactly the same code: run_target at
// the end of this file is the whole of what a target does with one input.
//
// Each run returns what happened; `contract_violation` says what broke the project's rule for bad
// input ("a clear error, never a crash"): a refusal without an error diagnostic, a diagnostic
// without a code, diagnostics or a robot summary that cannot be written as JSON (what
// `rdtf validate --json`, `rdtf inspect --json` and the daemon print), or a converted model whose
// output no longer loads.
#pragma once

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "rdtf/convert.h"
#include "rdtf/glb.h"
#include "rdtf/gltf.h"
#include "rdtf/summary.h"
#include "rdtf/urdf.h"
#include "rdtf/write.h"

#include "decoder_models.h"

namespace rdtf::fuzz {

struct RunResult {
  bool succeeded = false;
  Diagnostics diag;
  std::string output;   // The RDTF JSON text (or the GLB JSON chunk) when it succeeded.
  std::string summary;  // robot_summary as JSON text, for a converted robot.
};

inline std::vector<std::uint8_t> to_bytes(const std::string& text) {
  return {text.begin(), text.end()};
}

inline std::vector<std::uint8_t> read_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// Empty when the run kept the contract; else what went wrong.
inline std::string contract_violation(const RunResult& run) {
  for (const Diagnostic& d : run.diag.all()) {
    if (d.code.empty()) return "a diagnostic without a code: " + format(d);
  }
  if (!run.succeeded && !run.diag.has_errors()) return "refused without an error diagnostic";
  if (run.diag.contains("FUZZ_SUMMARY_NOT_JSON")) return "the robot summary cannot be written as JSON";
  try {
    diagnostics_json(run.diag).dump();
  } catch (const Json::exception& error) {
    return std::string("the diagnostics cannot be written as JSON: ") + error.what();
  }
  return {};
}

// `rdtf inspect --json` and the plain table: what a reader of a converted robot gets.
inline std::string summary_text(const Conversion& conversion, Diagnostics& diag) {
  robot_table(conversion.robot, diag);
  try {
    return robot_summary(conversion.robot, conversion.asset.document, diag).dump();
  } catch (const Json::exception& error) {
    diag.error("FUZZ_SUMMARY_NOT_JSON", "", error.what());
    return {};
  }
}

// Load (confined to `folder`), convert, and write the RDTF JSON in memory: the pipeline of
// `rdtf convert`, minus the files.
inline RunResult convert_bytes(const std::vector<std::uint8_t>& bytes,
                               const std::filesystem::path& folder, Conversion* kept = nullptr) {
  RunResult run;
  const char* name = looks_like_glb(bytes) ? "fuzz.glb" : "fuzz.gltf";
  const ConvertOptions options;
  auto asset = load_gltf_from_memory(bytes, folder / name, folder, options.limits, run.diag);
  if (!asset) return run;
  auto conversion = convert(std::move(*asset), options, run.diag);
  if (!conversion) return run;
  run.output = document_text(conversion->asset.document);
  run.summary = summary_text(*conversion, run.diag);
  run.succeeded = true;
  if (kept != nullptr) *kept = std::move(*conversion);
  return run;
}

// The output of a conversion (`run`, `conversion`) loaded and converted again: what rdtf writes
// must be a model rdtf reads (a GLB's buffer travels in the binary chunk, as write_rdtf puts it).
// Empty when it does, else why not.
inline std::string reconvert(const RunResult& run, const Conversion& conversion,
                             const std::filesystem::path& folder) {
  std::vector<std::uint8_t> again = to_bytes(run.output);
  if (conversion.asset.binary) {
    const auto& buffers = conversion.asset.buffers;
    const bool first_in_bin = !buffers.empty() && !conversion.asset.document["buffers"][0].contains("uri");
    again = make_glb(run.output, first_in_bin ? std::span<const std::uint8_t>(buffers[0])
                                              : std::span<const std::uint8_t>());
  }
  RunResult second = convert_bytes(again, folder);
  if (second.succeeded) return {};
  std::string failure = "the converted model does not convert again:";
  for (const Diagnostic& d : second.diag.all()) failure += "\n  " + format(d);
  return failure;
}

// convert_bytes, then reconvert.
inline RunResult convert_and_reconvert(const std::vector<std::uint8_t>& bytes,
                                       const std::filesystem::path& folder,
                                       std::string& reconvert_failure) {
  Conversion conversion;
  RunResult run = convert_bytes(bytes, folder, &conversion);
  if (run.succeeded) reconvert_failure = reconvert(run, conversion, folder);
  return run;
}

// The GLB container alone. A container that parses must survive make_glb -> parse_glb unchanged.
inline RunResult parse_glb_bytes(const std::vector<std::uint8_t>& bytes, std::string& roundtrip_failure) {
  RunResult run;
  const auto chunks = parse_glb(bytes, run.diag);
  if (!chunks) return run;
  run.succeeded = true;
  run.output.assign(chunks->json);
  const std::span<const std::uint8_t> bin = chunks->bin.value_or(std::span<const std::uint8_t>());
  const auto rebuilt = make_glb(chunks->json, bin);
  Diagnostics diag;
  const auto again = parse_glb(rebuilt, diag);
  if (!again || again->json != chunks->json ||
      (bin.empty() ? again->bin.has_value()
                   : !again->bin || !std::equal(bin.begin(), bin.end(), again->bin->begin(),
                                                again->bin->end()))) {
    roundtrip_failure = "make_glb of a parsed GLB does not parse back to the same chunks";
  }
  return run;
}

// extras.RDTF and node extras, read by typing, completion, the robot and the extras writer: the
// fuzzed JSON goes into a real model (`base`, a glTF JSON with its buffers in `folder`). An
// object input becomes extras.RDTF, except its "nodeExtras" array, whose entries become the
// extras of the nodes in order; any other value becomes extras.RDTF as it is.
inline std::optional<std::vector<std::uint8_t>> model_with_extras(const Json& base,
                                                                  const std::string& extras_text) {
  Json extras;
  try {
    extras = Json::parse(extras_text);
  } catch (const Json::exception&) {
    return std::nullopt;  // Not JSON: nothing to put in the model (the loaders fuzz the parser).
  }
  Json document = base;
  if (extras.is_object() && extras.contains("nodeExtras")) {
    const Json node_extras = extras["nodeExtras"];
    extras.erase("nodeExtras");
    if (node_extras.is_array()) {
      Json& nodes = document["nodes"];
      for (std::size_t i = 0; i < node_extras.size() && i < nodes.size(); ++i) {
        nodes[i]["extras"] = node_extras[i];
      }
    }
  }
  document["extras"]["RDTF"] = std::move(extras);
  return to_bytes(document.dump());
}

// URDF import from a file: `dir/fuzz.urdf` holds the bytes (import_urdf takes a path).
inline RunResult import_urdf_bytes(const std::vector<std::uint8_t>& bytes,
                                   const std::filesystem::path& dir, Conversion* kept = nullptr) {
  RunResult run;
  const std::filesystem::path urdf = dir / "fuzz.urdf";
  {
    std::ofstream out(urdf, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  }
  const UrdfImportOptions options;
  auto conversion = import_urdf(urdf, options, run.diag);
  if (!conversion) return run;
  run.output = document_text(conversion->asset.document);
  run.summary = summary_text(*conversion, run.diag);
  run.succeeded = true;
  if (kept != nullptr) *kept = std::move(*conversion);
  return run;
}

// A closed tetrahedron (outward winding), the mesh a URDF seed refers to.
inline constexpr const char* kTetraStl =
    "solid tetra\n"
    "facet normal 0 0 -1 outer loop vertex 0 0 0 vertex 0 1 0 vertex 1 0 0 endloop endfacet\n"
    "facet normal 0 -1 0 outer loop vertex 0 0 0 vertex 1 0 0 vertex 0 0 1 endloop endfacet\n"
    "facet normal -1 0 0 outer loop vertex 0 0 0 vertex 0 0 1 vertex 0 1 0 endloop endfacet\n"
    "facet normal 1 1 1 outer loop vertex 1 0 0 vertex 0 1 0 vertex 0 0 1 endloop endfacet\n"
    "endsolid tetra\n";

// Where a target's inputs are loaded: a folder holding copies of every external buffer of the
// test models (tests/data/blender and tests/data/gltf-validator, whose .bin names are all
// distinct), so that seeds made from them load, and tetra.stl for URDF meshes; every URI stays
// confined to it. `extras_base` is the model the extras target puts its input into.
struct Workspace {
  std::filesystem::path folder;
  Json extras_base;
};

inline Workspace make_workspace(const std::filesystem::path& folder,
                                const std::filesystem::path& data_dir) {
  namespace fs = std::filesystem;
  fs::create_directories(folder);
  for (const char* models : {"blender", "gltf-validator"}) {
    if (!fs::is_directory(data_dir / models)) continue;
    for (const auto& entry : fs::recursive_directory_iterator(data_dir / models)) {
      if (entry.is_regular_file() && entry.path().extension() == ".bin") {
        fs::copy_file(entry.path(), folder / entry.path().filename(),
                      fs::copy_options::overwrite_existing);
      }
    }
  }
  std::ofstream(folder / "tetra.stl") << kTetraStl;
  const auto arm3 = read_bytes(data_dir / "blender/arm3.gltf");
  return {folder, Json::parse(arm3.begin(), arm3.end())};
}

// The targets, as fuzz/<name>_fuzzer.cc and the folders of tests/data/fuzz-regressions name them.
inline constexpr std::string_view kTargets[] = {"convert_gltf", "convert_glb", "glb", "extras",
                                                "urdf_import", "draco", "meshopt"};

struct TargetRun {
  bool not_for_target = false;  // An input this target leaves alone (libFuzzer: return -1).
  RunResult run;
  std::string violation;        // What broke the contract or a round trip; empty when kept.
};

// What the fuzz target `target` does with one input:
//   convert_gltf  JSON bytes through the whole convert pipeline, output converted again
//   convert_glb   the same from GLB bytes (the output's buffer goes in the binary chunk)
//   glb           the GLB container parser, with make_glb as its inverse
//   extras        the input (JSON) as extras.RDTF / node extras of blender/arm3, then converted
//   urdf_import   the input as a URDF file, imported and converted; the output converted again
//   draco         a Draco bitstream as the one mesh of a GLB (decoder_models.h), converted
//   meshopt       meshopt vertex and index streams as the one mesh of a GLB, converted
inline TargetRun run_target(std::string_view target, const std::vector<std::uint8_t>& bytes,
                            const Workspace& workspace) {
  TargetRun result;
  std::string failure;
  if (target == "convert_gltf" || target == "convert_glb") {
    if (looks_like_glb(bytes) != (target == "convert_glb")) {
      result.not_for_target = true;  // The other convert target's input: keep the corpora apart.
      return result;
    }
    result.run = convert_and_reconvert(bytes, workspace.folder, failure);
  } else if (target == "glb") {
    result.run = parse_glb_bytes(bytes, failure);
  } else if (target == "extras") {
    const auto model =
        model_with_extras(workspace.extras_base, std::string(bytes.begin(), bytes.end()));
    if (!model) {
      result.not_for_target = true;
      return result;
    }
    result.run = convert_and_reconvert(*model, workspace.folder, failure);
  } else if (target == "urdf_import") {
    Conversion conversion;
    result.run = import_urdf_bytes(bytes, workspace.folder, &conversion);
    if (result.run.succeeded) failure = reconvert(result.run, conversion, workspace.folder);
  } else if (target == "draco" || target == "meshopt") {
    const auto model = target == "draco" ? draco_model(bytes) : meshopt_model(bytes);
    if (!model) {
      result.not_for_target = true;
      return result;
    }
    Conversion conversion;
    result.run = convert_bytes(*model, workspace.folder, &conversion);
    if (result.run.succeeded) {
      RunResult again = convert_bytes(merged_glb(result.run.output, conversion.asset), workspace.folder);
      if (!again.succeeded) {
        failure = "the converted model does not convert again:";
        for (const Diagnostic& d : again.diag.all()) failure += "\n  " + format(d);
      }
    }
  } else {
    result.violation = "no fuzz target named '" + std::string(target) + "'";
    return result;
  }
  result.violation = contract_violation(result.run);
  if (result.violation.empty()) result.violation = failure;
  return result;
}

}  // namespace rdtf::fuzz
