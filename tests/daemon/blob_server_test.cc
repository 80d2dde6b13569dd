// The blob server on its own (daemon/blob_server.h): files in a temporary output folder, a
// Publisher whose sends are recorded, the clock stepped by hand. What goes out is decoded and
// checked chunk by chunk against the files.
#include <sys/stat.h>
#include <unistd.h>

#include <openssl/evp.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include <rdtf/blob_chunk_t.hpp>
#include <rdtf/blob_unavailable_t.hpp>

#include "blob_manifest.h"
#include "blob_server.h"
#include "support/test_support.h"

namespace rdtf::daemon {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using namespace std::chrono_literals;

std::string sha256(const std::string& bytes) {
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_Digest(bytes.data(), bytes.size(), digest, &length, EVP_sha256(), nullptr);
  static const char* const kHex = "0123456789abcdef";
  std::string out;
  for (unsigned int i = 0; i < length; ++i) {
    out += kHex[digest[i] >> 4];
    out += kHex[digest[i] & 15];
  }
  return out;
}

std::string random_bytes(std::size_t size, unsigned seed) {
  std::mt19937_64 random(seed);
  std::string out(size, '\0');
  for (char& c : out) c = static_cast<char>(random() & 0xff);
  return out;
}

void write(const fs::path& path, const std::string& bytes) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << bytes;
}

struct Sent {
  std::vector<rdtf::blob_chunk_t> chunks;
  std::vector<rdtf::blob_unavailable_t> unavailable;
};

struct Fixture {
  testing::TempDir root;
  fs::path output = root / "out";
  Sent sent;
  std::vector<std::string> log;
  Publisher publisher{[this](const std::string& channel, const std::uint8_t* data, unsigned int size) {
                        if (channel == "RDTF/BLOB") {
                          rdtf::blob_chunk_t chunk;
                          EXPECT_GE(chunk.decode(data, 0, static_cast<int>(size)), 0);
                          sent.chunks.push_back(std::move(chunk));
                        } else {
                          EXPECT_EQ(channel, "RDTF/BLOB_UNAVAILABLE");
                          rdtf::blob_unavailable_t message;
                          EXPECT_GE(message.decode(data, 0, static_cast<int>(size)), 0);
                          sent.unavailable.push_back(std::move(message));
                        }
                        return 0;
                      },
                      1e12, std::size_t{1} << 40};
  BlobServer server{[this](const std::string& line) { log.push_back(line); }};
  Clock::time_point now = Clock::time_point{} + 1h;

  Fixture() { server.set_max_message_bytes(1024); }

  // A model "m" whose output folder holds `files` (path -> bytes).
  std::vector<OutputFile> model(const std::map<std::string, std::string>& files, const std::string& id = "m") {
    std::vector<OutputFile> listed;
    for (const auto& [path, bytes] : files) {
      write(output / id / path, bytes);
      listed.push_back({path, sha256(bytes), static_cast<std::int64_t>(bytes.size()), "buffer"});
    }
    server.set_model(id, output / id, listed);
    return listed;
  }
  std::string ask(const std::vector<std::tuple<std::string, std::int32_t, std::int32_t>>& ranges,
                  const std::string& requester = "test") {
    rdtf::blob_request_t request;
    request.utime = 0;
    request.requester = requester;
    request.num_ranges = static_cast<std::int32_t>(ranges.size());
    for (const auto& [sha, first, count] : ranges) {
      request.sha256.push_back(sha);
      request.first_chunk.push_back(first);
      request.num_chunks.push_back(count);
    }
    return server.request(request, now, publisher, "RDTF");
  }
  // Pumps and sends until nothing is left.
  void run() {
    for (int i = 0; i < 100000 && (server.jobs() > 0 || publisher.queued() > 0); ++i) {
      server.pump(publisher, "RDTF");
      now += 1ms;
      publisher.drain(now);
    }
  }
  std::string reassemble(const std::string& sha) const {
    std::map<std::int32_t, std::string> chunks;
    for (const auto& c : sent.chunks) {
      if (c.sha256 == sha) chunks[c.index] = std::string(c.data.begin(), c.data.end());
    }
    std::string bytes;
    for (const auto& [index, data] : chunks) bytes += data;
    return bytes;
  }
  std::string reason(const std::string& sha) const {
    for (const auto& m : sent.unavailable) {
      for (std::size_t i = 0; i < m.sha256.size(); ++i) {
        if (m.sha256[i] == sha) return m.reason[i];
      }
    }
    return "";
  }
};

TEST(BlobServer, WholeBlobGoesInChunksThatFitTheMessageSizeAndReassemble) {
  Fixture f;
  const std::string bytes = random_bytes(5000, 1);
  const auto files = f.model({{"a.bin", bytes}, {"empty.bin", ""}});
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}, {sha256(""), 0, -1}}), "");
  f.run();
  const std::int32_t chunk = f.server.chunk_size();
  ASSERT_GT(chunk, 0);
  std::size_t of_a = 0;
  for (const auto& c : f.sent.chunks) {
    EXPECT_LE(c.getEncodedSize(), 1024);
    EXPECT_EQ(c.chunk_size, chunk);
    if (c.sha256 != sha256(bytes)) continue;
    ++of_a;
    EXPECT_EQ(c.count, (5000 + chunk - 1) / chunk);
    EXPECT_EQ(c.blob_size, 5000);
  }
  EXPECT_EQ(of_a, static_cast<std::size_t>((5000 + chunk - 1) / chunk));
  EXPECT_EQ(f.reassemble(sha256(bytes)), bytes);
  // An empty blob is one chunk of 0 bytes.
  std::size_t of_empty = 0;
  for (const auto& c : f.sent.chunks) {
    if (c.sha256 == sha256("")) {
      ++of_empty;
      EXPECT_EQ(c.count, 1);
      EXPECT_EQ(c.size, 0);
    }
  }
  EXPECT_EQ(of_empty, 1u);
  EXPECT_TRUE(f.sent.unavailable.empty());
  EXPECT_EQ(f.server.counters().requests, 1);
  EXPECT_EQ(f.server.counters().bytes_sent, 5000);
}

TEST(BlobServer, RangesSendOnlyTheirChunks) {
  Fixture f;
  const std::string bytes = random_bytes(10000, 2);
  f.model({{"a.bin", bytes}});
  const std::int32_t chunk = f.server.chunk_size();
  const std::int32_t count = (10000 + chunk - 1) / chunk;
  ASSERT_GE(count, 8);
  EXPECT_EQ(f.ask({{sha256(bytes), 2, 3}, {sha256(bytes), count - 1, 1000000}}), "");
  f.run();
  std::multiset<std::int32_t> indices;
  for (const auto& c : f.sent.chunks) {
    indices.insert(c.index);
    const auto begin = static_cast<std::size_t>(c.index) * static_cast<std::size_t>(chunk);
    EXPECT_EQ(std::string(c.data.begin(), c.data.end()), bytes.substr(begin, static_cast<std::size_t>(chunk)));
  }
  EXPECT_EQ(indices, (std::multiset<std::int32_t>{2, 3, 4, count - 1}));
  // Beyond the last chunk: well formed, answered unavailable with the blob's chunk count.
  EXPECT_EQ(f.ask({{sha256(bytes), count, 1}}), "");
  f.run();
  EXPECT_EQ(f.reason(sha256(bytes)), "chunk " + std::to_string(count) + " asked for, but the blob has " +
                                         std::to_string(count) + " chunks of " + std::to_string(chunk) + " bytes");
}

TEST(BlobServer, IdenticalRequestsWhileItsChunksWaitInTheQueueAreServedOnce) {
  Fixture f;
  const std::string bytes = random_bytes(20000, 3);
  f.model({{"a.bin", bytes}});
  const std::int32_t count = (20000 + f.server.chunk_size() - 1) / f.server.chunk_size();
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}}, "one"), "");
  f.server.pump(f.publisher, "RDTF");  // Every chunk queued, none sent yet.
  EXPECT_EQ(f.publisher.queued(), static_cast<std::size_t>(count));
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}}, "two"), "");
  EXPECT_EQ(f.ask({{sha256(bytes), 3, 2}}, "three"), "");
  f.server.pump(f.publisher, "RDTF");
  EXPECT_EQ(f.publisher.queued(), static_cast<std::size_t>(count));
  EXPECT_EQ(f.server.counters().chunks_sent, count);
  f.run();
  EXPECT_EQ(f.sent.chunks.size(), static_cast<std::size_t>(count));
  // Once they are sent, a new request gets them again (its sender may have missed them).
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}}, "four"), "");
  f.run();
  EXPECT_EQ(f.sent.chunks.size(), 2 * static_cast<std::size_t>(count));
  EXPECT_EQ(f.server.counters().requests, 4);
}

TEST(BlobServer, ChunksAlreadySentAreSentAgainThoseStillQueuedAreNot) {
  Fixture f;
  const std::string bytes = random_bytes(20000, 4);
  f.model({{"a.bin", bytes}});
  const std::int32_t count = (20000 + f.server.chunk_size() - 1) / f.server.chunk_size();
  // A publisher that sends two chunks per burst and never refills (a slow rate, a frozen clock).
  Publisher slow([&](const std::string&, const std::uint8_t*, unsigned int) { return 0; }, 1e-9,
                 static_cast<std::size_t>(2 * receive_buffer_cost(1024)));
  rdtf::blob_request_t request;
  request.utime = 0;
  request.requester = "a";
  request.num_ranges = 1;
  request.sha256 = {sha256(bytes)};
  request.first_chunk = {0};
  request.num_chunks = {-1};
  EXPECT_EQ(f.server.request(request, f.now, slow, "RDTF"), "");
  f.server.pump(slow, "RDTF");
  slow.drain(f.now);
  EXPECT_EQ(slow.departed(), 2u);
  EXPECT_EQ(f.server.request(request, f.now, slow, "RDTF"), "");
  f.server.pump(slow, "RDTF");
  EXPECT_EQ(f.server.counters().chunks_sent, count + 2);
}

TEST(BlobServer, MalformedRequestsAreDroppedWithTheirReason) {
  Fixture f;
  const std::string bytes = random_bytes(100, 5);
  f.model({{"a.bin", bytes}});
  const std::string sha = sha256(bytes);
  std::string upper = sha;
  for (char& c : upper) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  EXPECT_EQ(f.ask({{upper, 0, -1}}), "blob request from 'test': range 0: sha256 '" + upper +
                                         "' is not 64 lowercase hex digits");
  EXPECT_EQ(f.ask({{sha, -1, 1}}), "blob request from 'test': range 0: first_chunk -1 is negative");
  EXPECT_EQ(f.ask({{sha, 0, 0}}), "blob request from 'test': range 0: num_chunks 0 is neither -1 (to the end) nor positive");
  EXPECT_EQ(f.ask({{sha, 0, -2}}), "blob request from 'test': range 0: num_chunks -2 is neither -1 (to the end) nor positive");
  EXPECT_EQ(f.ask({}), "blob request from 'test': no blobs asked for");
  std::vector<std::tuple<std::string, std::int32_t, std::int32_t>> many(257, {sha, 0, -1});
  EXPECT_EQ(f.ask(many), "blob request from 'test': 257 ranges, over the limit of 256 per request");
  EXPECT_EQ(f.ask({{sha, 0, -1}, {"zz", 0, -1}}), "blob request from 'test': range 1: sha256 'zz' is not 64 lowercase hex digits");
  EXPECT_EQ(f.server.counters().dropped, 7);
  EXPECT_EQ(f.server.counters().requests, 0);
  f.run();
  EXPECT_TRUE(f.sent.chunks.empty()) << "a dropped request serves nothing, not even its good ranges";
}

TEST(BlobServer, RequestsBeyondTheRateOfOneRequesterAreDropped) {
  Fixture f;
  const std::string bytes = random_bytes(100, 6);
  f.model({{"a.bin", bytes}});
  int dropped = 0;
  for (int i = 0; i < 150; ++i) dropped += f.ask({{sha256(bytes), 0, -1}}, "flood").empty() ? 0 : 1;
  EXPECT_EQ(dropped, 150 - static_cast<int>(BlobServer::kRequestBurst));
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}}, "flood"), "blob request from 'flood': over the limit of 50 requests/s per requester and 500 in all");
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}}, "someone else"), "");
  f.now += 1s;  // 50 more for the flood.
  int taken = 0;
  for (int i = 0; i < 60; ++i) taken += f.ask({{sha256(bytes), 0, -1}}, "flood").empty() ? 1 : 0;
  EXPECT_EQ(taken, 50);
}

TEST(BlobServer, UnavailableAnswersAreBoundedPerSecond) {
  Fixture f;
  f.model({{"a.bin", "a"}});
  // 20 requests of 256 unknown hashes each: 5,120 answers asked for, 4,000 at once allowed.
  for (int r = 0; r < 20; ++r) {
    std::vector<std::tuple<std::string, std::int32_t, std::int32_t>> ranges;
    for (int i = 0; i < 256; ++i) ranges.emplace_back(sha256(std::to_string(r * 1000 + i)), 0, -1);
    EXPECT_EQ(f.ask(ranges), "");
  }
  f.run();
  std::size_t answered = 0;
  for (const auto& m : f.sent.unavailable) {
    EXPECT_LE(m.getEncodedSize(), 1024);
    answered += m.sha256.size();
  }
  EXPECT_EQ(answered, static_cast<std::size_t>(BlobServer::kUnavailableBurst));
  EXPECT_EQ(f.server.counters().unavailable, static_cast<std::int64_t>(BlobServer::kUnavailableBurst));
  EXPECT_EQ(f.server.counters().dropped, 5);  // The requests that had answers left out.
  f.now += 1s;  // 2,000 more.
  EXPECT_EQ(f.ask({{sha256("later"), 0, -1}}), "");
  f.run();
  EXPECT_EQ(f.reason(sha256("later")), "not a file of any live revision");
}

TEST(BlobServer, UnknownChangedAndLinkedFilesAreUnavailable) {
  Fixture f;
  const std::string good = random_bytes(3000, 7);
  const std::string changed = random_bytes(3000, 8);
  const std::string linked = random_bytes(3000, 9);
  f.model({{"good.bin", good}, {"changed.bin", changed}, {"sub/linked.bin", linked}});
  // Changed in place after the manifest (same size), and a folder swapped for a symlink.
  write(f.output / "m" / "changed.bin", random_bytes(3000, 10));
  fs::rename(f.output / "m" / "sub", f.root / "elsewhere");
  fs::create_directory_symlink(f.root / "elsewhere", f.output / "m" / "sub");
  const std::string unknown = sha256("unknown");
  EXPECT_EQ(f.ask({{sha256(good), 0, -1}, {sha256(changed), 0, -1}, {sha256(linked), 0, -1}, {unknown, 0, -1}},
                  "asker"),
            "");
  f.run();
  EXPECT_EQ(f.reassemble(sha256(good)), good);
  EXPECT_EQ(f.reason(unknown), "not a file of any live revision");
  EXPECT_EQ(f.reason(sha256(changed)), "it changed on disk: its bytes no longer have the manifest's SHA-256");
  EXPECT_NE(f.reason(sha256(linked)).find("a symbolic link is never followed"), std::string::npos)
      << f.reason(sha256(linked));
  for (const auto& c : f.sent.chunks) {
    EXPECT_EQ(c.sha256, sha256(good)) << "nothing of a file that failed its check is sent";
  }
  for (const auto& m : f.sent.unavailable) EXPECT_EQ(m.requester, "asker");
  EXPECT_EQ(f.server.counters().unavailable, 3);
  ASSERT_FALSE(f.log.empty());
}

TEST(BlobServer, OnlyTheLiveRevisionIsServed) {
  Fixture f;
  const std::string old_bytes = random_bytes(500, 11);
  const std::string kept = random_bytes(500, 12);
  const std::string new_bytes = random_bytes(500, 13);
  f.model({{"old.bin", old_bytes}, {"kept.bin", kept}});
  f.model({{"new.bin", new_bytes}, {"kept.bin", kept}});  // Revision 2 goes live.
  EXPECT_EQ(f.ask({{sha256(old_bytes), 0, -1}, {sha256(kept), 0, -1}, {sha256(new_bytes), 0, -1}}), "");
  f.run();
  EXPECT_EQ(f.reason(sha256(old_bytes)), "not a file of any live revision");
  EXPECT_EQ(f.reassemble(sha256(kept)), kept);
  EXPECT_EQ(f.reassemble(sha256(new_bytes)), new_bytes);
  // A blob two models share stays while either lists it.
  f.model({{"kept.bin", kept}}, "other");
  f.server.remove_model("m");
  EXPECT_NE(f.server.index().find(sha256(kept)), nullptr);
  EXPECT_EQ(f.server.index().find(sha256(new_bytes)), nullptr);
  f.server.remove_model("other");
  EXPECT_EQ(f.server.index().size(), 0u);
}

TEST(BlobServer, ALargeBlobIsReadAsTheQueueDrainsWithinItsBound) {
  Fixture f;
  f.server.set_max_message_bytes(60000);
  const std::string bytes = random_bytes(8 << 20, 14);
  f.model({{"big.bin", bytes}});
  EXPECT_EQ(f.ask({{sha256(bytes), 0, -1}}), "");
  // Sending at a paced rate: a burst of 4 chunks per millisecond.
  Publisher paced([&](const std::string& channel, const std::uint8_t* data, unsigned int size) {
                    rdtf::blob_chunk_t chunk;
                    EXPECT_EQ(channel, "RDTF/BLOB");
                    EXPECT_GE(chunk.decode(data, 0, static_cast<int>(size)), 0);
                    f.sent.chunks.push_back(std::move(chunk));
                    return 0;
                  },
                  4 * receive_buffer_cost(60000) * 1000, static_cast<std::size_t>(4 * receive_buffer_cost(60000)));
  std::size_t most = 0;
  for (int i = 0; i < 100000 && (f.server.jobs() > 0 || paced.queued() > 0); ++i) {
    f.server.pump(paced, "RDTF");
    most = std::max(most, paced.queued_bytes());
    f.now += 1ms;
    paced.drain(f.now);
  }
  EXPECT_EQ(f.server.jobs(), 0u);
  EXPECT_LE(most, BlobServer::kQueueBytes + 60000);
  EXPECT_GE(most, BlobServer::kQueueBytes);
  EXPECT_TRUE(f.reassemble(sha256(bytes)) == bytes);
}

// A model whose image is missing converts (IMAGE_NOT_COPIED) and its output keeps the image's own
// URI: that file is not in the output and is left out of the manifest, and every other file is
// listed. The whole manifest was empty, so nothing of the model could be had from the bus
// (s80client D2).
TEST(OutputFiles, AnImageTheConversionCouldNotCopyIsLeftOutNotTheWholeManifest) {
  DigestLog log;
  const std::string bytes = "buffer bytes";
  const std::string hex = log.digest()(std::span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size()));
  const std::string bin = "arm." + hex.substr(0, 16) + ".bin";
  const std::string json = R"({"buffers": [{"uri": ")" + bin + R"(", "byteLength": 12}], "images": [{"uri": "tex/missing.png"}]})";
  std::string why;
  const auto files = output_files("arm.rdtf.gltf", json, "", log, why);
  EXPECT_TRUE(why.empty()) << why;
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].path, "arm.rdtf.gltf");
  EXPECT_EQ(files[1].path, bin);
  EXPECT_EQ(files[1].sha256, hex);
  // A content-addressed file the conversion did not write is still no manifest at all.
  const std::string stray = R"({"buffers": [{"uri": "arm.0123456789abcdef.bin"}]})";
  EXPECT_TRUE(output_files("arm.rdtf.gltf", stray, "", log, why).empty());
  EXPECT_FALSE(why.empty());
}

}  // namespace
}  // namespace rdtf::daemon
