#include "server.h"

#include <cerrno>
#include <chrono>
#include <deque>
#include <map>
#include <fstream>
#include <iostream>
#include <sstream>
#include <variant>

#include <boost/asio/steady_timer.hpp>
#include <boost/asio/strand.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "http_paths.h"
#include "page_protocol.h"
#include "rdtf/shortage.h"

namespace rdtf::view {
namespace {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using namespace std::chrono_literals;

// Above kMaxPageMessageBytes a message is refused with its reason; above this it closes the socket
// (Beast sends close code 1009, though a peer still sending may see the reset first).
constexpr std::size_t kMaxSocketMessageBytes = std::size_t{1} << 20;
constexpr std::size_t kMaxQueuedBytes = std::size_t{32} << 20;
constexpr int kRefusalAnswersPerSecond = 20;

std::string_view sv(beast::string_view text) { return std::string_view(text.data(), text.size()); }

double seconds_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::optional<std::string> read_file(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) return std::nullopt;  // A folder opens, and reads as empty.
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

}  // namespace

class SocketSession;

struct Server::Impl {
  Impl(asio::io_context& context, ServerOptions server_options, ModelHub& model_hub)
      : io(context), acceptor(context), options(std::move(server_options)), hub(model_hub) {}
  asio::io_context& io;
  tcp::acceptor acceptor;
  ServerOptions options;
  ModelHub& hub;
  ServerStats stats;
  std::set<std::shared_ptr<SocketSession>> sockets;
  bool stopped = false;
  std::weak_ptr<Impl> self;
  asio::steady_timer accept_retry{io};
  std::uint64_t failures_in_a_row = 0;
  void accept();
};

// One WebSocket: the page protocol.
class SocketSession : public std::enable_shared_from_this<SocketSession> {
 public:
  SocketSession(tcp::socket socket, std::shared_ptr<Server::Impl> server)
      : ws_(std::move(socket)), server_(std::move(server)), limiter_(server_->options.page_rate, 2 * server_->options.page_rate) {}

  void run(http::request<http::string_body> request) {
    auto timeouts = websocket::stream_base::timeout::suggested(beast::role_type::server);
    timeouts.idle_timeout = 60s;  // with pings: a page whose host vanished is closed
    timeouts.keep_alive_pings = true;
    ws_.set_option(timeouts);
    ws_.read_message_max(kMaxSocketMessageBytes);
    ws_.async_accept(request, beast::bind_front_handler(&SocketSession::on_accept, shared_from_this()));
  }

  void send(const std::shared_ptr<const std::string>& message) {
    if (closed_) return;
    queued_bytes_ += message->size();
    if (queued_bytes_ > kMaxQueuedBytes) {
      std::cerr << "rdtf-view: a page fell " << (kMaxQueuedBytes >> 20) << " MiB behind: closing it\n";
      close();
      return;
    }
    queue_.push_back(message);
    write_next();
  }

  // The newest state of a model: replaces one of the same model not sent yet.
  void send_state(const std::string& model_id, const std::shared_ptr<const std::string>& message) {
    if (closed_) return;
    auto [it, added] = states_.try_emplace(model_id, message);
    if (added) {
      state_order_.push_back(model_id);
    } else {
      queued_bytes_ -= it->second->size();
      it->second = message;
    }
    queued_bytes_ += message->size();
    write_next();
  }

  void close() {
    if (closed_) return;
    closed_ = true;
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().close(ignored);
    server_->sockets.erase(shared_from_this());
  }

 private:
  void on_accept(beast::error_code ec) {
    if (ec || server_->stopped) return;
    server_->sockets.insert(shared_from_this());
    ++server_->stats.sockets_opened;
    for (const auto& message : server_->hub.welcome()) send(message);
    read();
  }

  void read() {
    ws_.async_read(buffer_, beast::bind_front_handler(&SocketSession::on_read, shared_from_this()));
  }

  void on_read(beast::error_code ec, std::size_t) {
    if (ec) {
      // A page that closed, vanished mid-message, or sent more than kMaxSocketMessageBytes
      // (websocket::error::message_too_big: Beast answers with close code 1009).
      if (ec != websocket::error::closed && ec != asio::error::operation_aborted) {
        std::cerr << "rdtf-view: page connection ended: " << ec.message() << "\n";
      }
      close();
      return;
    }
    const std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    ++server_->stats.page_messages;
    handle(text, ws_.got_text());
    if (!closed_) read();
  }

  void handle(const std::string& text, bool is_text) {
    if (!limiter_.allow(seconds_now())) {
      refuse("too many messages: more than " + std::to_string(static_cast<int>(server_->options.page_rate)) +
             " a second");
      return;
    }
    if (!is_text) {
      refuse("binary message: the page protocol is JSON text");
      return;
    }
    const PageRequest request = parse_page_message(text, server_->hub.catalog());
    std::string why;
    if (const auto* refusal = std::get_if<Refusal>(&request)) {
      why = refusal->reason;
    } else if (const auto* set = std::get_if<SetJoint>(&request)) {
      why = server_->hub.apply(*set);
    } else {
      why = server_->hub.apply(std::get<Release>(request));
    }
    if (!why.empty()) refuse(why);
  }

  // Answers a refusal with its reason, at most kRefusalAnswersPerSecond a second; the ones left
  // unanswered are counted in the next answer.
  void refuse(const std::string& reason) {
    ++server_->stats.refused;
    const auto second = static_cast<std::int64_t>(seconds_now());
    if (second != refusal_second_) {
      refusal_second_ = second;
      refusals_this_second_ = 0;
    }
    if (++refusals_this_second_ > kRefusalAnswersPerSecond) {
      ++unanswered_;
      return;
    }
    nlohmann::json answer = {{"type", "refused"}, {"reason", reason}, {"unanswered_before", unanswered_}};
    unanswered_ = 0;
    send(std::make_shared<const std::string>(answer.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)));
  }

  // One write at a time: the queued messages in order, then the states waiting (oldest model first).
  void write_next() {
    if (writing_ || closed_) return;
    if (!queue_.empty()) {
      writing_ = queue_.front();
      queue_.pop_front();
    } else if (!state_order_.empty()) {
      const auto state = states_.find(state_order_.front());
      state_order_.pop_front();
      writing_ = state->second;
      states_.erase(state);
    } else {
      return;
    }
    ws_.text(true);
    ws_.async_write(asio::buffer(*writing_), beast::bind_front_handler(&SocketSession::on_write, shared_from_this()));
  }

  void on_write(beast::error_code ec, std::size_t) {
    if (ec) {
      close();
      return;
    }
    queued_bytes_ -= writing_->size();
    writing_.reset();
    write_next();
  }

  websocket::stream<beast::tcp_stream> ws_;
  std::shared_ptr<Server::Impl> server_;
  beast::flat_buffer buffer_;
  std::deque<std::shared_ptr<const std::string>> queue_;
  std::map<std::string, std::shared_ptr<const std::string>> states_;  // by model id, not sent yet
  std::deque<std::string> state_order_;
  std::shared_ptr<const std::string> writing_;  // the message being written (the buffer Beast reads)
  std::size_t queued_bytes_ = 0;
  bool closed_ = false;
  RateLimiter limiter_;
  std::int64_t refusal_second_ = -1;
  int refusals_this_second_ = 0;
  std::uint64_t unanswered_ = 0;
};

// One HTTP connection: GETs until it closes, or its upgrade to a WebSocket.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(tcp::socket socket, std::shared_ptr<Server::Impl> server)
      : stream_(std::move(socket)), server_(std::move(server)) {}

  void read() {
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(0);  // GET has no body
    stream_.expires_after(30s);
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&HttpSession::on_read, shared_from_this()));
  }

 private:
  void on_read(beast::error_code ec, std::size_t) {
    if (ec) {
      // end of stream, a timeout, a malformed or oversized request, a client that vanished
      // mid-request: the connection is closed, nothing else happens.
      beast::error_code ignored;
      stream_.socket().shutdown(tcp::socket::shutdown_both, ignored);
      return;
    }
    if (server_->stopped) return;
    ++server_->stats.http_requests;
    auto request = parser_->release();
    const Route r = route(sv(request.target()));
    if (websocket::is_upgrade(request)) {
      if (r.kind != Route::Kind::kSocket) return reply_text(request, http::status::not_found, "no WebSocket here\n");
      const std::string why = check_socket_origin(sv(request[http::field::host]), sv(request[http::field::origin]),
                                                  server_->options.loopback_only, server_->acceptor.local_endpoint().port());
      if (!why.empty()) {
        std::cerr << "rdtf-view: WebSocket refused: " << why << "\n";
        return reply_text(request, http::status::forbidden, why + "\n");
      }
      stream_.expires_never();
      std::make_shared<SocketSession>(stream_.release_socket(), server_)->run(std::move(request));
      return;
    }
    if (request.method() != http::verb::get) return reply_text(request, http::status::method_not_allowed, "GET only\n");
    const auto& web = server_->options.web_dir;
    switch (r.kind) {
      case Route::Kind::kPage:
      case Route::Kind::kApp:
        return reply_file(request, web / r.path, r.path);
      case Route::Kind::kThree:
        return reply_file(request, web / "node_modules" / "three" / r.path, r.path);
      case Route::Kind::kModelFile: {
        auto bytes = server_->hub.file(r.model_id, r.revision, r.path);
        if (!bytes) {
          return reply_text(request, http::status::not_found,
                            "no file '" + r.path + "' in the recent revisions of model '" + r.model_id + "'\n");
        }
        // And sandboxed, should a browser still render one as a document: no script, no origin.
        return reply_bytes(request, std::move(bytes), model_file_content_type(r.path), "max-age=3600, immutable",
                           http::status::ok, "sandbox; default-src 'none'");
      }
      case Route::Kind::kSocket:
        return reply_text(request, http::status::upgrade_required, "WebSocket only\n");
      case Route::Kind::kNotFound:
        return reply_text(request, http::status::not_found, r.why + "\n");
    }
  }

  void reply_file(const http::request<http::string_body>& request, const std::filesystem::path& path,
                  const std::string& name) {
    auto bytes = read_file(path);
    if (!bytes) return reply_text(request, http::status::not_found, "no file " + name + "\n");
    reply_bytes(request, std::make_shared<const std::string>(std::move(*bytes)), content_type(name), "no-cache");
  }

  void reply_text(const http::request<http::string_body>& request, http::status status, const std::string& text) {
    reply_bytes(request, std::make_shared<const std::string>(text), "text/plain; charset=utf-8", "no-store", status);
  }

  void reply_bytes(const http::request<http::string_body>& request, std::shared_ptr<const std::string> bytes,
                   const std::string& type, const std::string& cache, http::status status = http::status::ok,
                   const char* content_security_policy = nullptr) {
    auto response = std::make_shared<http::response<http::span_body<const char>>>(status, request.version());
    response->set(http::field::server, "rdtf-view");
    response->set(http::field::content_type, type);
    if (content_security_policy) response->set("Content-Security-Policy", content_security_policy);
    response->set(http::field::cache_control, cache);
    response->set("X-Content-Type-Options", "nosniff");
    response->body() = http::span_body<const char>::value_type(bytes->data(), bytes->size());
    response->keep_alive(request.keep_alive());
    response->prepare_payload();
    http::async_write(stream_, *response,
                      [self = shared_from_this(), response, bytes](beast::error_code ec, std::size_t) {
                        if (ec) return;
                        if (response->need_eof()) {
                          beast::error_code ignored;
                          self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
                          return;
                        }
                        self->read();
                      });
  }

  beast::tcp_stream stream_;
  std::shared_ptr<Server::Impl> server_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
};

// An accept that fails for want of a descriptor or of memory (rdtf/shortage.h) leaves the
// connection waiting in the backlog, so accepting again at once fails again at once: a loop that
// holds a core until some descriptor is freed. Those are retried after kAcceptRetry, and said once
// when they start and once when they end.
static bool out_of_resources(const beast::error_code& ec) {
  return ec.category() == beast::system_category() && rdtf::is_shortage(ec.value());
}

void Server::Impl::accept() {
  // The handler holds the Impl: the acceptor's pending accept never outlives it.
  acceptor.async_accept([impl = self.lock()](beast::error_code ec, tcp::socket socket) {
    if (impl->stopped) return;
    if (!ec) {
      ++impl->stats.connections_accepted;
      if (impl->failures_in_a_row > 0) {
        std::cerr << "rdtf-view: accepting connections again after " << impl->failures_in_a_row
                  << " attempts failed\n";
        impl->failures_in_a_row = 0;
      }
      // Without TCP_NODELAY a small message (a state, a revision) sent while an earlier one is
      // unacknowledged waits for the browser's delayed ACK: 40 ms on Linux (Nagle's algorithm).
      beast::error_code ignored;
      socket.set_option(tcp::no_delay(true), ignored);
      std::make_shared<HttpSession>(std::move(socket), impl)->read();
    } else if (out_of_resources(ec)) {
      ++impl->stats.accept_failures;
      if (impl->failures_in_a_row++ == 0) {
        std::cerr << "rdtf-view: cannot accept a connection: " << ec.message() << "; trying again every "
                  << kAcceptRetry.count() << " ms\n";
      }
      impl->accept_retry.expires_after(kAcceptRetry);
      impl->accept_retry.async_wait([impl](beast::error_code wait_ec) {
        if (!wait_ec && !impl->stopped) impl->accept();
      });
      return;
    }
    impl->accept();
  });
}

Server::Server(asio::io_context& io, const tcp::endpoint& endpoint, ServerOptions options, ModelHub& hub)
    : impl_(std::make_shared<Impl>(io, std::move(options), hub)) {
  impl_->self = impl_;
  impl_->acceptor.open(endpoint.protocol());
  impl_->acceptor.set_option(asio::socket_base::reuse_address(true));
  impl_->acceptor.bind(endpoint);
  impl_->acceptor.listen(asio::socket_base::max_listen_connections);
  impl_->accept();
}

Server::~Server() {
  impl_->stopped = true;
  beast::error_code ignored;
  impl_->acceptor.close(ignored);
  impl_->accept_retry.cancel();
  const auto sockets = impl_->sockets;
  for (const auto& socket : sockets) socket->close();
}

std::uint16_t Server::port() const { return impl_->acceptor.local_endpoint().port(); }

const ServerStats& Server::stats() const { return impl_->stats; }

void Server::broadcast(const std::shared_ptr<const std::string>& json) {
  const auto sockets = impl_->sockets;  // a send may close a socket, which leaves the set
  for (const auto& socket : sockets) socket->send(json);
}

void Server::broadcast_state(const std::string& model_id, const std::shared_ptr<const std::string>& json) {
  const auto sockets = impl_->sockets;
  for (const auto& socket : sockets) socket->send_state(model_id, json);
}

}  // namespace rdtf::view
