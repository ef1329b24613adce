#pragma once
/// @file vr_server.hpp
/// pmg_vr_bridge's server: one HTTPS port (Boost.Beast over Asio + OpenSSL) that serves the WebXR
/// page (static files below a web root, GET/HEAD only, vr_static_files.hpp) and a secure
/// WebSocket endpoint `/ws` that receives the page's pose messages (vr_protocol.hpp).
///
/// Threads: one I/O thread owned by the server runs every handler; the sink is called on it. No
/// exception leaves that thread (a throwing handler is counted in `internal_errors` and the loop
/// goes on).
///
/// WebSocket sessions:
///  - the upgrade must target `/ws`; with an access token configured, `/ws?token=<token>`. A
///    browser's Origin header must name this same host (cross-site pages are refused, 403);
///  - keep-alive: Beast's idle timeout with keep-alive pings. After idle_timeout_s / 2 without a
///    byte from the client the server pings; after idle_timeout_s it closes the session (a
///    half-open connection ends within idle_timeout_s). A live browser answers pings by itself;
///  - every message is checked (parseVrMessage, then per session: frame strictly increasing, at
///    most max_message_rate_hz messages per second); a refused message is counted by reason and
///    the session goes on. A message over kVrMaxMessageBytes is discarded while it arrives
///    (too_large, the session goes on); one over 1 MB ends the session (close 1009, too_large);
///    WebSocket protocol violations end it too (ws_errors);
///  - at most max_clients sessions. One of them is *active*: only its poses reach the sink. The
///    active session keeps that role while it streams; when it has sent no valid pose for
///    stale_after_s, the next session that sends one takes over. A new connection beyond
///    max_clients replaces the session that has been silent longest if that one is stale
///    (closed with code 4001 "replaced"), otherwise it is refused (code 4002 "busy");
///  - a wrong or missing token closes the session with code 4003 (the page then shows why);
///  - every status_period_s the server sends the page
///    `{"type":"status","received":N,"rejected":M,"published":P,"active":b,"lcm":"ok"|"error"|"idle",
///      "last_error":"...","clients":C,"server":"pmg_vr_bridge"}` (counts of this session).
///
/// Setup (constructor) allocates and throws; stop() and the destructor do not throw.

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>

#include "pmg/teleop/vr_protocol.hpp"
#include "pmg/teleop/vr_sample.hpp"

namespace pmg::teleop {

struct VrServerOptions {
  std::string bind_address = "0.0.0.0";  ///< IPv4 or IPv6 literal
  std::uint16_t port = 8443;             ///< 0: any free port (see VrServer::port())
  std::filesystem::path cert_file;       ///< PEM certificate (vr_certificate.hpp)
  std::filesystem::path key_file;        ///< PEM private key
  std::filesystem::path web_root;        ///< folder with index.html (data/vr/web)
  std::string access_token;              ///< required `token` query of /ws; empty: none
  int max_clients = 2;                   ///< WebSocket sessions [1, 16]
  int max_connections = 32;              ///< TLS connections in all (HTTP + WebSocket) [2, 1024]
  double handshake_timeout_s = 10.0;     ///< TLS / HTTP / WebSocket handshake limit [s], [0.1, 120]
  double idle_timeout_s = 10.0;          ///< WebSocket idle limit [s] (pings at half), [0.2, 600]
  double http_timeout_s = 30.0;          ///< HTTP keep-alive connection idle limit [s], [0.1, 600]
  double stale_after_s = 1.0;            ///< active session silent this long may be replaced [s], [0.05, 60]
  double status_period_s = 0.5;          ///< status message period [s], [0.05, 10]
  double max_message_rate_hz = 250.0;    ///< per session; excess refused as rate_limited, [1, 10000]
  /// Optional event log (connections, refusals, replacements), called on the I/O thread.
  std::function<void(const std::string&)> on_event;

  /// @throws std::invalid_argument naming the field and its allowed range.
  void validate() const;
};

/// Counters since start (a consistent snapshot).
struct VrServerStats {
  std::uint64_t tls_connections = 0;      ///< TCP connections accepted
  std::uint64_t tls_failures = 0;         ///< TLS handshakes that failed (e.g. certificate not accepted)
  std::uint64_t refused_connections = 0;  ///< over max_connections, closed at once
  std::uint64_t http_requests = 0;
  std::uint64_t http_errors = 0;       ///< answered with 4xx
  std::uint64_t ws_sessions = 0;       ///< WebSocket sessions opened (accepted upgrades)
  std::uint64_t ws_refused = 0;        ///< upgrades refused: origin, token, busy
  std::uint64_t ws_replaced = 0;       ///< stale sessions replaced by a new connection
  std::uint64_t ws_timeouts = 0;       ///< sessions closed by the idle timeout
  std::uint64_t ws_errors = 0;         ///< sessions ended by a protocol or transport error
  std::uint64_t takeovers = 0;         ///< active role passed to another session
  std::uint64_t messages = 0;          ///< WebSocket messages received
  std::uint64_t accepted = 0;          ///< valid pose messages
  std::uint64_t published = 0;         ///< given to the sink, which reported success
  std::uint64_t publish_failures = 0;  ///< the sink reported failure or threw
  std::uint64_t standby = 0;           ///< valid poses of a non-active session (not published)
  std::uint64_t rejected_total = 0;
  std::uint64_t rejected[kVrRejectCount] = {};  ///< per VrReject
  std::uint64_t internal_errors = 0;            ///< exceptions caught on the I/O thread
  int clients = 0;                              ///< open WebSocket sessions now
  std::string last_error;                       ///< last rejection / failure, one line
};

/// Receives each published sample: @p receive_utime is the receive time [µs, wall clock].
/// Returns false if publishing failed (shown on the page as lcm "error"). May throw (counted).
using VrSampleSink = std::function<bool(const VrSample& sample, std::int64_t receive_utime)>;

class VrServer {
 public:
  /// Loads the certificate and key, binds and listens (no thread yet).
  /// @throws std::invalid_argument (options) or std::runtime_error (certificate, bind: naming
  /// the address, port and reason).
  VrServer(const VrServerOptions& options, VrSampleSink sink);
  ~VrServer();
  VrServer(const VrServer&) = delete;
  VrServer& operator=(const VrServer&) = delete;

  /// Starts the I/O thread.
  void start();
  /// Closes every session (code 1001), stops accepting and joins the thread (≤ ~2 s). Idempotent.
  void stop() noexcept;

  /// The port listened on (the chosen one when options.port was 0).
  std::uint16_t port() const noexcept;
  VrServerStats stats() const;
  /// Closes every WebSocket session's TCP connection without a closing handshake (what a Wi-Fi
  /// drop looks like to the page). For tests and the reconnect measurement.
  void dropClients();

  struct Impl;

 private:
  std::shared_ptr<Impl> impl_;
};

}  // namespace pmg::teleop
