// rdtf-view's HTTP and WebSocket server: Boost.Beast on one asio io_context, the same thread that
// dispatches LCM (main.cc), so the hub and the client library need no lock.
//
// HTTP: GET only (http_paths.h routes): the page and its modules from the web folder, three.js
// from the web folder's node_modules/three, and the files of recent model revisions from the
// blobs the client library fetched (nothing of a model is read from disk). Requests larger than
// 8 KiB of headers, with a body, or idle for 30 s are closed.
//
// WebSocket (/ws): the page protocol (docs/view.md). The upgrade must come from this viewer's
// page (check_socket_origin). Each message a page sends is checked (page_protocol.h) and rate
// limited; a refusal is answered with its reason ({"type":"refused"}), at most 20 answers a
// second, the rest counted in the next one. A message over 1 MiB closes the connection ("message
// too big", close code 1009). Outgoing messages queue per connection; a page that falls 32 MiB behind is closed
// (a slow page must not make the viewer hold the bus's traffic for it).
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <set>
#include <string>

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>

#include "model_hub.h"

namespace rdtf::view {

struct ServerOptions {
  std::filesystem::path web_dir;  // index.html, *.js, node_modules/three
  bool loopback_only = true;      // bound to a loopback address: Host must name loopback
  double page_rate = 200;         // messages a second a page may send (burst twice that)
};

struct ServerStats {
  std::uint64_t http_requests = 0;
  std::uint64_t sockets_opened = 0;
  std::uint64_t page_messages = 0;
  std::uint64_t refused = 0;
  std::uint64_t connections_accepted = 0;
  // Accepts that failed for want of a resource (descriptors, buffers): each is retried after
  // kAcceptRetry, not at once, or the failing accept would spin a core until a descriptor frees.
  std::uint64_t accept_failures = 0;
};

// How long the server waits before accepting again after running out of descriptors or memory.
inline constexpr std::chrono::milliseconds kAcceptRetry{100};

class Server {
 public:
  // Listens on `endpoint` (port 0: any free port; port() says which).
  Server(boost::asio::io_context& io, const boost::asio::ip::tcp::endpoint& endpoint, ServerOptions options,
         ModelHub& hub);
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  std::uint16_t port() const;
  // Sends a message to every open page.
  void broadcast(const std::shared_ptr<const std::string>& json);
  // Sends a model's state message to every open page; one still waiting for a page's socket is
  // replaced by the newer one (a page that reads slowly gets the newest states, not a backlog).
  void broadcast_state(const std::string& model_id, const std::shared_ptr<const std::string>& json);
  const ServerStats& stats() const;

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace rdtf::view
