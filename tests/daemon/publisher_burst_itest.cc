// The publisher's first burst fits a receiving socket that has Linux's default buffer and is not
// read at all (a subscriber descheduled for a while): the real kernel decides, on loopback inside
// the test's network namespace. Counting payload bytes, a 128 KiB burst of 8,000-byte chunks
// overflowed it (12 fit), which lost URDF chunks under load (docs/lcm.md, "Pacing").
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstring>
#include <string>

#include <gtest/gtest.h>

#include <rdtf/request_t.hpp>

#include "publisher.h"

namespace rdtf::daemon {
namespace {

using Clock = std::chrono::steady_clock;

// Linux's default net.core.rmem_default; SO_RCVBUF asks for half, the kernel doubles it.
constexpr int kDefaultReceiveBuffer = 212992;
constexpr std::size_t kBurst = 128 * 1024;  // As rdtfd configures its publisher.

class UdpSocket {
 public:
  UdpSocket() : fd_(::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK, 0)) {}
  ~UdpSocket() {
    if (fd_ >= 0) ::close(fd_);
  }
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;
  int fd() const { return fd_; }

 private:
  int fd_;
};

struct Receiver {
  UdpSocket socket;
  sockaddr_in address{};

  Receiver() {
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    const int half = kDefaultReceiveBuffer / 2;
    EXPECT_EQ(::setsockopt(socket.fd(), SOL_SOCKET, SO_RCVBUF, &half, sizeof(half)), 0) << std::strerror(errno);
    EXPECT_EQ(::bind(socket.fd(), reinterpret_cast<sockaddr*>(&address), sizeof(address)), 0) << std::strerror(errno);
    socklen_t length = sizeof(address);
    EXPECT_EQ(::getsockname(socket.fd(), reinterpret_cast<sockaddr*>(&address), &length), 0);
  }
  int buffer_size() const {
    int size = 0;
    socklen_t length = sizeof(size);
    ::getsockopt(socket.fd(), SOL_SOCKET, SO_RCVBUF, &size, &length);
    return size;
  }
  // Datagrams waiting in the socket, each checked to be `size` bytes long.
  int drain(std::size_t size) {
    std::vector<char> buffer(70000);
    int count = 0;
    for (;;) {
      const auto got = ::recv(socket.fd(), buffer.data(), buffer.size(), 0);
      if (got < 0) break;
      EXPECT_EQ(static_cast<std::size_t>(got), size);
      ++count;
    }
    return count;
  }
};

// An LCM message whose encoding is exactly `size` bytes.
rdtf::request_t message_of(std::size_t size) {
  rdtf::request_t message;
  message.utime = 0;
  const std::size_t overhead = rdtf::request_t().getEncodedSize();
  message.requester = std::string(size - overhead, 'x');
  EXPECT_EQ(static_cast<std::size_t>(message.getEncodedSize()), size);
  return message;
}

class PublisherBurst : public ::testing::TestWithParam<std::size_t> {};

TEST_P(PublisherBurst, TheFirstBurstFitsAnUnreadSocketWithTheDefaultBuffer) {
  const std::size_t payload = GetParam();
  Receiver receiver;
  ASSERT_EQ(receiver.buffer_size(), kDefaultReceiveBuffer);
  UdpSocket sender;
  // As LCM's small-message datagram: an 8-byte header and the channel name before the payload.
  const std::string channel = "RDTF/model.gltf/URDF_CHUNK";
  const std::size_t datagram = 8 + channel.size() + 1 + payload;
  Publisher publisher(
      [&](const std::string& name, const std::uint8_t* data, unsigned int size) {
        std::vector<std::uint8_t> bytes(8, 0);
        bytes.insert(bytes.end(), name.begin(), name.end());
        bytes.push_back(0);
        bytes.insert(bytes.end(), data, data + size);
        const auto sent = ::sendto(sender.fd(), bytes.data(), bytes.size(), 0,
                                   reinterpret_cast<const sockaddr*>(&receiver.address), sizeof(receiver.address));
        return sent == static_cast<ssize_t>(bytes.size()) ? 0 : -1;
      },
      32e6, kBurst);
  constexpr int kQueued = 400;
  const auto message = message_of(payload);
  for (int i = 0; i < kQueued; ++i) publisher.publish(channel, message);

  const auto next = publisher.drain(Clock::now());
  ASSERT_TRUE(next.has_value()) << "the whole queue went in one burst: nothing was paced";
  const int sent = kQueued - static_cast<int>(publisher.queued());
  ASSERT_FALSE(publisher.failing());
  EXPECT_GE(sent, 1);
  // Nobody read the socket: every datagram of the burst must still be there.
  EXPECT_EQ(receiver.drain(datagram), sent) << sent << " datagrams of " << datagram << " bytes sent at once";
}

// From LCM's smallest messages to one datagram's worth (max_chunk_bytes is at most 65,000).
INSTANTIATE_TEST_SUITE_P(Sizes, PublisherBurst, ::testing::Values(100, 300, 1000, 4000, 8000, 16000, 30000, 60000),
                         [](const auto& param_info) { return std::to_string(param_info.param) + "_bytes"; });

}  // namespace
}  // namespace rdtf::daemon
