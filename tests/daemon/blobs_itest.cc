// Files and blobs (docs/lcm.md, "Files and blobs"): every revision's MANIFEST lists the files of
// its output folder by SHA-256, and <prefix>/BLOB_REQUEST is answered with chunks on <prefix>/BLOB
// that reassemble to exactly those files, or with BLOB_UNAVAILABLE. The test's own LCM subscriber
// (BlobCollector) asks, reassembles, and asks again for chunks it lost, as a client would.
#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_request_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>
#include <rdtf/manifest_t.hpp>

#include <atomic>
#include <set>

#include "harness.h"

namespace rdtf::itest {
namespace {

struct Range {
  std::string sha256;
  std::int32_t first = 0;
  std::int32_t count = -1;
};

rdtf::blob_request_t make_request(const std::vector<Range>& ranges, const std::string& requester) {
  rdtf::blob_request_t request;
  request.utime = 0;
  request.requester = requester;
  request.num_ranges = static_cast<std::int32_t>(ranges.size());
  for (const Range& r : ranges) {
    request.sha256.push_back(r.sha256);
    request.first_chunk.push_back(r.first);
    request.num_chunks.push_back(r.count);
  }
  return request;
}

// Records every chunk and unavailable answer (its own LCM instance and thread), and fetches blobs
// as a client does: ask for them whole, then for the chunks still missing.
class BlobCollector {
 public:
  struct Blob {
    std::int64_t size = -1;
    std::int32_t chunk_size = 0;
    std::int32_t count = 0;
    std::map<std::int32_t, std::string> chunks;
    std::vector<std::int32_t> arrivals;  // Every index received, repeats included.
  };

  BlobCollector() : lcm_("") {
    if (!lcm_.good()) throw std::runtime_error("cannot open LCM");
    lcm_.subscribe(std::string(kPrefix) + "/BLOB", &BlobCollector::on_chunk, this)->setQueueCapacity(100000);
    lcm_.subscribe(std::string(kPrefix) + "/BLOB_UNAVAILABLE", &BlobCollector::on_unavailable, this);
    thread_ = std::thread([this] {
      while (!stop_) lcm_.handleTimeout(20);
    });
  }
  ~BlobCollector() {
    stop_ = true;
    thread_.join();
  }

  void request(const std::vector<Range>& ranges, const std::string& requester = "blobs_itest") {
    const auto message = make_request(ranges, requester);
    if (lcm_.publish(std::string(kPrefix) + "/BLOB_REQUEST", &message) != 0) throw std::runtime_error("publish failed");
  }
  void publish_raw(const std::vector<std::uint8_t>& bytes) {
    lcm_.publish(std::string(kPrefix) + "/BLOB_REQUEST", bytes.data(), static_cast<unsigned>(bytes.size()));
  }
  void clear() {
    std::lock_guard lock(mutex_);
    blobs_.clear();
    unavailable_.clear();
  }
  Blob blob(const std::string& sha) const {
    std::lock_guard lock(mutex_);
    auto it = blobs_.find(sha);
    return it == blobs_.end() ? Blob{} : it->second;
  }
  std::map<std::string, std::pair<std::string, std::string>> unavailable() const {  // sha -> (requester, reason)
    std::lock_guard lock(mutex_);
    return unavailable_;
  }
  bool complete(const std::string& sha) const {
    std::lock_guard lock(mutex_);
    auto it = blobs_.find(sha);
    return it != blobs_.end() && it->second.count > 0 &&
           it->second.chunks.size() == static_cast<std::size_t>(it->second.count);
  }
  std::string assembled(const std::string& sha) const {
    std::lock_guard lock(mutex_);
    std::string bytes;
    for (const auto& [index, data] : blobs_.at(sha).chunks) bytes += data;
    return bytes;
  }

  // Every blob whole (or answered unavailable), asking again for what was lost; the bytes of those
  // that came whole.
  std::map<std::string, std::string> fetch(const std::set<std::string>& shas, const std::string& requester = "blobs_itest") {
    std::vector<Range> ranges;
    for (const auto& sha : shas) ranges.push_back({sha, 0, -1});
    for (int round = 0; round < 8 && !ranges.empty(); ++round) {
      for (std::size_t i = 0; i < ranges.size(); i += 200) {
        request({ranges.begin() + static_cast<std::ptrdiff_t>(i),
                 ranges.begin() + static_cast<std::ptrdiff_t>(std::min(ranges.size(), i + 200))},
                requester);
      }
      // Until everything is here, or nothing came for a while (then ask again for what is missing).
      std::size_t heard = arrivals();
      auto quiet_since = Clock::now();
      wait_until(
          [&] {
            if (missing(shas).empty()) return true;
            if (arrivals() != heard) {
              heard = arrivals();
              quiet_since = Clock::now();
            }
            return Clock::now() - quiet_since > 500ms;
          },
          30s);
      ranges = missing(shas);
    }
    std::map<std::string, std::string> out;
    for (const auto& sha : shas) {
      if (complete(sha)) out[sha] = assembled(sha);
    }
    return out;
  }

 private:
  std::size_t arrivals() const {
    std::lock_guard lock(mutex_);
    std::size_t n = unavailable_.size();
    for (const auto& [sha, blob] : blobs_) n += blob.arrivals.size();
    return n;
  }
  // The ranges still missing: whole blobs never heard of, runs of lost chunks of the others.
  std::vector<Range> missing(const std::set<std::string>& shas) const {
    std::lock_guard lock(mutex_);
    std::vector<Range> out;
    for (const auto& sha : shas) {
      if (unavailable_.count(sha) > 0) continue;
      auto it = blobs_.find(sha);
      if (it == blobs_.end()) {
        out.push_back({sha, 0, -1});
        continue;
      }
      const Blob& b = it->second;
      for (std::int32_t i = 0; i < b.count;) {
        if (b.chunks.count(i) > 0) {
          ++i;
          continue;
        }
        std::int32_t end = i;
        while (end < b.count && b.chunks.count(end) == 0) ++end;
        out.push_back({sha, i, end - i});
        i = end;
      }
    }
    return out;
  }
  void on_chunk(const lcm::ReceiveBuffer* buffer, const std::string&) {
    rdtf::blob_chunk_t chunk;
    if (chunk.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) < 0) return;
    std::lock_guard lock(mutex_);
    Blob& b = blobs_[chunk.sha256];
    b.size = chunk.blob_size;
    b.chunk_size = chunk.chunk_size;
    b.count = chunk.count;
    b.chunks[chunk.index] = std::string(chunk.data.begin(), chunk.data.end());
    b.arrivals.push_back(chunk.index);
  }
  void on_unavailable(const lcm::ReceiveBuffer* buffer, const std::string&) {
    rdtf::blob_unavailable_t message;
    if (message.decode(buffer->data, 0, static_cast<int>(buffer->data_size)) < 0) return;
    std::lock_guard lock(mutex_);
    for (std::int32_t i = 0; i < message.num_blobs; ++i) {
      unavailable_[message.sha256[static_cast<std::size_t>(i)]] = {message.requester, message.reason[static_cast<std::size_t>(i)]};
    }
  }

  lcm::LCM lcm_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
  mutable std::mutex mutex_;
  std::map<std::string, Blob> blobs_;
  std::map<std::string, std::pair<std::string, std::string>> unavailable_;
};

// The manifest of one revision, parts joined: path -> file.
std::optional<std::map<std::string, rdtf::file_t>> manifest(const std::vector<Message>& all, const std::string& id,
                                                             std::int64_t revision) {
  std::map<std::int32_t, rdtf::manifest_t> parts;
  std::int32_t num_parts = -1;
  for (const auto& m : decoded<rdtf::manifest_t>(all, "MANIFEST", id)) {
    if (m.revision != revision) continue;
    parts[m.part] = m;
    num_parts = m.num_parts;
  }
  if (num_parts < 1 || parts.size() != static_cast<std::size_t>(num_parts)) return std::nullopt;
  std::map<std::string, rdtf::file_t> files;
  for (const auto& [index, part] : parts) {
    for (const auto& file : part.files) files[file.path] = file;
  }
  if (files.size() != static_cast<std::size_t>(parts.begin()->second.total_files)) return std::nullopt;
  return files;
}

std::map<std::string, rdtf::file_t> wait_manifest(Session& s, const std::string& id, std::int64_t revision) {
  std::optional<std::map<std::string, rdtf::file_t>> files;
  s.wait_for([&](const auto& all) { return (files = manifest(all, id, revision)).has_value(); });
  if (!files) throw std::runtime_error("no whole MANIFEST of " + id + " revision " + std::to_string(revision));
  return *files;
}

std::string expected_role(const std::string& path) {
  if (path.ends_with(".rdtf.gltf")) return "rdtf";
  if (path == "urdf/robot.urdf") return "urdf";
  if (path.starts_with("urdf/meshes/")) return "urdf_mesh";
  if (path.ends_with(".bin")) return "buffer";
  return "image";
}

// The manifest lists the files of the model's output folder, with their hashes and sizes, and
// every blob fetched over LCM is byte-equal to its file. After an edit the folder also holds the
// previous revision's content-addressed files (kept until the next revision is committed).
void expect_served(Session& s, const std::string& id, std::int64_t revision, bool first_revision = true) {
  SCOPED_TRACE(id + " revision " + std::to_string(revision));
  const auto files = wait_manifest(s, id, revision);
  const auto on_disk = snapshot(s.output / id);
  std::set<std::string> listed, present;
  for (const auto& [path, file] : files) listed.insert(path);
  for (const auto& [path, bytes] : on_disk) present.insert(path);
  if (first_revision) {
    EXPECT_EQ(listed, present);
  } else {
    EXPECT_TRUE(std::includes(present.begin(), present.end(), listed.begin(), listed.end()));
  }
  std::set<std::string> shas;
  for (const auto& [path, file] : files) {
    ASSERT_EQ(on_disk.count(path), 1u) << path;
    EXPECT_EQ(file.sha256, sha256_plain(on_disk.at(path))) << path;
    EXPECT_EQ(file.size, static_cast<std::int64_t>(on_disk.at(path).size())) << path;
    EXPECT_EQ(file.role, expected_role(path)) << path;
    shas.insert(file.sha256);
  }
  // The description's documents are files of the manifest too.
  const auto description = last_description(s.messages(), id);
  ASSERT_TRUE(description.has_value());
  bool rdtf_listed = false;
  for (const auto& [path, file] : files) rdtf_listed |= file.role == "rdtf" && file.sha256 == description->rdtf_json_sha256;
  EXPECT_TRUE(rdtf_listed);
  BlobCollector collector;
  const auto fetched = collector.fetch(shas);
  for (const auto& [path, file] : files) {
    ASSERT_EQ(fetched.count(file.sha256), 1u) << path << " was not served whole";
    EXPECT_EQ(fetched.at(file.sha256), on_disk.at(path)) << path;
  }
  EXPECT_TRUE(collector.unavailable().empty());
}


TEST(DaemonBlobs, GltfWithBinAndUrdfMeshesIsServedByteForByte) {
  Session s;
  s.start(DaemonOptions{}.with("urdf", true).with("max_chunk_bytes", 1024));
  copy_fixture(s.watch, "arm3");
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  // The .rdtf.gltf, its .bin, urdf/robot.urdf and a mesh per link at least.
  const auto files = wait_manifest(s, "arm3.gltf", 1);
  EXPECT_GE(files.size(), 4u);
  expect_served(s, "arm3.gltf", 1);
}

TEST(DaemonBlobs, GlbModelIsServedByteForByte) {
  Session s;
  s.start();
  fs::copy_file(testing::data_dir() / "blender" / "arm3.glb", s.watch / "arm3.glb");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return last_description(all, "arm3.glb").has_value(); }));
  expect_served(s, "arm3.glb", 1);
}

TEST(DaemonBlobs, ManifestComesBeforeEveryDescription) {
  Session s;
  s.start(DaemonOptions{}.with_republish(300));
  copy_fixture(s.watch, "arm3");
  ASSERT_TRUE(s.wait_for([](const auto& all) { return decoded<rdtf::description_t>(all, "DESCRIPTION").size() >= 3; }));
  s.subscriber.publish(std::string(kPrefix) + "/REQUEST", [] {
    rdtf::request_t r;
    r.utime = 0;
    r.model_id = "arm3.gltf";
    r.requester = "blobs_itest";
    return r;
  }());
  ASSERT_TRUE(s.wait_for([](const auto& all) { return decoded<rdtf::description_t>(all, "DESCRIPTION").size() >= 4; }));
  // Each DESCRIPTION has a whole manifest of its revision since the one before.
  const auto all = s.messages();
  std::size_t manifests_since = 0;
  for (const auto& m : all) {
    if (m.model_id() != "arm3.gltf") continue;
    if (m.kind() == "MANIFEST") ++manifests_since;
    if (m.kind() == "DESCRIPTION") {
      EXPECT_EQ(manifests_since, 1u);
      manifests_since = 0;
    }
  }
}

TEST(DaemonBlobs, ChunkRangeReturnsExactlyThoseChunks) {
  Session s;
  s.start(DaemonOptions{}.with("max_chunk_bytes", 1024));
  copy_fixture(s.watch, "arm3");
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  const auto files = wait_manifest(s, "arm3.gltf", 1);
  const rdtf::file_t& gltf = files.at("arm3.rdtf.gltf");
  const std::string bytes = read(s.output / "arm3.gltf" / "arm3.rdtf.gltf");
  BlobCollector collector;
  // Chunks 2 and 3 only (asked again while one was lost: the same range, nothing else).
  for (int attempt = 0; attempt < 5 && !(collector.blob(gltf.sha256).chunks.size() == 2); ++attempt) {
    collector.request({{gltf.sha256, 2, 2}});
    wait_until([&] { return collector.blob(gltf.sha256).chunks.size() == 2; }, 5s);
  }
  s.wait_idle();
  const auto blob = collector.blob(gltf.sha256);
  ASSERT_GT(blob.count, 3) << "the document should need several chunks of " << blob.chunk_size << " bytes";
  EXPECT_EQ(blob.size, gltf.size);
  EXPECT_EQ(blob.count, (gltf.size + blob.chunk_size - 1) / blob.chunk_size);
  EXPECT_EQ(std::set<std::int32_t>(blob.arrivals.begin(), blob.arrivals.end()), (std::set<std::int32_t>{2, 3}));
  for (const auto& [index, data] : blob.chunks) {
    EXPECT_EQ(data, bytes.substr(static_cast<std::size_t>(index) * static_cast<std::size_t>(blob.chunk_size),
                                 static_cast<std::size_t>(blob.chunk_size)));
  }
  // A chunk that encodes to at most max_chunk_bytes.
  EXPECT_LE(blob.chunk_size + 109, 1024);
}

TEST(DaemonBlobs, UnknownHashIsAnsweredUnavailable) {
  Session s;
  s.start();
  copy_fixture(s.watch, "arm3");
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  const auto files = wait_manifest(s, "arm3.gltf", 1);
  const std::string known = files.at("arm3.rdtf.gltf").sha256;
  const std::string unknown = sha256_plain("no file has these bytes");
  BlobCollector collector;
  for (int attempt = 0; attempt < 5 && (collector.unavailable().empty() || !collector.complete(known)); ++attempt) {
    collector.request({{unknown, 0, -1}, {known, 0, -1}}, "asker-7");
    wait_until([&] { return !collector.unavailable().empty() && collector.complete(known); }, 5s);
  }
  const auto answers = collector.unavailable();
  ASSERT_EQ(answers.count(unknown), 1u);
  EXPECT_EQ(answers.at(unknown).first, "asker-7");
  EXPECT_NE(answers.at(unknown).second.find("not a file of any live revision"), std::string::npos)
      << answers.at(unknown).second;
  EXPECT_EQ(answers.count(known), 0u);
  EXPECT_EQ(collector.assembled(known), read(s.output / "arm3.gltf" / "arm3.rdtf.gltf"));
  const auto status = s.wait_idle();
  ASSERT_TRUE(status.has_value());
  EXPECT_GE(status->blob_unavailable, 1);
  EXPECT_GE(status->blob_requests, 1);
}

TEST(DaemonBlobs, AfterAnEditUnchangedFilesKeepTheirHashesAndOldOnesAreUnavailable) {
  Session s;
  s.start(DaemonOptions{}.with("urdf", true));
  const auto v1 = box_model("base_v1", 0.1, 3, "chain.bin");
  write_model(s.watch, "chain.gltf", v1);
  ASSERT_TRUE(s.wait_revision("chain.gltf", 1, content_hash(v1)));
  const auto before = wait_manifest(s, "chain.gltf", 1);
  expect_served(s, "chain.gltf", 1);
  // Only the JSON changes (the base link's name): the .bin and every mesh keep their bytes.
  const auto v2 = box_model("base_v2", 0.1, 3, "chain.bin");
  ASSERT_EQ(v1.bin, v2.bin);
  write_model(s.watch, "chain.gltf", v2);
  ASSERT_TRUE(s.wait_revision("chain.gltf", 2, content_hash(v2)));
  const auto after = wait_manifest(s, "chain.gltf", 2);
  std::set<std::string> after_shas;
  for (const auto& [path, file] : after) after_shas.insert(file.sha256);
  std::set<std::string> gone;
  int kept = 0;
  for (const auto& [path, file] : before) {
    if (after.count(path) > 0 && file.role != "rdtf" && file.role != "urdf") {
      EXPECT_EQ(after.at(path).sha256, file.sha256) << path;
      ++kept;
    }
    if (after_shas.count(file.sha256) == 0) gone.insert(file.sha256);
  }
  EXPECT_GE(kept, 1) << "the .bin at least keeps its name and hash";
  ASSERT_GE(gone.size(), 2u) << "the old .rdtf.gltf and robot.urdf";
  BlobCollector collector;
  std::vector<Range> ranges;
  for (const auto& sha : gone) ranges.push_back({sha, 0, -1});
  auto all_answered = [&] {
    const auto answers = collector.unavailable();
    return std::all_of(gone.begin(), gone.end(), [&](const auto& sha) { return answers.count(sha) > 0; });
  };
  for (int attempt = 0; attempt < 5 && !all_answered(); ++attempt) {
    collector.request(ranges);
    wait_until(all_answered, 5s);
  }
  EXPECT_TRUE(all_answered());
  for (const auto& sha : gone) EXPECT_TRUE(collector.blob(sha).arrivals.empty()) << sha;
  expect_served(s, "chain.gltf", 2, false);
}

// Big-endian fields as LCM encodes them.
struct Bytes {
  std::vector<std::uint8_t> data;
  Bytes& u(std::uint64_t value, int width) {
    for (int k = width - 1; k >= 0; --k) data.push_back(static_cast<std::uint8_t>(value >> (8 * k)));
    return *this;
  }
  Bytes& i64(std::int64_t v) { return u(static_cast<std::uint64_t>(v), 8); }
  Bytes& i32(std::int32_t v) { return u(static_cast<std::uint32_t>(v), 4); }
  Bytes& str(const std::string& s) {
    i32(static_cast<std::int32_t>(s.size() + 1));
    data.insert(data.end(), s.begin(), s.end());
    data.push_back(0);
    return *this;
  }
};

TEST(DaemonBlobs, HostileRequestsAreDroppedAndAGoodOneIsStillServed) {
  Session s;
  s.start();
  copy_fixture(s.watch, "arm3");
  ASSERT_TRUE(s.wait_revision("arm3.gltf", 1, fixture_hash("arm3")));
  const auto files = wait_manifest(s, "arm3.gltf", 1);
  std::string known, known_path;
  for (const auto& [path, file] : files) {
    if (file.role == "buffer") std::tie(known, known_path) = std::pair{file.sha256, path};
  }
  ASSERT_FALSE(known.empty());
  BlobCollector collector;
  std::string upper = known;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  const std::vector<std::vector<Range>> malformed = {
      {{upper, 0, -1}},                      // not lowercase hex
      {{std::string(64, 'g'), 0, -1}},       // not hex
      {{known.substr(0, 63), 0, -1}},        // 63 digits
      {{known, -1, 1}},                      // negative first chunk
      {{known, 0, 0}},                       // no chunks
      {{known, 0, -5}},                      // a count below -1
      {{known, std::numeric_limits<std::int32_t>::min(), std::numeric_limits<std::int32_t>::max()}},
      {},                                    // nothing asked for
      std::vector<Range>(300, Range{known, 0, -1}),  // over 256 ranges
  };
  for (const auto& ranges : malformed) collector.request(ranges, "hostile");
  // Counts that do not match the arrays (the schema check), a truncated datagram, noise.
  const auto one = make_request({{known, 0, -1}}, "hostile");
  std::vector<std::uint8_t> encoded(static_cast<std::size_t>(one.getEncodedSize()));
  one.encode(encoded.data(), 0, static_cast<int>(encoded.size()));
  Bytes lying;
  lying.data.assign(encoded.begin(), encoded.end());
  const std::size_t count_at = 8 + 8 + 4 + std::string("hostile").size() + 1;
  lying.data[count_at + 3] = 2;  // num_ranges 2, one range present
  collector.publish_raw(lying.data);
  Bytes huge;
  huge.u(static_cast<std::uint64_t>(rdtf::blob_request_t::getHash()), 8).i64(0).str("hostile").i32(0x7fffffff);
  collector.publish_raw(huge.data);
  collector.publish_raw(std::vector<std::uint8_t>(encoded.begin(), encoded.begin() + 30));
  collector.publish_raw(std::vector<std::uint8_t>(1000, 0xab));
  // A huge first chunk of a known blob is well formed: answered unavailable, with the reason.
  collector.request({{known, 1 << 30, -1}}, "hostile-range");
  // A flood from one requester: beyond its rate (100 at once, then 50 a second) dropped.
  // Spaced a little (20 every 10 ms), so that the daemon's socket buffer, which holds about 90
  // small datagrams, does not overflow on a loaded machine: the limit, not the kernel, drops them.
  for (int i = 0; i < 400; ++i) {
    collector.request({{known, 0, -1}}, "flood");
    if (i % 20 == 19) std::this_thread::sleep_for(10ms);
  }
  // And a good request from someone else is still served.
  std::map<std::string, std::string> fetched;
  fetched = collector.fetch({known}, "good");
  ASSERT_EQ(fetched.count(known), 1u);
  EXPECT_EQ(fetched.at(known), read(s.output / "arm3.gltf" / known_path));
  ASSERT_TRUE(wait_until([&] { return collector.unavailable().count(known) > 0; }, 5s));
  const auto answers = collector.unavailable();
  EXPECT_EQ(answers.at(known).first, "hostile-range");
  EXPECT_NE(answers.at(known).second.find("chunk 1073741824 asked for"), std::string::npos) << answers.at(known).second;
  const auto status = s.wait_idle();
  ASSERT_TRUE(status.has_value());
  // 9 malformed + 4 that fail the schema check, and some of the flood (beyond 100 at once).
  EXPECT_GT(status->blob_requests_dropped, 13) << "taken: " << status->blob_requests;
  EXPECT_GE(status->dropped_messages, status->blob_requests_dropped);
  EXPECT_TRUE(s.daemon->wait_log("is not 64 lowercase hex digits")) << "the first drop is logged at once";
  EXPECT_TRUE(s.daemon->running());
}

// A blob of tens of MB goes out with the send queue bounded: chunks are read as the queue drains.
TEST(DaemonBlobs, LargeBlobIsServedWithABoundedSendQueue) {
  Session s;
  s.start();
  // 24 MB of buffer: a box model whose .bin has a large unused tail.
  GeneratedModel model = box_model("big", 0.1, 1, "big.bin");
  std::string tail(24 << 20, '\0');
  std::uint64_t x = 88172645463325252ull;
  for (std::size_t i = 0; i < tail.size(); i += 8) {
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    std::memcpy(&tail[i], &x, 8);
  }
  model.bin += tail;
  Json document = Json::parse(model.gltf);
  document["buffers"][0]["byteLength"] = model.bin.size();
  model.gltf = document.dump(1);
  write_model(s.watch, "big.gltf", model);
  ASSERT_TRUE(s.wait_revision("big.gltf", 1, content_hash(model), 20s));
  const auto files = wait_manifest(s, "big.gltf", 1);
  std::string sha;
  for (const auto& [path, file] : files) {
    if (file.role == "buffer") sha = file.sha256;
  }
  ASSERT_EQ(sha, sha256_plain(model.bin));
  BlobCollector collector;
  const std::size_t statuses_before = statuses(s.messages()).size();
  const auto fetched = collector.fetch({sha});
  ASSERT_EQ(fetched.count(sha), 1u);
  EXPECT_TRUE(fetched.at(sha) == model.bin);
  // The heartbeat that counts the last chunk may come after the collector has it all (statuses go
  // every 100 ms): wait for it rather than read the one heard last.
  EXPECT_TRUE(wait_until([&] {
    const auto heard = statuses(s.messages());
    return !heard.empty() && heard.back().blob_bytes_sent >= static_cast<std::int64_t>(model.bin.size());
  }, 5s));
  const auto all = statuses(s.messages());
  ASSERT_GT(all.size(), statuses_before + 3);
  std::int64_t most = 0;
  for (std::size_t i = statuses_before; i < all.size(); ++i) most = std::max(most, all[i].send_queue_bytes);
  // The blob server feeds chunks while the queue holds less than 1 MiB: one chunk (60 KB) more at
  // most, and the heartbeat itself.
  EXPECT_LT(most, (1 << 20) + 64 * 1024 + 4096);
  EXPECT_GT(most, 0);
  EXPECT_GE(all.back().blob_bytes_sent, static_cast<std::int64_t>(model.bin.size()));
}

}  // namespace
}  // namespace rdtf::itest
