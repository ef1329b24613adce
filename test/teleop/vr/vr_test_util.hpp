#pragma once
// Helpers of the VR bridge tests: a TLS WebSocket client and an HTTPS client (Boost.Beast; they
// verify the server's certificate against its own PEM file and host 127.0.0.1, i.e. the SAN), an
// LCM listener of PMG_VR_POSE, a per-process LCM URL, and percentiles.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <mutex>
#include <pmg_lcm/vr_pose_t.hpp>
#include <string>
#include <thread>
#include <vector>

namespace pmg::test::vr {

using Clock = std::chrono::steady_clock;

/// A WebSocket client over TLS. The constructor connects and completes the handshake (throws on
/// failure, e.g. an HTTP 403 answer). With read_loop, an I/O thread keeps reading (so the client
/// answers pings and collects the server's messages); without, nothing reads and pings go
/// unanswered (a client that stopped responding).
class WsClient {
 public:
  WsClient(std::uint16_t port, const std::string& target, const std::string& ca_file, bool read_loop = true,
           const std::string& origin = "");
  ~WsClient();
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  /// Sends one message (text or binary); false if the connection failed. Blocks until written.
  bool send(const std::string& payload, bool binary = false);
  /// Text messages received so far (server status messages).
  std::vector<std::string> messages() const;
  /// The read loop ended (connection closed or failed).
  bool closed() const { return closed_.load(); }
  /// Close code received from the server (0: none yet).
  int closeCode() const { return close_code_.load(); }
  std::string closeReason() const;
  /// Waits up to @p timeout for closed().
  bool waitClosed(std::chrono::milliseconds timeout) const;
  /// Closing handshake (best effort).
  void close();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
  std::atomic<bool> closed_{false};
  std::atomic<int> close_code_{0};
};

/// One HTTPS request (new connection); returns status, Content-Type, Cache-Control and body.
struct HttpAnswer {
  int status = 0;
  std::string content_type;
  std::string cache_control;
  std::string body;
  std::size_t content_length = 0;
};
HttpAnswer httpsRequest(std::uint16_t port, const std::string& method, const std::string& target,
                        const std::string& ca_file);

/// An LCM URL private to this process (multicast group and port from the pid), ttl=0.
std::string privateLcmUrl();
/// Empty if LCM multicast loops back on @p url here; otherwise why not (the test then skips).
std::string multicastUnavailable(const std::string& url);

/// Receives PMG_VR_POSE on its own thread and keeps every message with its receive time.
class VrPoseListener {
 public:
  explicit VrPoseListener(const std::string& url);
  ~VrPoseListener();
  struct Received {
    Clock::time_point at;
    pmg_lcm::vr_pose_t msg;
  };
  std::vector<Received> received() const;
  std::size_t count() const;
  /// Waits until count() ≥ n or @p timeout passes; returns count().
  std::size_t waitFor(std::size_t n, std::chrono::milliseconds timeout) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Percentile (nearest rank) of @p v, p in [0, 100]; NaN for an empty vector.
double percentile(std::vector<double> v, double p);

}  // namespace pmg::test::vr
