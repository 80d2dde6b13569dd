// The catalogue of diagnostic codes: core/include/rdtf/diagnostic_codes.h, docs/diagnostics.md and
// the sources agree. A code emitted but not catalogued, catalogued but never emitted, or documented
// with other severities fails here.
#include "rdtf/diagnostic_codes.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <regex>
#include <set>
#include <string>

#include "support/test_support.h"

namespace rdtf {
namespace {

namespace fs = std::filesystem;

fs::path source_dir() { return testing::data_dir() / ".." / ".."; }

std::string severity_text(unsigned severities) {
  std::string text;
  for (const auto& [bit, name] : {std::pair{kSeverityError, "error"}, std::pair{kSeverityWarning, "warning"},
                                  std::pair{kSeverityInfo, "info"}}) {
    if ((severities & bit) != 0) text += (text.empty() ? "" : " or ") + std::string(name);
  }
  return text;
}

// Upper-case literals in the sources that are not diagnostic codes: glTF's names (attributes,
// accessor types, primitive modes), channel kinds, environment variables, verdicts, option types.
const std::set<std::string>& not_codes() {
  static const std::set<std::string> names{
      "BLEND", "COLOR", "JOINTS", "JOINTS_", "JOINTS_0", "NORMAL", "POSITION", "TANGENT", "TEXCOORD", "TEXCOORD_0",
      "WEIGHTS", "WEIGHTS_", "TEXCOORD_", "SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4", "POINTS", "LINES",
      "LINE_LOOP", "LINE_STRIP", "JSON", "RDTF", "DESCRIPTION", "DESCRIPTION_CHUNK", "URDF_CHUNK", "INERTIA",
      "VALIDATION", "ERROR", "REMOVED", "SAVING", "STATUS", "REQUEST", "JOINT_STATE", "JOINT_COMMAND", "LINK_STATE",
      "MANIFEST", "DELTA", "URDF", "BLOB", "BLOB_REQUEST", "BLOB_CHUNK", "BLOB_UNAVAILABLE", "HOME", "XDG_DATA_HOME",
      "XDG_STATE_HOME", "LCM_DEFAULT_URL", "NOTIFY_SOCKET", "RDTFD_TEST_INOTIFY_LIMIT_FILE", "PASS", "FAIL", "FAILED", "TEXT",
      "NUMBER",
      // Mesh file formats a URDF names (core/urdf/import.cc).
      "COLLADA", "OBJ",
      // COLLADA's transparency mode (core/urdf/mesh_file.cc).
      "RGB_ZERO",
      // EXT_meshopt_compression's modes and filters, EXT_mesh_gpu_instancing's attributes.
      "ATTRIBUTES", "TRIANGLES", "INDICES", "NONE", "OCTAHEDRAL", "QUATERNION", "EXPONENTIAL",
      "TRANSLATION", "ROTATION", "SCALE",
      // A material's alpha modes (BLEND is above).
      "OPAQUE", "MASK",
      // Animation samplers' interpolations.
      "LINEAR", "STEP", "CUBICSPLINE",
      // Accessors' component types, as messages name them.
      "BYTE", "UNSIGNED_BYTE", "SHORT", "UNSIGNED_SHORT", "UNSIGNED_INT", "FLOAT"};
  return names;
}

// Every upper-case string literal (4 characters or more) and every codes::NAME in the C++ sources
// of core/, daemon/ and clients/, but the catalogue itself, with a file that has it.
std::map<std::string, std::string> codes_in_sources() {
  const std::regex literal(R"re("([A-Z][A-Z0-9_]{3,})"|\bcodes::([A-Z][A-Z0-9_]+))re");
  std::map<std::string, std::string> found;
  for (const char* folder : {"core", "daemon", "clients"}) {
    for (const auto& entry : fs::recursive_directory_iterator(source_dir() / folder)) {
      const auto extension = entry.path().extension();
      if (!entry.is_regular_file() || (extension != ".cc" && extension != ".h")) continue;
      if (entry.path().filename() == "diagnostic_codes.h") continue;
      const std::string text = testing::read_file(entry.path());
      for (std::sregex_iterator it(text.begin(), text.end(), literal), end; it != end; ++it) {
        const std::string name = (*it)[1].matched ? (*it)[1].str() : (*it)[2].str();
        found.emplace(name, entry.path().lexically_relative(source_dir()).string());
      }
    }
  }
  return found;
}

TEST(DiagnosticCodes, EveryCodeInTheSourcesIsCataloguedAndEveryCatalogedOneIsUsed) {
  const auto found = codes_in_sources();
  for (const auto& [name, file] : found) {
    if (not_codes().count(name) != 0) continue;
    EXPECT_NE(find_diagnostic_code(name), nullptr)
        << name << " (in " << file << ") is no catalogued code: add it to core/include/rdtf/diagnostic_codes.h "
        << "and docs/diagnostics.md, or, if it is no diagnostic code, to not_codes() here";
  }
  for (const DiagnosticCode& code : diagnostic_codes()) {
    EXPECT_EQ(found.count(std::string(code.code)), 1u) << code.code << " is catalogued but never used in the sources";
    EXPECT_EQ(not_codes().count(std::string(code.code)), 0u) << code.code;
  }
}

TEST(DiagnosticCodes, TheDocsListEveryCodeOnceWithItsSeverities) {
  const std::string text = testing::read_file(source_dir() / "docs" / "diagnostics.md");
  const std::regex row(R"(\n\| `([A-Z][A-Z0-9_]+)` \| ([a-z ]+) \| [^|\n]+ \| [^\n]+ \|)");
  std::map<std::string, std::string> documented;
  for (std::sregex_iterator it(text.begin(), text.end(), row), end; it != end; ++it) {
    EXPECT_TRUE(documented.emplace((*it)[1].str(), (*it)[2].str()).second) << (*it)[1] << " is documented twice";
  }
  std::set<std::string> names;
  for (const DiagnosticCode& code : diagnostic_codes()) {
    const std::string name(code.code);
    EXPECT_TRUE(names.insert(name).second) << name << " is catalogued twice";
    const auto it = documented.find(name);
    if (it == documented.end()) {
      ADD_FAILURE() << name << " is not in docs/diagnostics.md (a row: | `" << name << "` | "
                    << severity_text(code.severities) << " | meaning | fix |)";
      continue;
    }
    EXPECT_EQ(it->second, severity_text(code.severities)) << name << "'s severity in docs/diagnostics.md";
  }
  for (const auto& [name, severity] : documented) {
    EXPECT_NE(find_diagnostic_code(name), nullptr) << name << " is documented but not catalogued";
  }
}

TEST(DiagnosticCodes, ConstantsAreTheirNames) {
  EXPECT_STREQ(codes::MESH_OPEN, "MESH_OPEN");
  EXPECT_STREQ(codes::URDF_INVALID_NUMBER, "URDF_INVALID_NUMBER");
  ASSERT_NE(find_diagnostic_code("SIM_JOINT_MISALIGNMENT"), nullptr);
  EXPECT_EQ(find_diagnostic_code("SIM_JOINT_MISALIGNMENT")->severities, unsigned{kSeverityError | kSeverityWarning});
  EXPECT_EQ(find_diagnostic_code("NO_SUCH_CODE"), nullptr);
}

}  // namespace
}  // namespace rdtf
