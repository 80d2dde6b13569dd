// One diagnostic in each of its forms: the core value, its JSON (CLI and rdtf-echo alike), its LCM
// diagnostic_t and back; a URDF diagnostic's line in a field of its own; and the length fields of
// LCM messages set by lcmtypes/counts.h.
#include <gtest/gtest.h>

#include <rdtf/model_error_t.hpp>

#include "counts.h"
#include "diagnostic_message.h"
#include "message_json.h"
#include "publisher.h"
#include "rdtf/diagnostic_codes.h"
#include "rdtf/diagnostics_json.h"
#include "rdtf/utf8.h"
#include "support/test_support.h"

namespace rdtf {
namespace {

Diagnostic urdf_finding() {
  Diagnostics diag("arm.urdf");
  diag.error_at_line(codes::URDF_INVALID_NUMBER, "/robot/joint[@name='j']/limit/@lower", 5,
                     "<limit lower=\"abc\">: 'abc' is not a number");
  return diag.all().front();
}

TEST(DiagnosticForms, AUrdfFindingHasItsLineInAFieldAndInItsMessage) {
  const Diagnostic d = urdf_finding();
  EXPECT_EQ(d.line, 5);
  EXPECT_EQ(d.pointer, "/robot/joint[@name='j']/limit/@lower");
  EXPECT_EQ(d.message, "line 5: <limit lower=\"abc\">: 'abc' is not a number");
  EXPECT_FALSE(d.byte_offset);
}

TEST(DiagnosticForms, FirstErrorSkipsWarningsAndIsNothingWithoutErrors) {
  Diagnostics diag("a.glb");
  diag.warning(codes::MESH_OPEN, "/nodes/2", "open");
  EXPECT_EQ(diag.first_error(), nullptr);
  diag.error(codes::ACCESSOR_TOO_LONG, "/accessors/1", "first");
  diag.error(codes::ACCESSOR_TOO_LONG, "/accessors/2", "second");
  ASSERT_NE(diag.first_error(), nullptr);
  EXPECT_EQ(diag.first_error()->pointer, "/accessors/1");
  EXPECT_EQ(diag.first_error()->message, "first");
}

TEST(DiagnosticForms, TerminalTextEscapesControlsBackslashesAndBytesThatAreNotUtf8) {
  EXPECT_EQ(escape_for_terminal("a\nb\r\x1b[31m\tc\\ \xc3\xa9\xff\xc0\xaf\x7f"),
            "a\\nb\\r\\x1b[31m\\tc\\\\ \xc3\xa9\\xff\\xc0\\xaf\\x7f");
  EXPECT_EQ(escape_for_terminal(std::string("n\0x", 3)), "n\\x00x");
  EXPECT_EQ(escape_for_terminal("\xf0\x9f\xa4\x96 plain"), "\xf0\x9f\xa4\x96 plain");  // U+1F916, kept
  EXPECT_EQ(escape_for_terminal("cut \xe2\x82"), "cut \\xe2\\x82");  // A sequence cut short.
}

// Whether a text is UTF-8 as a whole: what decides how rdtfd stores a file name (json_bytes.h).
TEST(DiagnosticForms, IsUtf8JudgesTheWholeText) {
  EXPECT_TRUE(is_utf8(""));
  EXPECT_TRUE(is_utf8("/models/\xC3\xBC-arm.gltf"));           // ü
  EXPECT_FALSE(is_utf8("/models/a\xFF.gltf"));
  EXPECT_FALSE(is_utf8("\xC3"));                                 // cut short
  EXPECT_FALSE(is_utf8("\xED\xA0\x80"));                        // a surrogate
  EXPECT_FALSE(is_utf8("\xC0\xAF"));                             // overlong '/'
}

TEST(DiagnosticForms, TerminalTextEscapesC1ControlsAndBidirectionalFormatting) {
  // U+009B (CSI as one byte pair), U+0085 (next line): C1 controls.
  EXPECT_EQ(escape_for_terminal("a\xc2\x9b""31mb\xc2\x85""c"), "a\\u009b31mb\\u0085c");
  // "link_\u202Egnp.exe" shows as "link_exe.png" unescaped: right-to-left override.
  EXPECT_EQ(escape_for_terminal("link_\xe2\x80\xae""gnp.exe"), "link_\\u202egnp.exe");
  // Isolates, marks, and the line and paragraph separators.
  EXPECT_EQ(escape_for_terminal("\xe2\x81\xa6x\xe2\x81\xa9\xe2\x80\x8f\xd8\x9c\xe2\x80\xa8\xe2\x80\xa9"),
            "\\u2066x\\u2069\\u200f\\u061c\\u2028\\u2029");
  // Their neighbours are text: U+00A0, U+00E9, U+2010 (hyphen), U+2030 (per mille), U+2070.
  const std::string kept = "\xc2\xa0\xc3\xa9\xe2\x80\x90\xe2\x80\xb0\xe2\x81\xb0";
  EXPECT_EQ(escape_for_terminal(kept), kept);
}

TEST(DiagnosticForms, JsonHasLineAndByteOffsetOnlyWhenGiven) {
  const Json urdf = diagnostic_json(urdf_finding());
  EXPECT_EQ(urdf.dump(), R"({"severity":"error","code":"URDF_INVALID_NUMBER","file":"arm.urdf",)"
                         R"("pointer":"/robot/joint[@name='j']/limit/@lower","line":5,)"
                         R"("message":"line 5: <limit lower=\"abc\">: 'abc' is not a number"})");
  Diagnostics glb("a.glb");
  glb.error_at_offset(codes::GLB_LENGTH_MISMATCH, 8, "header says 100 bytes but the file has 90");
  glb.warning(codes::MESH_OPEN, "/nodes/2", "open");
  const Json list = diagnostics_json(glb);
  ASSERT_EQ(list.size(), 2u);
  EXPECT_EQ(list[0]["byteOffset"], 8);
  EXPECT_FALSE(list[0].contains("line"));
  EXPECT_FALSE(list[1].contains("byteOffset"));
  EXPECT_FALSE(list[1].contains("line"));
  EXPECT_EQ(list[1]["severity"], "warning");
}

TEST(DiagnosticForms, LcmMessageCarriesEveryFieldBothWays) {
  const Diagnostic d = urdf_finding();
  const diagnostic_t m = to_message(d);
  EXPECT_EQ(m.severity, diagnostic_t::ERROR);
  EXPECT_EQ(m.code, "URDF_INVALID_NUMBER");
  EXPECT_EQ(m.file, "arm.urdf");
  EXPECT_EQ(m.pointer, d.pointer);
  EXPECT_EQ(m.line, 5);
  EXPECT_EQ(m.byte_offset, -1);
  EXPECT_EQ(m.message, d.message);
  const Diagnostic back = from_message(m);
  EXPECT_EQ(diagnostic_json(back), diagnostic_json(d));
  Diagnostics glb("a.glb");
  glb.error_at_offset(codes::GLB_CHUNK_TOO_BIG, 20, "chunk 1 length 4000 runs past the end of the file");
  const diagnostic_t at_offset = to_message(glb.all().front());
  EXPECT_EQ(at_offset.byte_offset, 20);
  EXPECT_EQ(at_offset.line, 0);
  EXPECT_EQ(diagnostic_json(from_message(at_offset)), diagnostic_json(glb.all().front()));
  const diagnostic_t own = to_message(Severity::kInfo, codes::DIAGNOSTICS_TRUNCATED, "3 more");
  EXPECT_EQ(own.severity, diagnostic_t::INFO);
  EXPECT_EQ(own.line, 0);
  EXPECT_EQ(own.byte_offset, -1);
  EXPECT_EQ(own.file, "");
}

// A NUL quoted from a model (JSON allows \u0000 in names and URIs) would end an LCM string early
// and leave the message undecodable: it goes as the four characters \x00, every other byte as is.
TEST(DiagnosticForms, LcmMessageCarriesANulAsBackslashX00) {
  Diagnostics diag("a.gltf");
  using namespace std::string_literals;
  diag.error("URI_REFUSED", "/nodes/0/extras/a\0b"s, "'a\0\0b\xff\\x00'"s);
  const diagnostic_t m = to_message(diag.all().front());
  EXPECT_EQ(m.pointer, "/nodes/0/extras/a\\x00b");
  EXPECT_EQ(m.message, "'a\\x00\\x00b\xff\\x00'");
  EXPECT_EQ(lcm_text("no nul"), "no nul");
  EXPECT_EQ(lcm_text(std::string("\0", 1)), "\\x00");
}

// rdtf-echo prints a received diagnostic as the CLI prints it.
TEST(DiagnosticForms, EchoPrintsTheCliJson) {
  model_error_t error{};
  error.model_id = "arm";
  error.diagnostics = {to_message(urdf_finding())};
  set_counts(error);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(error.getEncodedSize()));
  error.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const auto json = clients::message_to_json(bytes.data(), static_cast<std::uint32_t>(bytes.size()));
  ASSERT_TRUE(json);
  ASSERT_EQ((*json)["diagnostics"].size(), 1u);
  EXPECT_EQ((*json)["diagnostics"][0].dump(), diagnostic_json(urdf_finding()).dump());
}

TEST(DiagnosticForms, CountsFollowTheArrays) {
  model_error_t error{};
  error.num_diagnostics = 7;  // Stale: set_counts makes it the vector's length.
  error.diagnostics = {to_message(Severity::kError, codes::INTERNAL_ERROR, "a"),
                       to_message(Severity::kError, codes::INTERNAL_ERROR, "b")};
  set_counts(error);
  EXPECT_EQ(error.num_diagnostics, 2);
  link_state_t links{};
  links.name = {"a", "b", "c"};
  links.position.assign(3, {});
  links.orientation.assign(3, {});
  links.linear_velocity.assign(3, {});
  links.angular_velocity.assign(3, {});
  set_counts(links);
  EXPECT_EQ(links.num_links, 3);
  status_t status{};
  status.model_ids = {"a"};
  set_counts(status);
  EXPECT_EQ(status.num_model_ids, 1);
  description_chunk_t chunk{};
  chunk.data = {1, 2, 3, 4};
  set_counts(chunk);
  EXPECT_EQ(chunk.size, 4);
  joint_command_t command{};
  command.name = {"j"};
  set_counts(command);
  EXPECT_EQ(command.num_joints, 1);
}

}  // namespace
}  // namespace rdtf

namespace rdtf::daemon {
namespace {

// The daemon's publisher sets the counts of whatever it sends: a caller never does.
TEST(DiagnosticForms, ThePublisherSendsCountsThatFollowTheArrays) {
  std::vector<std::uint8_t> sent;
  Publisher publisher(
      [&](const std::string&, const std::uint8_t* data, unsigned int size) {
        sent.assign(data, data + size);
        return 0;
      },
      1e9, 1 << 20);
  model_error_t error{};
  error.model_id = "arm";
  error.diagnostics = {to_message(Severity::kError, codes::INTERNAL_ERROR, "a"),
                       to_message(Severity::kWarning, codes::MESH_OPEN, "b")};
  error.num_diagnostics = 0;  // As a caller that forgot it would leave it.
  publisher.publish("RDTF/ERROR", error);
  publisher.drain(Publisher::Clock::now());
  ASSERT_FALSE(sent.empty());
  model_error_t decoded;
  ASSERT_GT(decoded.decode(sent.data(), 0, static_cast<int>(sent.size())), 0);
  EXPECT_EQ(decoded.num_diagnostics, 2);
  ASSERT_EQ(decoded.diagnostics.size(), 2u);
  EXPECT_EQ(decoded.diagnostics[1].code, "MESH_OPEN");
}

}  // namespace
}  // namespace rdtf::daemon
