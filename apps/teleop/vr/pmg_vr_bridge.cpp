// pmg_vr_bridge: serves the WebXR page to a headset (Meta Quest 3) over HTTPS and publishes the
// poses it streams back over a secure WebSocket as pmg_lcm::vr_pose_t on PMG_VR_POSE (frame V,
// include/pmg/teleop/vr_sample.hpp), signed when a key is given. docs/teleop.md.
//
//   pmg_vr_bridge [--port 8443] [--bind 0.0.0.0] [--cert-dir DIR] [--web-root DIR]
//                 [--lcm-url URL] [--key FILE] [--duration S] [--no-token]
//
// Exit codes: 0 stopped normally (SIGINT/SIGTERM or --duration), 1 setup error (certificate, port,
// LCM, key file), 2 bad command line.
#include <CLI/CLI.hpp>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <string>
#include <thread>

#include "pmg/common/cli_checks.hpp"
#include "pmg/common/data_paths.hpp"
#include "pmg/comms/channels.hpp"
#include "pmg/comms/command_publisher.hpp"
#include "pmg/teleop/vr_certificate.hpp"
#include "pmg/teleop/vr_protocol.hpp"
#include "pmg/teleop/vr_server.hpp"

namespace {

volatile std::sig_atomic_t g_stop = 0;
extern "C" void onSignal(int) { g_stop = 1; }

double monotonicSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

std::string rejectionSummary(const pmg::teleop::VrServerStats& s) {
  std::string out;
  for (int r = 1; r < pmg::teleop::kVrRejectCount; ++r)
    if (s.rejected[r] > 0)
      out += (out.empty() ? "" : ", ") + std::string(pmg::teleop::toString(static_cast<pmg::teleop::VrReject>(r))) +
             " " + std::to_string(s.rejected[r]);
  return out;
}

bool isLoopback(const std::string& a) { return a == "localhost" || a == "::1" || a.rfind("127.", 0) == 0; }
bool isIpv4(const std::string& a) { return a.find_first_not_of("0123456789.") == std::string::npos && !a.empty(); }

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "pmg_vr_bridge: serve the WebXR teleoperation page over HTTPS and publish the headset's poses on LCM "
      "(PMG_VR_POSE). Open the printed URL in the Quest browser. docs/teleop.md"};
  int port = 8443;
  std::string bind = "0.0.0.0";
  std::string cert_dir, web_root, key_file;
  std::string lcm_url = pmg::kDefaultLcmUrl;
  double duration = 0.0, stats_period = 5.0, idle_timeout = 10.0;
  int max_clients = 2;
  bool no_token = false;
  app.add_option("--port", port, "HTTPS port (page and WebSocket /ws); 0: any free port (printed)")
      ->check(CLI::Range(0, 65535))
      ->capture_default_str();
  app.add_option("--bind", bind, "address to listen on (IPv4/IPv6 literal)")->capture_default_str();
  app.add_option("--cert-dir", cert_dir,
                 "folder of the self-signed certificate, key and access token (created on first run; default "
                 "$XDG_CONFIG_HOME/pmg/vr or ~/.config/pmg/vr)");
  app.add_option("--web-root", web_root, "folder of the WebXR page (default <data dir>/data/vr/web)");
  app.add_option("--lcm-url", lcm_url, "LCM provider URL")->capture_default_str();
  app.add_option("--key", key_file, "authentication key file (pmg_keygen, mode 0600); none: unsigned messages")
      ->check(CLI::ExistingFile);
  app.add_option("--duration", duration, "stop after this many seconds (0: run until SIGINT/SIGTERM)")
      ->check(pmg::cli::finiteIn(0.0, 1e7))
      ->capture_default_str();
  app.add_option("--stats-period", stats_period, "seconds between stats lines")
      ->check(pmg::cli::finiteIn(0.5, 3600.0))
      ->capture_default_str();
  app.add_option("--idle-timeout", idle_timeout,
                 "WebSocket idle limit [s]: the server pings after half of it and drops a silent client after it")
      ->check(pmg::cli::finiteIn(0.2, 600.0))
      ->capture_default_str();
  app.add_option("--max-clients", max_clients, "WebSocket clients at once (one streams, the others wait)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app.add_flag("--no-token", no_token,
               "do not require the access token in the page URL (anyone who reaches the port can stream poses)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  try {
    namespace vr = pmg::teleop;
    const std::filesystem::path dir = cert_dir.empty() ? vr::defaultVrConfigDir() : std::filesystem::path(cert_dir);
    std::vector<std::string> extra;
    if (bind != "0.0.0.0" && bind != "::") extra.push_back(bind);
    const vr::VrCertificateInfo cert = vr::ensureVrCertificate(dir, extra);
    const std::string token = no_token ? std::string() : vr::ensureVrAccessToken(dir);

    pmg::comms::CommandPublisher publisher(lcm_url, key_file, vr::kVrSource);

    vr::VrServerOptions opt;
    opt.bind_address = bind;
    opt.port = static_cast<std::uint16_t>(port);
    opt.cert_file = cert.cert_file;
    opt.key_file = cert.key_file;
    opt.web_root = web_root.empty() ? pmg::resolveData("data/vr/web") : std::filesystem::path(web_root);
    opt.access_token = token;
    opt.max_clients = max_clients;
    opt.idle_timeout_s = idle_timeout;
    const double t0 = monotonicSeconds();
    opt.on_event = [t0](const std::string& line) {
      std::printf("[%8.2f s] %s\n", monotonicSeconds() - t0, line.c_str());
      std::fflush(stdout);
    };
    vr::VrServer server(opt, [&publisher](const vr::VrSample& s, std::int64_t utime) {
      return publisher.publishVrPose(vr::toVrPoseMessage(s, utime));
    });

    std::printf("pmg_vr_bridge: certificate %s (%s)\n", cert.cert_file.string().c_str(),
                cert.created ? "generated now" : "reused");
    std::printf("  SHA-256 fingerprint %s\n  valid until %s; names:", cert.sha256_fingerprint.c_str(),
                cert.not_after.c_str());
    for (const auto& n : cert.subject_alt_names) std::printf(" %s", n.c_str());
    std::printf("\n  web root %s\n  LCM %s, channel %s, %s\n", opt.web_root.string().c_str(), lcm_url.c_str(),
                pmg::kVrPoseChannel, publisher.authenticated() ? "signed" : "UNSIGNED (no --key)");
    const std::string query = token.empty() ? std::string() : "?token=" + token;
    std::printf("Open on the headset (accept the certificate once, compare the fingerprint):\n");
    std::vector<std::string> hosts;
    if (bind == "0.0.0.0" || bind == "::") {
      for (const std::string& a : vr::hostNamesAndAddresses())
        if (isIpv4(a) && !isLoopback(a)) hosts.push_back(a);
    } else {
      hosts.push_back(bind.find(':') != std::string::npos ? "[" + bind + "]" : bind);
    }
    for (const std::string& h : hosts) std::printf("  https://%s:%u/%s\n", h.c_str(), server.port(), query.c_str());
    if (bind == "0.0.0.0" || bind == "127.0.0.1")
      std::printf("Synthetic poses from a desktop browser on this host:\n  https://127.0.0.1:%u/%s%ssynthetic=1\n",
                  server.port(), query.c_str(), query.empty() ? "?" : "&");
    std::fflush(stdout);

    std::signal(SIGINT, onSignal);
    std::signal(SIGTERM, onSignal);
    server.start();
    double next_stats = t0 + stats_period;
    vr::VrServerStats last = server.stats();
    double last_t = t0;
    while (!g_stop) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      const double now = monotonicSeconds();
      if (duration > 0.0 && now - t0 >= duration) break;
      if (now >= next_stats) {
        const vr::VrServerStats s = server.stats();
        const double dt = now - last_t;
        std::printf(
            "[%8.2f s] clients %d  rx %.1f msg/s  published %llu (%.1f/s)  rejected %llu%s%s%s  standby %llu  "
            "lcm failures %llu\n",
            now - t0, s.clients, static_cast<double>(s.messages - last.messages) / dt,
            static_cast<unsigned long long>(s.published), static_cast<double>(s.published - last.published) / dt,
            static_cast<unsigned long long>(s.rejected_total), s.rejected_total ? " (" : "",
            rejectionSummary(s).c_str(), s.rejected_total ? ")" : "", static_cast<unsigned long long>(s.standby),
            static_cast<unsigned long long>(s.publish_failures));
        if (!s.last_error.empty() && s.last_error != last.last_error)
          std::printf("           last error: %s\n", s.last_error.c_str());
        std::fflush(stdout);
        last = s;
        last_t = now;
        next_stats = now + stats_period;
      }
    }
    server.stop();
    const vr::VrServerStats s = server.stats();
    std::printf(
        "pmg_vr_bridge: stopped after %.1f s: %llu sessions, %llu messages, %llu published, %llu rejected%s%s%s, "
        "%llu standby, %llu timeouts, %llu TLS failures, %llu internal errors\n",
        monotonicSeconds() - t0, static_cast<unsigned long long>(s.ws_sessions),
        static_cast<unsigned long long>(s.messages), static_cast<unsigned long long>(s.published),
        static_cast<unsigned long long>(s.rejected_total), s.rejected_total ? " (" : "", rejectionSummary(s).c_str(),
        s.rejected_total ? ")" : "", static_cast<unsigned long long>(s.standby),
        static_cast<unsigned long long>(s.ws_timeouts), static_cast<unsigned long long>(s.tls_failures),
        static_cast<unsigned long long>(s.internal_errors));
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_vr_bridge: %s\n", e.what());
    return 1;
  }
}
