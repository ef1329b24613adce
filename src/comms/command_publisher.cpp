#include "pmg/comms/command_publisher.hpp"

#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>
#include <pmg_lcm/vr_pose_t.hpp>

namespace pmg::comms {

namespace {
/// Longest `source` string the controller accepts, without its NUL (kMaxSourceBytes − 1).
constexpr std::size_t kMaxSourceChars = 63;
}  // namespace

CommandPublisher::CommandPublisher(const std::string& lcm_url, const std::string& key_file, std::string source)
    : source_(std::move(source)) {
  if (source_.empty() || source_.size() > kMaxSourceChars || source_.find('\0') != std::string::npos)
    throw std::invalid_argument("CommandPublisher: source '" + source_ + "': expected 1..63 characters");
  if (!key_file.empty()) {
    const AuthKey key = loadAuthKey(key_file);
    signer_ = std::make_unique<MessageSigner>(key);
    key_id_ = comms::keyId(key);
  }
  lcm_ = std::make_unique<lcm::LCM>(lcm_url);
  if (!lcm_->good()) throw std::runtime_error("LCM provider '" + lcm_url + "' not available");
  buffer_.reserve(4096);
}

CommandPublisher::~CommandPublisher() = default;

std::uint32_t CommandPublisher::senderId() const noexcept { return signer_ ? signer_->senderId() : 0u; }

namespace {

/// Encodes @p msg into @p out (resized to the encoded size). False if the encoder fails.
template <class Msg>
bool encodeInto(const Msg& msg, std::vector<std::uint8_t>& out) {
  const int n = msg.getEncodedSize();
  if (n < 0) return false;
  out.resize(static_cast<std::size_t>(n));
  return msg.encode(out.data(), 0, n) == n;
}

}  // namespace

bool CommandPublisher::send(const char* channel) {
  if (signer_) signer_->sign(channel, buffer_);
  if (lcm_->publish(channel, buffer_.data(), static_cast<unsigned>(buffer_.size())) != 0) {
    failed_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  published_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

bool CommandPublisher::publishVelocity(double vx, double vy, double wz) {
  pmg_lcm::velocity_command_t m;
  m.utime = wallClockNowUs();
  m.vx = vx;
  m.vy = vy;
  m.wz = wz;
  m.source = source_;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!encodeInto(m, buffer_)) return failed_.fetch_add(1, std::memory_order_relaxed), false;
  return send(kVelocityChannel);
}

bool CommandPublisher::publishPosture(double pitch, double roll, std::optional<double> height) {
  pmg_lcm::posture_command_t m;
  m.utime = wallClockNowUs();
  m.pitch = pitch;
  m.roll = roll;
  m.has_height = height.has_value();
  m.height = height.value_or(0.0);
  m.source = source_;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!encodeInto(m, buffer_)) return failed_.fetch_add(1, std::memory_order_relaxed), false;
  return send(kPostureChannel);
}

bool CommandPublisher::publishMode(pmg::ModeRequest request) {
  if (request == ModeRequest::kNone) {
    failed_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  pmg_lcm::mode_command_t m;
  m.utime = wallClockNowUs();
  m.mode = static_cast<std::int8_t>(request);
  m.source = source_;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!encodeInto(m, buffer_)) return failed_.fetch_add(1, std::memory_order_relaxed), false;
  return send(kModeChannel);
}

bool CommandPublisher::publishVrPose(const pmg_lcm::vr_pose_t& pose) {
  pmg_lcm::vr_pose_t m = pose;
  m.utime = wallClockNowUs();
  m.source = source_;
  std::lock_guard<std::mutex> lock(mutex_);
  if (!encodeInto(m, buffer_)) return failed_.fetch_add(1, std::memory_order_relaxed), false;
  return send(kVrPoseChannel);
}

bool CommandPublisher::publishEncoded(const std::string& channel, const std::vector<std::uint8_t>& lcm_bytes) {
  if (channel.empty() || channel.size() > kMaxChannelBytes) {
    failed_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  std::size_t n = lcm_bytes.size();
  if (hasTrailerHeader(lcm_bytes.data(), n)) {
    if (signer_ && !tagValid(signer_->key(), channel, lcm_bytes.data(), n)) {
      failed_.fetch_add(1, std::memory_order_relaxed);
      return false;
    }
    n -= kAuthTrailerBytes;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  buffer_.assign(lcm_bytes.begin(), lcm_bytes.begin() + static_cast<std::ptrdiff_t>(n));
  return send(channel.c_str());
}

}  // namespace pmg::comms
