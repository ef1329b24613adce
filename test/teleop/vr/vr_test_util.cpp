#include "vr_test_util.hpp"

#include "lcm_loopback.hpp"

#include <unistd.h>

#include <algorithm>
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#include <cmath>
#include <condition_variable>
#include <future>
#include <lcm/lcm-cpp.hpp>
#include <limits>
#include <stdexcept>

namespace pmg::test::vr {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace ssl = net::ssl;
using tcp = net::ip::tcp;

namespace {
void verifyAgainst(ssl::context& ctx, const std::string& ca_file) {
  ctx.load_verify_file(ca_file);
  ctx.set_verify_mode(ssl::verify_peer);
}
}  // namespace

struct WsClient::Impl {
  net::io_context ioc;
  ssl::context ctx{ssl::context::tls_client};
  std::unique_ptr<websocket::stream<beast::ssl_stream<beast::tcp_stream>>> ws;
  beast::flat_buffer buffer;
  std::thread thread;
  bool read_loop = true;
  mutable std::mutex mutex;
  std::vector<std::string> messages;
  std::string close_reason;
  std::unique_ptr<net::executor_work_guard<net::io_context::executor_type>> work;
};

WsClient::WsClient(std::uint16_t port, const std::string& target, const std::string& ca_file, bool read_loop,
                   const std::string& origin)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.read_loop = read_loop;
  verifyAgainst(d.ctx, ca_file);
  d.ws = std::make_unique<websocket::stream<beast::ssl_stream<beast::tcp_stream>>>(d.ioc, d.ctx);
  auto& ssl_stream = d.ws->next_layer();
  ssl_stream.set_verify_callback(ssl::host_name_verification("127.0.0.1"));
  beast::get_lowest_layer(*d.ws).expires_after(std::chrono::seconds(5));
  beast::get_lowest_layer(*d.ws).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  beast::get_lowest_layer(*d.ws).socket().set_option(tcp::no_delay(true));  // as browsers do
  ssl_stream.handshake(ssl::stream_base::client);
  beast::get_lowest_layer(*d.ws).expires_never();
  d.ws->set_option(websocket::stream_base::timeout::suggested(beast::role_type::client));
  d.ws->set_option(websocket::stream_base::decorator([origin](websocket::request_type& req) {
    if (!origin.empty()) req.set(http::field::origin, origin);
  }));
  d.ws->handshake("127.0.0.1:" + std::to_string(port), target);
  if (!read_loop) return;
  d.work = std::make_unique<net::executor_work_guard<net::io_context::executor_type>>(d.ioc.get_executor());
  auto read = std::make_shared<std::function<void()>>();
  *read = [this, read] {
    impl_->ws->async_read(impl_->buffer, [this, read](beast::error_code ec, std::size_t) {
      if (ec) {
        {
          std::lock_guard<std::mutex> lock(impl_->mutex);
          impl_->close_reason = std::string(impl_->ws->reason().reason.c_str());
        }
        close_code_ = impl_->ws->reason().code;
        closed_ = true;
        impl_->work.reset();
        return;
      }
      {
        std::lock_guard<std::mutex> lock(impl_->mutex);
        impl_->messages.push_back(beast::buffers_to_string(impl_->buffer.data()));
      }
      impl_->buffer.consume(impl_->buffer.size());
      (*read)();
    });
  };
  net::post(d.ioc, [read] { (*read)(); });
  d.thread = std::thread([this] {
    try {
      impl_->ioc.run();
    } catch (...) {
      closed_ = true;
    }
  });
}

WsClient::~WsClient() {
  close();
  impl_->work.reset();
  impl_->ioc.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

bool WsClient::send(const std::string& payload, bool binary) {
  if (closed_) return false;
  if (!impl_->read_loop) {
    beast::error_code ec;
    impl_->ws->binary(binary);
    impl_->ws->write(net::buffer(payload), ec);
    return !ec;
  }
  auto done = std::make_shared<std::promise<bool>>();
  auto f = done->get_future();
  auto copy = std::make_shared<std::string>(payload);
  net::post(impl_->ioc, [this, done, copy, binary] {
    impl_->ws->binary(binary);
    impl_->ws->async_write(net::buffer(*copy),
                           [done, copy](beast::error_code ec, std::size_t) { done->set_value(!ec); });
  });
  if (f.wait_for(std::chrono::seconds(3)) != std::future_status::ready) return false;
  return f.get();
}

std::vector<std::string> WsClient::messages() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->messages;
}

std::string WsClient::closeReason() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->close_reason;
}

bool WsClient::waitClosed(std::chrono::milliseconds timeout) const {
  const auto end = Clock::now() + timeout;
  while (!closed_ && Clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  return closed_;
}

void WsClient::close() {
  if (closed_) return;
  if (!impl_->read_loop) {
    beast::error_code ec;
    impl_->ws->close(websocket::close_code::normal, ec);
    closed_ = true;
    return;
  }
  net::post(impl_->ioc, [this] { impl_->ws->async_close(websocket::close_code::normal, [](beast::error_code) {}); });
  waitClosed(std::chrono::milliseconds(2000));
}

HttpAnswer httpsRequest(std::uint16_t port, const std::string& method, const std::string& target,
                        const std::string& ca_file) {
  net::io_context ioc;
  ssl::context ctx{ssl::context::tls_client};
  verifyAgainst(ctx, ca_file);
  beast::ssl_stream<beast::tcp_stream> stream(ioc, ctx);
  stream.set_verify_callback(ssl::host_name_verification("127.0.0.1"));
  beast::get_lowest_layer(stream).expires_after(std::chrono::seconds(5));
  beast::get_lowest_layer(stream).connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
  stream.handshake(ssl::stream_base::client);
  http::request<http::empty_body> req{http::string_to_verb(method), target, 11};
  req.set(http::field::host, "127.0.0.1:" + std::to_string(port));
  req.keep_alive(false);
  http::write(stream, req);
  beast::flat_buffer buffer;
  http::response_parser<http::string_body> parser;
  parser.body_limit(16u << 20);
  if (method == "HEAD") parser.skip(true);
  http::read(stream, buffer, parser);
  const auto& res = parser.get();
  HttpAnswer a;
  a.status = static_cast<int>(res.result_int());
  a.content_type = std::string(res[http::field::content_type]);
  a.cache_control = std::string(res[http::field::cache_control]);
  a.body = res.body();
  const auto len = res[http::field::content_length];
  a.content_length = len.empty() ? 0 : static_cast<std::size_t>(std::stoul(std::string(len)));
  beast::error_code ec;
  stream.shutdown(ec);
  return a;
}

std::string privateLcmUrl() {
  const auto pid = static_cast<unsigned>(::getpid());
  return "udpm://239.255.76." + std::to_string(100 + pid % 100) + ":" + std::to_string(17000 + pid % 5000) + "?ttl=0";
}

std::string multicastUnavailable(const std::string& url) { return pmg::test::lcmMulticastUnavailable(url); }

struct VrPoseListener::Impl {
  lcm::LCM lcm;
  std::thread thread;
  std::atomic<bool> stop{false};
  mutable std::mutex mutex;
  mutable std::condition_variable cv;
  std::vector<Received> received;
  explicit Impl(const std::string& url) : lcm(url) {}
};

VrPoseListener::VrPoseListener(const std::string& url) : impl_(std::make_unique<Impl>(url)) {
  if (!impl_->lcm.good()) throw std::runtime_error("LCM cannot open " + url);
  struct Handler {
    static void on(const lcm::ReceiveBuffer* rbuf, const std::string&, Impl* d) {
      Received r;
      r.at = Clock::now();
      if (r.msg.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
      std::lock_guard<std::mutex> lock(d->mutex);
      d->received.push_back(r);
      d->cv.notify_all();
    }
  };
  impl_->lcm.subscribeFunction("PMG_VR_POSE", &Handler::on, impl_.get());
  impl_->thread = std::thread([d = impl_.get()] {
    while (!d->stop) d->lcm.handleTimeout(20);
  });
}

VrPoseListener::~VrPoseListener() {
  impl_->stop = true;
  impl_->thread.join();
}

std::vector<VrPoseListener::Received> VrPoseListener::received() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->received;
}

std::size_t VrPoseListener::count() const {
  std::lock_guard<std::mutex> lock(impl_->mutex);
  return impl_->received.size();
}

std::size_t VrPoseListener::waitFor(std::size_t n, std::chrono::milliseconds timeout) const {
  std::unique_lock<std::mutex> lock(impl_->mutex);
  impl_->cv.wait_for(lock, timeout, [&] { return impl_->received.size() >= n; });
  return impl_->received.size();
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, rank == 0 ? 0 : rank - 1)];
}

}  // namespace pmg::test::vr
