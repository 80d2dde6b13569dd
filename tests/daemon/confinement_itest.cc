// rdtfd never reads outside a model's folder. The daemon runs with its working directory at "/"
// (what systemd gives a service), so a loader that resolved relative paths against the working
// directory, or searched it, would find /etc/passwd. Every escape gets its own model; each must
// be rejected with an ERROR naming the model file and /buffers/0, nothing of /etc/passwd may
// appear in any LCM message or output file, and the daemon must go on serving other models.
#include <sys/stat.h>

#include "daemon/harness.h"

namespace rdtf::itest {
namespace {

// A box model whose only buffer has `uri` and `byte_length` instead of its own.
std::string model_with_buffer(const std::string& uri, std::uint64_t byte_length) {
  Json document = Json::parse(box_model("escape", 0.1).gltf);
  document["buffers"][0] = {{"uri", uri}, {"byteLength", byte_length}};
  return document.dump(1);
}

// A box model with an image of `uri` besides its own buffer.
std::string model_with_image(const std::string& uri) {
  Json document = Json::parse(box_model("picture", 0.1).gltf);
  document["images"] = Json::array({{{"uri", uri}}});
  return document.dump(1);
}

struct Escape {
  std::string file;    // Model file name in the watched folder.
  std::string uri;     // What its buffer (or image) refers to.
  bool image = false;  // An image's URI, not the buffer's.
};

// Every byte sequence that would betray that /etc/passwd was read: its lines of 8+ characters.
std::vector<std::string> secrets() {
  std::vector<std::string> lines;
  std::istringstream in(read("/etc/passwd"));
  for (std::string line; std::getline(in, line);) {
    if (line.size() >= 8) lines.push_back(line);
  }
  return lines;
}

bool contains_any(const std::string& haystack, const std::vector<std::string>& needles, std::string& found) {
  for (const auto& needle : needles) {
    if (haystack.find(needle) != std::string::npos) {
      found = needle;
      return true;
    }
  }
  return false;
}

TEST(DaemonConfinement, EveryEscapeIsRejectedWithItsPlaceAndNothingLeaks) {
  ASSERT_TRUE(fs::is_regular_file("/etc/passwd"));
  const std::uint64_t passwd_size = fs::file_size("/etc/passwd");
  Session s;
  // Links and special files the models point at, inside the watched folder.
  fs::create_symlink("/etc/passwd", s.watch / "passwd_link.bin");
  fs::create_symlink("/etc", s.watch / "etc_link");
  fs::create_symlink("/dev/zero", s.watch / "zero_link.bin");
  fs::create_directory(s.watch / "folder.bin");
  ASSERT_EQ(::mkfifo((s.watch / "pipe.bin").c_str(), 0644), 0);
  const auto good = box_model("good_base", 0.1);
  write_model(s.watch, "good.gltf", good);

  const std::vector<Escape> escapes = {
      {"absolute.gltf", "/etc/passwd"},
      {"relative_to_cwd.gltf", "etc/passwd"},  // Resolves against "/" only if the cwd is used.
      {"dotdot.gltf", "../../../../../../../../../../etc/passwd"},
      {"percent_dots.gltf", "%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/%2e%2e/etc/passwd"},
      {"percent_slashes.gltf", "..%2F..%2F..%2F..%2F..%2F..%2F..%2F..%2Fetc%2Fpasswd"},
      {"percent_mixed.gltf", "%2e%2e%2f%2e%2e%2f%2e%2e%2f%2e%2e%2f%2e%2e%2f%2e%2e%2f%2e%2e%2fetc%2fpasswd"},
      {"file_uri.gltf", "file:///etc/passwd"},
      {"symlink_file.gltf", "passwd_link.bin"},
      {"symlink_folder.gltf", "etc_link/passwd"},
      {"dot.gltf", "."},
      {"directory.gltf", "folder.bin"},
      {"dev_zero.gltf", "/dev/zero"},
      {"dev_zero_link.gltf", "zero_link.bin"},
      {"fifo.gltf", "pipe.bin"},
      // An image is confined as a buffer is (only a missing one is a warning, below).
      {"image_symlink_file.gltf", "passwd_link.bin", true},
      {"image_symlink_folder.gltf", "etc_link/passwd", true},
      {"image_absolute.gltf", "/etc/passwd", true},
      {"image_dev_zero_link.gltf", "zero_link.bin", true},
  };
  // byteLength as /etc/passwd's own size: only the confinement can stop these.
  for (const auto& escape : escapes) {
    write_in_place(s.watch / escape.file,
                   escape.image ? model_with_image(escape.uri) : model_with_buffer(escape.uri, passwd_size));
  }
  // A texture moved away since the export costs only its look: the model is published, warned.
  const std::string missing_image = model_with_image("moved_away.png");
  write_in_place(s.watch / "missing_image.gltf", missing_image);
  // So does a symbolic link whose target moved away: it is not there either.
  fs::create_symlink("gone.png", s.watch / "dangling.png");
  const std::string dangling_image = model_with_image("dangling.png");
  write_in_place(s.watch / "dangling_image.gltf", dangling_image);
  // An embedded buffer over the cap (max_buffer_bytes, above /etc/passwd's size so that only the
  // confinement stops the others): 3,000 bytes more than the cap, in base64.
  const std::uint64_t cap = passwd_size + 4096;
  const std::uint64_t over = cap + 3000;
  Json big = Json::parse(box_model("big", 0.1).gltf);
  big["buffers"][0] = {{"uri", "data:application/octet-stream;base64," + std::string(over / 3 * 4, 'A')},
                       {"byteLength", over / 3 * 3}};
  write_in_place(s.watch / "data_over_cap.gltf", big.dump(1));

  // One worker: a read that blocked (the FIFO) would stop every later conversion.
  s.start(DaemonOptions().in_directory("/").with("workers", 1).with("max_buffer_bytes", cap));

  std::vector<std::string> rejected;
  for (const auto& escape : escapes) rejected.push_back(escape.file);
  rejected.push_back("data_over_cap.gltf");
  ASSERT_TRUE(s.wait_for([&](const auto& all) {
    for (const auto& id : rejected) {
      if (on_kind(all, "ERROR", id).empty()) return false;
    }
    return has_revision(all, "good.gltf", 1, content_hash(good)) &&
           has_revision(all, "missing_image.gltf", 1, content_hash(missing_image, {std::nullopt})) &&
           has_revision(all, "dangling_image.gltf", 1, content_hash(dangling_image, {std::nullopt}));
  }, 10s)) << ::testing::PrintToString(model_events(s.messages()));

  for (std::size_t k = 0; k < rejected.size(); ++k) {
    const std::string& id = rejected[k];
    const std::string place = k < escapes.size() && escapes[k].image ? "/images/0" : "/buffers/0";
    SCOPED_TRACE(id);
    const auto errors = decoded<rdtf::model_error_t>(s.messages(), "ERROR", id);
    ASSERT_EQ(errors.size(), 1u);
    const auto& error = errors.front();
    EXPECT_EQ(error.live_revision, 0);
    EXPECT_EQ(fs::path(error.source_path), fs::canonical(s.watch / id));
    bool placed = false;
    std::string all_text;
    for (const auto& d : error.diagnostics) {
      all_text += d.code + " " + d.pointer + " " + d.message + "\n";
      if (d.severity == rdtf::diagnostic_t::ERROR && d.file == error.source_path &&
          d.pointer.rfind(place, 0) == 0) {
        placed = true;
      }
    }
    EXPECT_TRUE(placed) << "no ERROR naming " << error.source_path << " and " << place << ":\n" << all_text;
    EXPECT_TRUE(s.daemon->log().find("rejected " + id) != std::string::npos);
  }

  // The daemon still serves: a new model after all of that converts.
  const auto later = box_model("later_base", 0.15);
  write_model(s.watch, "later.gltf", later);
  ASSERT_TRUE(s.wait_revision("later.gltf", 1, content_hash(later)));
  const auto idle = s.wait_idle();
  ASSERT_TRUE(idle);
  EXPECT_EQ(idle->conversions, 4);
  EXPECT_EQ(idle->rejections, static_cast<std::int64_t>(rejected.size()));
  EXPECT_TRUE(s.daemon->running());

  // Nothing of /etc/passwd in any message or output file.
  const auto needles = secrets();
  ASSERT_FALSE(needles.empty());
  std::string found;
  for (const auto& m : s.messages()) {
    const std::string bytes(m.bytes.begin(), m.bytes.end());
    EXPECT_FALSE(contains_any(bytes, needles, found)) << m.channel << " carries '" << found << "'";
  }
  int outputs = 0;
  for (const auto& entry : fs::recursive_directory_iterator(s.output)) {
    if (!entry.is_regular_file()) continue;
    ++outputs;
    EXPECT_FALSE(contains_any(read(entry.path()), needles, found)) << entry.path() << " holds '" << found << "'";
  }
  EXPECT_GT(outputs, 0);
  EXPECT_FALSE(contains_any(s.daemon->log(), needles, found)) << "the log holds '" << found << "'";
}

// A buffer that is a FIFO with a writer that never writes, and one with no writer: the daemon
// opens neither in a way that waits, and a model saved afterwards converts at once.
TEST(DaemonConfinement, FifoBuffersNeverHangTheDaemon) {
  Session s;
  ASSERT_EQ(::mkfifo((s.watch / "held.bin").c_str(), 0644), 0);
  // A writer that holds the FIFO open: a blocking read would wait for it forever.
  const int held = ::open((s.watch / "held.bin").c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  ASSERT_GE(held, 0);
  write_in_place(s.watch / "held.gltf", model_with_buffer("held.bin", 168));
  s.start(DaemonOptions().in_directory("/").with("workers", 1));
  ASSERT_TRUE(s.wait_for([](const auto& all) { return !on_kind(all, "ERROR", "held.gltf").empty(); }));
  const auto error = decoded<rdtf::model_error_t>(s.messages(), "ERROR", "held.gltf").front();
  ASSERT_FALSE(error.diagnostics.empty());
  EXPECT_EQ(error.diagnostics[0].pointer, "/buffers/0/uri");
  EXPECT_NE(error.diagnostics[0].message.find("FIFO"), std::string::npos) << error.diagnostics[0].message;

  const auto good = box_model("good_base", 0.1);
  write_model(s.watch, "good.gltf", good);
  EXPECT_TRUE(s.wait_revision("good.gltf", 1, content_hash(good)));
  ::close(held);
}

}  // namespace
}  // namespace rdtf::itest
