// The jar of rdtf types that lcm-spy loads (lcmtypes/CMakeLists.txt, target rdtf_lcmtypes_jar)
// decodes every channel rdtfd sends: a session recorded by lcm-logger is read back by a small Java
// program with LCM's own lcm.logging.Log and the jar's classes, one class per channel kind, and
// what it prints is compared field by field with what the C++ subscriber received.
//
// Java classes check the type fingerprint when they decode, so a channel decoded with the wrong
// class, or a jar built from older .lcm files, fails here instead of showing garbage in lcm-spy.
#include <algorithm>
#include <set>
#include <sstream>

#include <rdtf/delta_t.hpp>
#include <rdtf/joint_state_t.hpp>
#include <rdtf/link_state_t.hpp>
#include <rdtf/manifest_t.hpp>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

// Reads an LCM log and prints one tab-separated line per rdtf event:
//   channel utime model_id revision content_hash detail
// where detail is a field or two particular to the type (names without spaces: the models here
// have none). Anything it cannot decode ends it with
// exit code 1 (the event and the exception printed).
constexpr const char* kDecoder = R"java(
import java.io.EOFException;
import java.util.Locale;
import lcm.logging.Log;

public class DecodeLog {
  static String kind(String channel) { return channel.substring(channel.lastIndexOf('/') + 1); }

  public static void main(String[] args) throws Exception {
    Log log = new Log(args[0], "r");
    int decoded = 0;
    while (true) {
      Log.Event e;
      try { e = log.readNext(); } catch (EOFException end) { break; }
      if (!e.channel.startsWith("RDTF/")) continue;
      String k = kind(e.channel);
      String line;
      try {
        line = decode(k, e.data);
      } catch (Exception x) {
        System.out.println("UNDECODED\t" + e.channel + "\t" + x);
        System.exit(1);
        return;
      }
      System.out.println(e.channel + "\t" + line);
      ++decoded;
    }
    System.err.println(decoded + " events decoded");
  }

  // A model with no one-degree-of-freedom joint sends JOINT_STATEs with no joints.
  static String first(String[] names) { return names.length == 0 ? "-" : names[0]; }

  static String row(long utime, String model, long revision, String hash, String detail) {
    return utime + "\t" + model + "\t" + revision + "\t" + hash + "\t" + detail;
  }

  static String decode(String k, byte[] d) throws Exception {
    switch (k) {
      case "DESCRIPTION": {
        rdtf.description_t m = new rdtf.description_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash, m.num_chunks + " " + m.rdtf_json_sha256);
      }
      case "DESCRIPTION_CHUNK": {
        rdtf.description_chunk_t m = new rdtf.description_chunk_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash, m.index + "/" + m.count + " " + m.size);
      }
      case "MANIFEST": {
        rdtf.manifest_t m = new rdtf.manifest_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash,
                   m.part + "/" + m.num_parts + " " + m.num_files + " " + m.files[0].path + " " + m.files[0].sha256);
      }
      case "INERTIA": {
        rdtf.inertia_table_t m = new rdtf.inertia_table_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash,
                   m.num_links + " " + m.links[0].name + " " + m.links[0].gltf_name);
      }
      case "VALIDATION": {
        rdtf.validation_report_t m = new rdtf.validation_report_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash, m.passed + " " + m.steps);
      }
      case "DELTA": {
        rdtf.delta_t m = new rdtf.delta_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash,
                   m.previous_revision + " " + m.total_changes + " " +
                   (m.num_changes == 0 ? "-" : m.changes[0].name + ":" + m.changes[0].change));
      }
      case "STATUS": {
        rdtf.status_t m = new rdtf.status_t(d);
        return row(m.utime, "", 0, "", m.pid + " " + m.num_models);
      }
      case "JOINT_STATE": {
        rdtf.joint_state_t m = new rdtf.joint_state_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash,
                   Double.toString(m.sim_time) + " " + m.num_joints + " " + first(m.name) + " " + first(m.gltf_name));
      }
      case "LINK_STATE": {
        rdtf.link_state_t m = new rdtf.link_state_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash,
                   Double.toString(m.sim_time) + " " + m.num_links + " " + m.name[0] + " " + m.gltf_name[0] + " " +
                   Double.toString(m.position[m.num_links - 1][1]) + " " +
                   Double.toString(m.orientation[m.num_links - 1][0]));
      }
      case "ERROR": {
        rdtf.model_error_t m = new rdtf.model_error_t(d);
        return row(m.utime, m.model_id, m.live_revision, m.content_hash, m.diagnostics[0].code);
      }
      case "REMOVED": {
        rdtf.model_removed_t m = new rdtf.model_removed_t(d);
        return row(m.utime, m.model_id, m.last_revision, "", m.source_path);
      }
      case "REQUEST": {
        rdtf.request_t m = new rdtf.request_t(d);
        return row(m.utime, m.model_id, 0, "", m.requester);
      }
      case "JOINT_COMMAND": {
        rdtf.joint_command_t m = new rdtf.joint_command_t(d);
        return row(m.utime, m.model_id, m.revision, m.content_hash, Integer.toString(m.num_joints));
      }
      default:
        throw new Exception("no rdtf type for channel kind " + k);
    }
  }
}
)java";

// Java's Double.toString: the shortest decimal that reads back as the same double. Parsed back
// with strtod, so the comparison below is of doubles, not of two printers.
double parse_double(const std::string& text) { return std::strtod(text.c_str(), nullptr); }

// The line DecodeLog prints for a message, made here from the C++ decoding of the same bytes;
// doubles are compared separately (see parse_double).
struct Expected {
  std::string head;                  // channel utime model_id revision content_hash
  std::vector<std::string> words;    // detail, words that are not doubles
  std::vector<double> numbers;       // detail, the doubles
};

std::string head(const Message& m, std::int64_t utime, const std::string& model, std::int64_t revision,
                 const std::string& hash) {
  return m.channel + "\t" + std::to_string(utime) + "\t" + model + "\t" + std::to_string(revision) + "\t" + hash;
}

std::optional<std::string> expected_line(const Message& m) {
  const std::string k = m.kind();
  const auto join = [](std::initializer_list<std::string> words) {
    std::string out;
    for (const auto& w : words) out += (out.empty() ? "" : " ") + w;
    return out;
  };
  if (k == "DESCRIPTION") {
    const auto d = m.as<rdtf::description_t>();
    return head(m, d.utime, d.model_id, d.revision, d.content_hash) + "\t" +
           join({std::to_string(d.num_chunks), d.rdtf_json_sha256});
  }
  if (k == "DESCRIPTION_CHUNK") {
    const auto d = m.as<rdtf::description_chunk_t>();
    return head(m, d.utime, d.model_id, d.revision, d.content_hash) + "\t" +
           join({std::to_string(d.index) + "/" + std::to_string(d.count), std::to_string(d.size)});
  }
  if (k == "MANIFEST") {
    const auto d = m.as<rdtf::manifest_t>();
    return head(m, d.utime, d.model_id, d.revision, d.content_hash) + "\t" +
           join({std::to_string(d.part) + "/" + std::to_string(d.num_parts), std::to_string(d.num_files),
                 d.files.at(0).path, d.files.at(0).sha256});
  }
  if (k == "INERTIA") {
    const auto d = m.as<rdtf::inertia_table_t>();
    return head(m, d.utime, d.model_id, d.revision, d.content_hash) + "\t" +
           join({std::to_string(d.num_links), d.links.at(0).name, d.links.at(0).gltf_name});
  }
  if (k == "VALIDATION") {
    const auto d = m.as<rdtf::validation_report_t>();
    return head(m, d.utime, d.model_id, d.revision, d.content_hash) + "\t" +
           join({d.passed ? "true" : "false", std::to_string(d.steps)});
  }
  if (k == "DELTA") {
    const auto d = m.as<rdtf::delta_t>();
    return head(m, d.utime, d.model_id, d.revision, d.content_hash) + "\t" +
           join({std::to_string(d.previous_revision), std::to_string(d.total_changes),
                 d.changes.empty() ? "-" : d.changes[0].name + ":" + d.changes[0].change});
  }
  if (k == "STATUS") {
    const auto d = m.as<rdtf::status_t>();
    return head(m, d.utime, "", 0, "") + "\t" + join({std::to_string(d.pid), std::to_string(d.num_models)});
  }
  return std::nullopt;  // JOINT_STATE and LINK_STATE carry doubles: compared by value below.
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> out;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, separator);) out.push_back(part);
  return out;
}

TEST(LcmSpyJar, DecodesEveryChannelOfARecordedSession) {
  const std::string jar = RDTF_LCM_JAR_PATH;
  const std::string lcm_jar = RDTF_LCM_JAVA_JAR;
  ASSERT_FALSE(jar.empty()) << "CMake made no rdtf_lcmtypes_jar (javac or lcm.jar was not found when the build "
                               "was configured): install a JDK (default-jdk-headless) and liblcm-java, reconfigure";
  ASSERT_TRUE(fs::exists(jar)) << jar << " was not built (cmake --build build --target rdtf_lcmtypes_jar)";
  const auto javac = testing::run_command("javac -version");
  ASSERT_EQ(javac.exit_code, 0) << "javac is needed to compile the decoder (install default-jdk-headless): "
                                << javac.err;

  Session s;
  // Two models: arm3 (simulated, validated) and one whose document needs DESCRIPTION_CHUNKs.
  copy_fixture(s.watch, "arm3");
  const auto parts = many_parts_model("parts", 1500, 0.01);
  write_model(s.watch, "parts.gltf", parts);
  const fs::path log = s.root / "session.lcmlog";
  ChildProcess logger({"lcm-logger", "-f", log.string()}, s.root / "logger.out");
  ASSERT_TRUE(s.wait_logger_recording(log)) << "lcm-logger recorded nothing: " << logger.output();

  auto& daemon = s.start(DaemonOptions().with("simulate", true).with("validate", true).with("state_rate_hz", 50));
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3"), 20s));
  ASSERT_TRUE(s.wait_revision("parts.gltf", 1, content_hash(parts), 20s));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return on_kind(all, "LINK_STATE", "arm3.gltf").size() >= 10; }));
  daemon.signal(SIGTERM);
  ASSERT_EQ(daemon.wait_exit(5s), std::optional<int>(0));
  logger.signal(SIGINT);
  ASSERT_TRUE(logger.wait_exit(5s).has_value()) << logger.output();

  const fs::path java = s.root / "java";
  fs::create_directories(java);
  testing::write_file(java / "DecodeLog.java", kDecoder);
  const std::string classpath = lcm_jar + ":" + jar;
  const auto compiled = testing::run_command("javac -nowarn -cp '" + classpath + "' -d '" + java.string() + "' '" +
                                             (java / "DecodeLog.java").string() + "'");
  ASSERT_EQ(compiled.exit_code, 0) << compiled.out << compiled.err;
  const auto run = testing::run_command("java -cp '" + java.string() + ":" + classpath + "' DecodeLog '" +
                                        log.string() + "'");
  ASSERT_EQ(run.exit_code, 0) << run.out << run.err;

  // Every rdtf message the subscriber received, by channel and utime (unique per channel but for
  // the chunks of one description, which share theirs).
  std::multimap<std::pair<std::string, std::int64_t>, const Message*> received;
  const auto all = s.messages();
  for (const auto& m : all) {
    if (m.channel.rfind("RDTF/", 0) != 0 || m.kind() == "REQUEST") continue;
    std::int64_t utime = 0;
    const Json json = m.json();
    if (!json.is_object()) continue;
    utime = json["utime"].get<std::int64_t>();
    received.emplace(std::make_pair(m.channel, utime), &m);
  }
  std::map<std::string, int> decoded_kinds;
  std::set<std::string> decoded_models;
  int matched = 0;
  for (const std::string& line : split(run.out, '\n')) {
    const auto fields = split(line, '\t');
    ASSERT_EQ(fields.size(), 6u) << line;
    const std::string channel = fields[0];
    const std::int64_t utime = std::stoll(fields[1]);
    const std::string kind = channel.substr(channel.rfind('/') + 1);
    ++decoded_kinds[kind];
    if (!fields[2].empty()) decoded_models.insert(fields[2] + " r" + fields[3]);
    const auto [begin, end] = received.equal_range({channel, utime});
    if (begin == end) continue;  // Lost by the subscriber (loopback: none seen).
    ++matched;
    SCOPED_TRACE(line);
    if (expected_line(*begin->second)) {
      std::vector<std::string> candidates;
      for (auto it = begin; it != end; ++it) candidates.push_back(*expected_line(*it->second));
      EXPECT_NE(std::find(candidates.begin(), candidates.end(), line), candidates.end())
          << "expected one of " << ::testing::PrintToString(candidates);
      continue;
    }
    const Message& m = *begin->second;
    const auto detail = split(fields[5], ' ');
    if (kind == "JOINT_STATE") {
      const auto d = m.as<rdtf::joint_state_t>();
      EXPECT_EQ(head(m, d.utime, d.model_id, d.revision, d.content_hash),
                fields[0] + "\t" + fields[1] + "\t" + fields[2] + "\t" + fields[3] + "\t" + fields[4]);
      ASSERT_EQ(detail.size(), 4u);
      EXPECT_EQ(parse_double(detail[0]), d.sim_time);
      EXPECT_EQ(detail[1], std::to_string(d.num_joints));
      EXPECT_EQ(detail[2], d.name.empty() ? "-" : d.name.front());
      EXPECT_EQ(detail[3], d.gltf_name.empty() ? "-" : d.gltf_name.front());
    } else if (kind == "LINK_STATE") {
      const auto d = m.as<rdtf::link_state_t>();
      EXPECT_EQ(head(m, d.utime, d.model_id, d.revision, d.content_hash),
                fields[0] + "\t" + fields[1] + "\t" + fields[2] + "\t" + fields[3] + "\t" + fields[4]);
      ASSERT_EQ(detail.size(), 6u);
      EXPECT_EQ(parse_double(detail[0]), d.sim_time);
      EXPECT_EQ(detail[1], std::to_string(d.num_links));
      EXPECT_EQ(detail[2], d.name.at(0));
      EXPECT_EQ(detail[3], d.gltf_name.at(0));
      EXPECT_EQ(parse_double(detail[4]), d.position.back().at(1));
      EXPECT_EQ(parse_double(detail[5]), d.orientation.back().at(0));
    } else {
      ADD_FAILURE() << "no check for kind " << kind;
    }
  }
  std::printf("%zu lines decoded by the jar, %d matched to the subscriber's messages:", split(run.out, '\n').size(),
              matched);
  for (const auto& [kind, count] : decoded_kinds) std::printf(" %s %d", kind.c_str(), count);
  std::printf("\n");

  // Every kind the daemon sent in this session was decoded, for both models.
  std::set<std::string> sent_kinds;
  for (const auto& m : all) {
    if (m.channel.rfind("RDTF/", 0) == 0 && m.kind() != "REQUEST") sent_kinds.insert(m.kind());
  }
  const std::set<std::string> expected_kinds = {"DESCRIPTION", "DESCRIPTION_CHUNK", "INERTIA",    "VALIDATION", "DELTA",
                                                "STATUS",      "JOINT_STATE",       "LINK_STATE", "MANIFEST"};
  EXPECT_EQ(sent_kinds, expected_kinds);
  for (const auto& kind : expected_kinds) EXPECT_GT(decoded_kinds[kind], 0) << kind << " not in the log";
  EXPECT_EQ(decoded_models, (std::set<std::string>{"arm3.gltf r1", "parts.gltf r1"}));
  // Loopback multicast within one namespace loses nothing at these rates: most of the log matches.
  EXPECT_GE(matched, static_cast<int>(0.99 * static_cast<double>(received.size())));
}

}  // namespace
}  // namespace rdtf::itest
