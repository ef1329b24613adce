#include "pmg/teleop/vr_server.hpp"

#include <openssl/crypto.h>

#include <algorithm>
#include <boost/asio/dispatch.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <chrono>
#include <cmath>
#include <fstream>
#include <future>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <vector>

#include "pmg/teleop/vr_static_files.hpp"

namespace pmg::teleop {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace ssl = net::ssl;
using tcp = net::ip::tcp;
using Clock = std::chrono::steady_clock;

namespace {

constexpr const char* kServerName = "pmg_vr_bridge";
// Messages are read in chunks; beyond kVrMaxMessageBytes the rest of a message is discarded as it
// arrives (refused as too_large, the session goes on). A message beyond kWsHardLimit ends the
// session (close 1009); Beast's own limit is a backstop above it.
constexpr std::size_t kWsReadChunk = 16 * 1024;
constexpr std::size_t kWsHardLimit = 1024 * 1024;
constexpr std::uint16_t kCloseReplaced = 4001;
constexpr std::uint16_t kCloseBusy = 4002;
constexpr std::uint16_t kCloseUnauthorized = 4003;

std::chrono::nanoseconds seconds(double s) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::duration<double>(s));
}

std::int64_t wallMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void requireRange(const char* field, double v, double lo, double hi) {
  if (!std::isfinite(v) || v < lo || v > hi) {
    std::ostringstream s;
    s << "VrServerOptions." << field << " = " << v << ": expected a finite number in [" << lo << ", " << hi << "]";
    throw std::invalid_argument(s.str());
  }
}

/// Value of @p key in the query part of @p target ("/ws?a=1&token=x"); nullopt if absent.
std::optional<std::string> queryValue(std::string_view target, std::string_view key) {
  const std::size_t q = target.find('?');
  if (q == std::string_view::npos) return std::nullopt;
  std::string_view rest = target.substr(q + 1);
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string_view part = rest.substr(0, amp);
    const std::size_t eq = part.find('=');
    if (part.substr(0, eq) == key) {
      std::string value;
      if (eq == std::string_view::npos || !vrPercentDecode(part.substr(eq + 1), value)) return std::string();
      return value;
    }
    if (amp == std::string_view::npos) break;
    rest = rest.substr(amp + 1);
  }
  return std::nullopt;
}

std::string_view sv(beast::string_view s) { return {s.data(), s.size()}; }

bool sameToken(const std::string& a, const std::string& b) {
  return a.size() == b.size() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

/// Origin "https://host:port" must name the Host header's host:port (a browser always sends Origin
/// on a WebSocket upgrade; other clients may leave it out).
bool originMatchesHost(std::string_view origin, std::string_view host) {
  constexpr std::string_view kScheme = "https://";
  if (origin.substr(0, kScheme.size()) != kScheme || host.empty()) return false;
  return origin.substr(kScheme.size()) == host;
}

}  // namespace

class HttpSession;
class WsSession;

struct VrServer::Impl : std::enable_shared_from_this<VrServer::Impl> {
  VrServerOptions opt;
  VrSampleSink sink;
  net::io_context ioc{1};
  ssl::context tls{ssl::context::tls_server};
  tcp::acceptor acceptor{ioc};
  net::steady_timer accept_retry{ioc};
  std::thread thread;
  std::promise<void> finished;
  std::future<void> finished_future = finished.get_future();
  std::uint16_t bound_port = 0;
  bool started = false;
  bool stopped = false;

  // I/O thread only.
  int connections = 0;
  std::uint64_t next_session_id = 1;
  std::vector<std::weak_ptr<WsSession>> ws_sessions;
  std::vector<std::weak_ptr<HttpSession>> http_sessions;
  std::weak_ptr<WsSession> active;
  bool lcm_ok = true;
  bool any_published = false;
  bool stopping = false;

  mutable std::mutex stats_mutex;
  VrServerStats counters;

  template <class F>
  void count(F&& f) {
    std::lock_guard<std::mutex> lock(stats_mutex);
    f(counters);
  }
  void event(const std::string& line) {
    if (!opt.on_event) return;
    try {
      opt.on_event(line);
    } catch (...) {
      count([](VrServerStats& s) { ++s.internal_errors; });
    }
  }
  void noteError(const std::string& what) {
    count([&](VrServerStats& s) { s.last_error = what; });
  }

  void doAccept();
  void onAccept(beast::error_code ec, tcp::socket socket);
  void shutdown();
  void dropAll();
  /// A new WebSocket session wants to register; returns the close code to send (0: accepted).
  std::uint16_t admit(const std::shared_ptr<WsSession>& s, std::string& reason);
  void forget(const WsSession* s);
  /// Poses of @p s may be published (it is, or becomes, the active session).
  bool mayPublish(const std::shared_ptr<WsSession>& s, Clock::time_point now);
  int liveClients();
};

/// Holds one of max_connections while alive.
struct ConnectionSlot {
  std::shared_ptr<VrServer::Impl> srv;
  explicit ConnectionSlot(std::shared_ptr<VrServer::Impl> s) : srv(std::move(s)) { ++srv->connections; }
  ~ConnectionSlot() { --srv->connections; }
  ConnectionSlot(const ConnectionSlot&) = delete;
  ConnectionSlot& operator=(const ConnectionSlot&) = delete;
};

// ---------------------------------------------------------------------------------------------
// WebSocket session
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(std::shared_ptr<VrServer::Impl> srv, beast::ssl_stream<beast::tcp_stream>&& stream,
            std::unique_ptr<ConnectionSlot> slot, std::string peer)
      : srv_(std::move(srv)),
        ws_(std::move(stream)),
        status_timer_(ws_.get_executor()),
        slot_(std::move(slot)),
        peer_(std::move(peer)),
        id_(srv_->next_session_id++) {}

  ~WsSession() { srv_->forget(this); }

  void run(http::request<http::string_body> req, std::uint16_t refuse_code, std::string refuse_reason) {
    beast::get_lowest_layer(ws_).expires_never();  // the websocket stream has its own timeouts
    websocket::stream_base::timeout t = websocket::stream_base::timeout::suggested(beast::role_type::server);
    t.handshake_timeout = seconds(srv_->opt.handshake_timeout_s);
    t.idle_timeout = seconds(srv_->opt.idle_timeout_s);
    t.keep_alive_pings = true;
    ws_.set_option(t);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(http::field::server, kServerName); }));
    ws_.read_message_max(4 * kWsHardLimit);
    refuse_code_ = refuse_code;
    refuse_reason_ = std::move(refuse_reason);
    ws_.async_accept(req, beast::bind_front_handler(&WsSession::onAccept, shared_from_this()));
  }

  std::uint64_t id() const { return id_; }
  Clock::time_point lastActivity() const { return last_rx_; }
  Clock::time_point lastValid() const { return last_valid_; }
  bool closing() const { return closing_; }

  /// Closing handshake with @p code (a read is pending; Beast allows a close beside it).
  void closeWith(std::uint16_t code, const std::string& reason) {
    if (closing_) return;
    closing_ = true;
    status_timer_.cancel();
    ws_.async_close(websocket::close_reason(static_cast<websocket::close_code>(code), reason),
                    [self = shared_from_this()](beast::error_code) {});
  }

  /// TCP close without a WebSocket closing handshake.
  void drop() {
    closing_ = true;
    status_timer_.cancel();
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(ws_).close();
  }

 private:
  void onAccept(beast::error_code ec) {
    if (ec) {
      srv_->count([](VrServerStats& s) { ++s.ws_errors; });
      srv_->noteError("websocket handshake with " + peer_ + ": " + ec.message());
      return;
    }
    const auto now = Clock::now();
    last_rx_ = now;
    if (refuse_code_ == 0) {
      std::string reason;
      refuse_code_ = srv_->admit(shared_from_this(), reason);
      refuse_reason_ = reason;
    }
    if (refuse_code_ != 0) {
      srv_->count([](VrServerStats& s) { ++s.ws_refused; });
      srv_->event("client " + peer_ + " refused: " + refuse_reason_);
      closeWith(refuse_code_, refuse_reason_);
      doRead();  // reads the client's close frame
      return;
    }
    srv_->count([](VrServerStats& s) { ++s.ws_sessions; });
    srv_->event("client #" + std::to_string(id_) + " connected from " + peer_);
    // The rate window starts at the session's first message (window_start_ is the epoch until then),
    // not at the handshake: a burst right after a slow handshake is counted in one window.
    doRead();
    scheduleStatus();
  }

  void doRead() {
    ws_.async_read_some(buffer_, kWsReadChunk, beast::bind_front_handler(&WsSession::onRead, shared_from_this()));
  }

  void onRead(beast::error_code ec, std::size_t n) {
    if (ec) {
      onReadError(ec);
      return;
    }
    message_bytes_ += n;
    if (message_bytes_ > kVrMaxMessageBytes) buffer_.consume(buffer_.size());  // discard as it arrives
    if (message_bytes_ > kWsHardLimit && !closing_) {
      reject(VrReject::kTooLarge, "message over " + std::to_string(kWsHardLimit / 1024) + " kB: session closed");
      srv_->event("client #" + std::to_string(id_) + " sent a message over 1 MB: closed");
      closeWith(static_cast<std::uint16_t>(websocket::close_code::too_big), "message too big");
    }
    if (!ws_.is_message_done()) {
      doRead();
      return;
    }
    const std::size_t size = message_bytes_;
    message_bytes_ = 0;
    try {
      if (size > kWsHardLimit) {
        // counted when it crossed the hard limit
      } else if (size > kVrMaxMessageBytes) {
        countMessage();
        reject(VrReject::kTooLarge,
               std::to_string(size) + " bytes, at most " + std::to_string(kVrMaxMessageBytes) + " (discarded)");
      } else {
        handleMessage();
      }
    } catch (const std::exception& e) {
      srv_->count([&](VrServerStats& s) {
        ++s.internal_errors;
        s.last_error = std::string("internal: ") + e.what();
      });
    } catch (...) {
      srv_->count([](VrServerStats& s) { ++s.internal_errors; });
    }
    buffer_.consume(buffer_.size());
    doRead();
  }

  void onReadError(beast::error_code ec, bool deferred = false) {
    if (ec == net::error::operation_aborted && !closing_ && !timed_out_ && !deferred) {
      // Possibly Beast's idle timeout delivered to a pending status write: classify once that
      // write's handler has run.
      net::post(ws_.get_executor(), [self = shared_from_this(), ec] { self->onReadError(ec, true); });
      return;
    }
    status_timer_.cancel();
    if (ec == websocket::error::closed || closing_) {
      if (!closing_) srv_->event("client #" + std::to_string(id_) + " closed the connection");
    } else if (ec == beast::error::timeout || timed_out_) {
      srv_->count([](VrServerStats& s) { ++s.ws_timeouts; });
      srv_->event("client #" + std::to_string(id_) + " timed out (no answer to pings)");
    } else {
      srv_->count([&](VrServerStats& s) {
        ++s.ws_errors;
        s.last_error = "session #" + std::to_string(id_) + ": " + ec.message();
      });
      srv_->event("client #" + std::to_string(id_) + " ended: " + ec.message());
    }
    closing_ = true;
    srv_->forget(this);
  }

  void reject(VrReject r, const std::string& detail) {
    ++rejected_;
    last_error_ = std::string(toString(r)) + (detail.empty() ? "" : ": " + detail);
    srv_->count([&](VrServerStats& s) {
      ++s.rejected[static_cast<int>(r)];
      ++s.rejected_total;
      s.last_error = last_error_;
    });
  }

  void countMessage() {
    last_rx_ = Clock::now();
    ++received_;
    srv_->count([](VrServerStats& s) { ++s.messages; });
  }

  void handleMessage() {
    countMessage();
    const auto now = last_rx_;
    if (closing_) return;
    // Rate: messages per 1 s window.
    if (now - window_start_ >= std::chrono::seconds(1)) {
      window_start_ = now;
      window_count_ = 0;
    }
    if (++window_count_ > srv_->opt.max_message_rate_hz) {
      reject(VrReject::kRateLimited,
             "more than " + std::to_string(static_cast<long>(srv_->opt.max_message_rate_hz)) + " messages per second");
      return;
    }
    if (!ws_.got_text()) {
      reject(VrReject::kBinaryFrame, "binary message, the protocol is JSON text");
      return;
    }
    const auto data = buffer_.data();
    const std::string_view text(static_cast<const char*>(data.data()), data.size());
    VrSample sample;
    std::string detail;
    const VrReject r = parseVrMessage(text, sample, &detail);
    if (r != VrReject::kAccepted) {
      reject(r, detail);
      return;
    }
    if (sample.frame <= last_frame_) {
      reject(VrReject::kFrameNotIncreasing,
             "frame " + std::to_string(sample.frame) + " after " + std::to_string(last_frame_));
      return;
    }
    last_frame_ = sample.frame;
    const std::int64_t utime = wallMicros();
    srv_->count([](VrServerStats& s) { ++s.accepted; });
    const bool may = srv_->mayPublish(shared_from_this(), now);
    last_valid_ = now;
    if (!may) {
      srv_->count([](VrServerStats& s) { ++s.standby; });
      return;
    }
    bool ok = false;
    try {
      ok = srv_->sink ? srv_->sink(sample, utime) : true;
    } catch (const std::exception& e) {
      srv_->noteError(std::string("publish: ") + e.what());
    } catch (...) {
      srv_->noteError("publish: unknown exception");
    }
    srv_->lcm_ok = ok;
    srv_->any_published = true;
    if (ok) {
      ++published_;
      srv_->count([](VrServerStats& s) { ++s.published; });
    } else {
      srv_->count([](VrServerStats& s) { ++s.publish_failures; });
    }
  }

  void scheduleStatus() {
    status_timer_.expires_after(seconds(srv_->opt.status_period_s));
    status_timer_.async_wait([self = shared_from_this()](beast::error_code ec) {
      if (ec || self->closing_) return;
      try {
        self->sendStatus();
      } catch (...) {
        self->srv_->count([](VrServerStats& s) { ++s.internal_errors; });
      }
      self->scheduleStatus();
    });
  }

  void sendStatus() {
    if (writing_) return;  // the previous status is still going out: skip this one
    const auto active = srv_->active.lock();
    nlohmann::json j = {{"type", "status"},
                        {"received", received_},
                        {"rejected", rejected_},
                        {"published", published_},
                        {"active", active.get() == this},
                        {"lcm", !srv_->any_published ? "idle" : (srv_->lcm_ok ? "ok" : "error")},
                        {"last_error", last_error_},
                        {"clients", srv_->liveClients()},
                        {"server", kServerName}};
    out_ = j.dump(-1, ' ', true, nlohmann::json::error_handler_t::replace);
    writing_ = true;
    ws_.text(true);
    ws_.async_write(net::buffer(out_), [self = shared_from_this()](beast::error_code ec, std::size_t) {
      self->writing_ = false;  // a failed write also fails the pending read, which ends the session
      // Beast hands its idle timeout to the first pending operation; the read then sees "aborted".
      if (ec == beast::error::timeout) self->timed_out_ = true;
    });
  }

  std::shared_ptr<VrServer::Impl> srv_;
  websocket::stream<beast::ssl_stream<beast::tcp_stream>> ws_;
  beast::flat_buffer buffer_;
  net::steady_timer status_timer_;
  std::unique_ptr<ConnectionSlot> slot_;
  std::string peer_;
  std::uint64_t id_;
  std::uint16_t refuse_code_ = 0;
  std::string refuse_reason_;
  bool closing_ = false;
  bool writing_ = false;
  bool timed_out_ = false;
  std::string out_;
  Clock::time_point last_rx_{};
  Clock::time_point last_valid_{};
  Clock::time_point window_start_{};
  double window_count_ = 0;
  std::int64_t last_frame_ = -1;
  std::size_t message_bytes_ = 0;
  std::uint64_t received_ = 0;
  std::uint64_t rejected_ = 0;
  std::uint64_t published_ = 0;
  std::string last_error_;
};

// ---------------------------------------------------------------------------------------------
// HTTPS session: TLS handshake, requests (static files), or the upgrade to a WsSession.
class HttpSession : public std::enable_shared_from_this<HttpSession> {
 public:
  HttpSession(std::shared_ptr<VrServer::Impl> srv, tcp::socket&& socket, std::unique_ptr<ConnectionSlot> slot)
      : srv_(std::move(srv)), stream_(std::move(socket), srv_->tls), slot_(std::move(slot)) {
    beast::error_code ec;
    const auto ep = beast::get_lowest_layer(stream_).socket().remote_endpoint(ec);
    peer_ = ec ? "?" : ep.address().to_string() + ":" + std::to_string(ep.port());
  }

  void run() {
    beast::get_lowest_layer(stream_).expires_after(seconds(srv_->opt.handshake_timeout_s));
    stream_.async_handshake(ssl::stream_base::server,
                            beast::bind_front_handler(&HttpSession::onHandshake, shared_from_this()));
  }

  void drop() {
    if (upgraded_) return;  // the stream belongs to a WsSession now
    beast::error_code ec;
    beast::get_lowest_layer(stream_).socket().shutdown(tcp::socket::shutdown_both, ec);
    beast::get_lowest_layer(stream_).close();
  }

 private:
  void onHandshake(beast::error_code ec) {
    if (ec) {
      srv_->count([&](VrServerStats& s) {
        ++s.tls_failures;
        s.last_error = "TLS handshake with " + peer_ + ": " + ec.message();
      });
      return;
    }
    doRead();
  }

  void doRead() {
    parser_.emplace();
    parser_->header_limit(8 * 1024);
    parser_->body_limit(4 * 1024);
    beast::get_lowest_layer(stream_).expires_after(seconds(srv_->opt.http_timeout_s));
    http::async_read(stream_, buffer_, *parser_, beast::bind_front_handler(&HttpSession::onRead, shared_from_this()));
  }

  void onRead(beast::error_code ec, std::size_t) {
    if (ec == http::error::end_of_stream) return doClose();
    if (ec) {
      if (ec != beast::error::timeout && ec != net::error::operation_aborted && ec != net::ssl::error::stream_truncated)
        srv_->count([&](VrServerStats& s) {
          ++s.http_errors;
          s.last_error = "HTTP from " + peer_ + ": " + ec.message();
        });
      return;
    }
    srv_->count([](VrServerStats& s) { ++s.http_requests; });
    http::request<http::string_body> req = parser_->release();
    try {
      if (websocket::is_upgrade(req)) return upgrade(std::move(req));
      respond(req);
    } catch (const std::exception& e) {
      srv_->count([&](VrServerStats& s) {
        ++s.internal_errors;
        s.last_error = std::string("internal: ") + e.what();
      });
    }
  }

  void upgrade(http::request<http::string_body>&& req) {
    const std::string target(req.target());
    if (target.substr(0, target.find('?')) != "/ws")
      return sendError(req, http::status::not_found, "no WebSocket here\n");
    const auto origin = req.find(http::field::origin);
    if (origin != req.end() && !originMatchesHost(sv(origin->value()), sv(req[http::field::host]))) {
      srv_->count([](VrServerStats& s) { ++s.ws_refused; });
      srv_->event("WebSocket from " + peer_ + " refused: Origin '" + std::string(origin->value()) +
                  "' is not this host");
      return sendError(req, http::status::forbidden, "cross-origin WebSocket refused\n");
    }
    std::uint16_t code = 0;
    std::string reason;
    if (!srv_->opt.access_token.empty()) {
      const auto token = queryValue(target, "token");
      if (!token || !sameToken(*token, srv_->opt.access_token)) {
        code = kCloseUnauthorized;
        reason = token ? "unauthorized: wrong token" : "unauthorized: token missing (open the URL the bridge printed)";
      }
    }
    beast::get_lowest_layer(stream_).expires_never();
    upgraded_ = true;
    std::make_shared<WsSession>(srv_, std::move(stream_), std::move(slot_), peer_)->run(std::move(req), code, reason);
  }

  template <class Body>
  void setCommonHeaders(http::response<Body>& res, bool keep_alive) {
    res.set(http::field::server, kServerName);
    res.set(http::field::cache_control, "no-store");  // a browser update never runs a stale page
    res.set("X-Content-Type-Options", "nosniff");
    res.set("Referrer-Policy", "no-referrer");
    res.set("Content-Security-Policy",
            "default-src 'self'; connect-src 'self'; img-src 'self' data:; frame-ancestors 'none'");
    res.keep_alive(keep_alive);
  }

  void sendError(const http::request<http::string_body>& req, http::status status, const std::string& text) {
    srv_->count([](VrServerStats& s) { ++s.http_errors; });
    auto res = std::make_shared<http::response<http::string_body>>(status, req.version());
    setCommonHeaders(*res, req.keep_alive());
    res->set(http::field::content_type, "text/plain; charset=utf-8");
    if (status == http::status::method_not_allowed) res->set(http::field::allow, "GET, HEAD");
    res->body() = req.method() == http::verb::head ? std::string() : text;
    res->prepare_payload();
    write(res);
  }

  void respond(const http::request<http::string_body>& req) {
    if (req.method() != http::verb::get && req.method() != http::verb::head)
      return sendError(req, http::status::method_not_allowed, "only GET and HEAD\n");
    const VrStaticLookup look = vrLookupStatic(srv_->opt.web_root, sv(req.target()));
    if (look.status != 200) {
      srv_->noteError("HTTP " + std::to_string(look.status) + " for '" + std::string(req.target()).substr(0, 80) +
                      "': " + look.reason);
      return sendError(req, look.status == 400 ? http::status::bad_request : http::status::not_found,
                       look.status == 400 ? "bad request\n" : "not found\n");
    }
    std::ifstream in(look.file, std::ios::binary);
    std::string body((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) return sendError(req, http::status::not_found, "not found\n");
    auto res = std::make_shared<http::response<http::string_body>>(http::status::ok, req.version());
    setCommonHeaders(*res, req.keep_alive());
    res->set(http::field::content_type, look.mime);
    if (req.method() == http::verb::head) {
      res->content_length(body.size());
    } else {
      res->body() = std::move(body);
      res->prepare_payload();
    }
    write(res);
  }

  void write(const std::shared_ptr<http::response<http::string_body>>& res) {
    beast::get_lowest_layer(stream_).expires_after(seconds(srv_->opt.http_timeout_s));
    http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code ec, std::size_t) {
      if (ec) return;
      if (!res->keep_alive()) return self->doClose();
      self->doRead();
    });
  }

  void doClose() {
    beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(2));
    stream_.async_shutdown([self = shared_from_this()](beast::error_code) {});
  }

  std::shared_ptr<VrServer::Impl> srv_;
  beast::ssl_stream<beast::tcp_stream> stream_;
  std::unique_ptr<ConnectionSlot> slot_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::string peer_;
  bool upgraded_ = false;
};

// ---------------------------------------------------------------------------------------------
// Impl

void VrServer::Impl::doAccept() {
  acceptor.async_accept(
      [self = shared_from_this()](beast::error_code ec, tcp::socket s) { self->onAccept(ec, std::move(s)); });
}

void VrServer::Impl::onAccept(beast::error_code ec, tcp::socket socket) {
  if (stopping || ec == net::error::operation_aborted) return;
  if (ec) {  // e.g. out of file descriptors: wait a little instead of spinning
    noteError("accept: " + ec.message());
    accept_retry.expires_after(std::chrono::milliseconds(100));
    accept_retry.async_wait([self = shared_from_this()](beast::error_code e) {
      if (!e && !self->stopping) self->doAccept();
    });
    return;
  }
  count([](VrServerStats& s) { ++s.tls_connections; });
  if (connections >= opt.max_connections) {
    count([](VrServerStats& s) { ++s.refused_connections; });
    beast::error_code ignored;
    socket.close(ignored);
  } else {
    socket.set_option(tcp::no_delay(true), ec);
    auto session = std::make_shared<HttpSession>(shared_from_this(), std::move(socket),
                                                 std::make_unique<ConnectionSlot>(shared_from_this()));
    http_sessions.erase(std::remove_if(http_sessions.begin(), http_sessions.end(),
                                       [](const std::weak_ptr<HttpSession>& w) { return w.expired(); }),
                        http_sessions.end());
    http_sessions.push_back(session);
    session->run();
  }
  doAccept();
}

int VrServer::Impl::liveClients() {
  int n = 0;
  for (const auto& w : ws_sessions)
    if (auto s = w.lock(); s && !s->closing()) ++n;
  return n;
}

std::uint16_t VrServer::Impl::admit(const std::shared_ptr<WsSession>& s, std::string& reason) {
  if (stopping) {
    reason = "server stopping";
    return static_cast<std::uint16_t>(websocket::close_code::going_away);
  }
  ws_sessions.erase(std::remove_if(ws_sessions.begin(), ws_sessions.end(),
                                   [](const std::weak_ptr<WsSession>& w) {
                                     auto p = w.lock();
                                     return !p || p->closing();
                                   }),
                    ws_sessions.end());
  if (static_cast<int>(ws_sessions.size()) >= opt.max_clients) {
    // Replace the session silent longest, if it is stale.
    std::shared_ptr<WsSession> oldest;
    for (const auto& w : ws_sessions)
      if (auto p = w.lock(); p && (!oldest || p->lastActivity() < oldest->lastActivity())) oldest = p;
    const auto now = Clock::now();
    if (!oldest || now - oldest->lastActivity() < seconds(opt.stale_after_s)) {
      reason = "busy: " + std::to_string(opt.max_clients) + " clients are streaming";
      return kCloseBusy;
    }
    count([](VrServerStats& st) { ++st.ws_replaced; });
    event("client #" + std::to_string(oldest->id()) + " replaced by #" + std::to_string(s->id()) + " (silent " +
          std::to_string(std::chrono::duration<double>(now - oldest->lastActivity()).count()).substr(0, 5) + " s)");
    oldest->closeWith(kCloseReplaced, "replaced by a newer connection");
    forget(oldest.get());
  }
  ws_sessions.push_back(s);
  count([&](VrServerStats& st) { st.clients = static_cast<int>(ws_sessions.size()); });
  return 0;
}

void VrServer::Impl::forget(const WsSession* s) {
  ws_sessions.erase(std::remove_if(ws_sessions.begin(), ws_sessions.end(),
                                   [s](const std::weak_ptr<WsSession>& w) {
                                     auto p = w.lock();
                                     return !p || p.get() == s;
                                   }),
                    ws_sessions.end());
  if (auto a = active.lock(); !a || a.get() == s) active.reset();
  count([&](VrServerStats& st) { st.clients = static_cast<int>(ws_sessions.size()); });
  if (stopping && ws_sessions.empty()) accept_retry.cancel();  // nothing left to cut off: let run() return
}

bool VrServer::Impl::mayPublish(const std::shared_ptr<WsSession>& s, Clock::time_point now) {
  auto a = active.lock();
  if (a == s) return true;
  if (a && !a->closing() && now - a->lastValid() < seconds(opt.stale_after_s)) return false;
  if (a) {
    count([](VrServerStats& st) { ++st.takeovers; });
    event("client #" + std::to_string(s->id()) + " takes over from stale client #" + std::to_string(a->id()));
  }
  active = s;
  return true;
}

void VrServer::Impl::shutdown() {
  stopping = true;
  beast::error_code ec;
  acceptor.close(ec);
  for (const auto& w : ws_sessions)
    if (auto s = w.lock())
      s->closeWith(static_cast<std::uint16_t>(websocket::close_code::going_away), "server stopping");
  for (const auto& w : http_sessions)
    if (auto s = w.lock()) s->drop();
  // Clients that do not answer the closing handshake within 0.5 s are cut off, so that every
  // pending operation ends and the I/O thread returns.
  if (ws_sessions.empty()) return;
  accept_retry.expires_after(std::chrono::milliseconds(500));
  accept_retry.async_wait([self = shared_from_this()](beast::error_code) {
    const auto sessions = self->ws_sessions;
    for (const auto& w : sessions)
      if (auto s = w.lock()) s->drop();
  });
}

void VrServer::Impl::dropAll() {
  const auto sessions = ws_sessions;
  for (const auto& w : sessions)
    if (auto s = w.lock()) {
      s->drop();
      forget(s.get());
    }
}

// ---------------------------------------------------------------------------------------------

void VrServerOptions::validate() const {
  if (max_clients < 1 || max_clients > 16)
    throw std::invalid_argument("VrServerOptions.max_clients = " + std::to_string(max_clients) + ": expected 1 to 16");
  if (max_connections < 2 || max_connections > 1024)
    throw std::invalid_argument("VrServerOptions.max_connections = " + std::to_string(max_connections) +
                                ": expected 2 to 1024");
  requireRange("handshake_timeout_s", handshake_timeout_s, 0.1, 120.0);
  requireRange("idle_timeout_s", idle_timeout_s, 0.2, 600.0);
  requireRange("http_timeout_s", http_timeout_s, 0.1, 600.0);
  requireRange("stale_after_s", stale_after_s, 0.05, 60.0);
  requireRange("status_period_s", status_period_s, 0.05, 10.0);
  requireRange("max_message_rate_hz", max_message_rate_hz, 1.0, 10000.0);
  if (cert_file.empty() || key_file.empty())
    throw std::invalid_argument("VrServerOptions: cert_file and key_file are required");
  if (web_root.empty()) throw std::invalid_argument("VrServerOptions.web_root is empty");
}

VrServer::VrServer(const VrServerOptions& options, VrSampleSink sink) : impl_(std::make_shared<Impl>()) {
  options.validate();
  impl_->opt = options;
  impl_->sink = std::move(sink);
  std::error_code fec;
  if (!std::filesystem::is_regular_file(options.web_root / "index.html", fec))
    throw std::runtime_error(options.web_root.string() +
                             ": no index.html (give --web-root, the folder of the VR page)");
  auto& tls = impl_->tls;
  tls.set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                  ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1 | ssl::context::single_dh_use);
  boost::system::error_code ec;
  tls.use_certificate_chain_file(options.cert_file.string(), ec);
  if (ec) throw std::runtime_error(options.cert_file.string() + ": cannot load certificate (" + ec.message() + ")");
  tls.use_private_key_file(options.key_file.string(), ssl::context::pem, ec);
  if (ec) throw std::runtime_error(options.key_file.string() + ": cannot load private key (" + ec.message() + ")");

  const auto address = net::ip::make_address(options.bind_address, ec);
  if (ec)
    throw std::runtime_error("bind address '" + options.bind_address + "': not an IP address (" + ec.message() + ")");
  const tcp::endpoint ep(address, options.port);
  const std::string where = options.bind_address + ":" + std::to_string(options.port);
  auto& acc = impl_->acceptor;
  acc.open(ep.protocol(), ec);
  if (!ec) acc.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) acc.bind(ep, ec);
  if (!ec) acc.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  impl_->bound_port = acc.local_endpoint().port();
}

VrServer::~VrServer() { stop(); }

void VrServer::start() {
  if (impl_->started) return;
  impl_->started = true;
  impl_->doAccept();
  impl_->thread = std::thread([impl = impl_.get()] {
    for (;;) {
      try {
        impl->ioc.run();
        break;
      } catch (const std::exception& e) {
        impl->count([&](VrServerStats& s) {
          ++s.internal_errors;
          s.last_error = std::string("internal: ") + e.what();
        });
      } catch (...) {
        impl->count([](VrServerStats& s) { ++s.internal_errors; });
      }
    }
    impl->finished.set_value();
  });
}

void VrServer::stop() noexcept {
  if (!impl_ || impl_->stopped) return;
  impl_->stopped = true;
  try {
    if (impl_->started) {
      net::post(impl_->ioc, [impl = impl_.get()] { impl->shutdown(); });
      if (impl_->finished_future.wait_for(std::chrono::seconds(3)) != std::future_status::ready) impl_->ioc.stop();
      if (impl_->thread.joinable()) impl_->thread.join();
    }
    // Handlers still queued hold shared_ptrs to the Impl through sessions: release them.
    impl_->ioc.stop();
    impl_->ioc.restart();
    impl_->ioc.poll();
  } catch (...) {
  }
}

std::uint16_t VrServer::port() const noexcept { return impl_->bound_port; }

VrServerStats VrServer::stats() const {
  std::lock_guard<std::mutex> lock(impl_->stats_mutex);
  return impl_->counters;
}

void VrServer::dropClients() {
  if (!impl_->started || impl_->stopped) return;
  auto done = std::make_shared<std::promise<void>>();
  auto f = done->get_future();
  net::post(impl_->ioc, [impl = impl_, done] {
    impl->dropAll();
    done->set_value();
  });
  f.wait_for(std::chrono::seconds(2));
}

}  // namespace pmg::teleop
