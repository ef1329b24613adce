#include "pmg/controller/lcm_command_source.hpp"

#include <cmath>
#include <cstring>
#include <stdexcept>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/mode_command_t.hpp>
#include <pmg_lcm/posture_command_t.hpp>
#include <pmg_lcm/velocity_command_t.hpp>
#include <pmg_lcm/vr_pose_t.hpp>

namespace pmg {

const char* toString(DecodeResult r) noexcept {
  switch (r) {
    case DecodeResult::kAccepted: return "accepted";
    case DecodeResult::kUnknownChannel: return "unknown channel";
    case DecodeResult::kTruncated: return "truncated";
    case DecodeResult::kTrailingBytes: return "trailing bytes";
    case DecodeResult::kBadFingerprint: return "bad fingerprint";
    case DecodeResult::kBadString: return "bad string";
    case DecodeResult::kNonFinite: return "non-finite value";
    case DecodeResult::kUnknownMode: return "unknown mode code";
    case DecodeResult::kOutOfRange: return "out of range";
    case DecodeResult::kUnauthenticated: return "unauthenticated";
    case DecodeResult::kBadMac: return "bad MAC";
    case DecodeResult::kReplayed: return "replayed";
    case DecodeResult::kStale: return "stale";
    case DecodeResult::kTooManySenders: return "too many senders";
    case DecodeResult::kInternalError: return "internal decoder error";
    case DecodeResult::kCount: break;
  }
  return "unknown";
}

DecodeResult toDecodeResult(comms::VerifyResult r) noexcept {
  switch (r) {
    case comms::VerifyResult::kOk: return DecodeResult::kAccepted;
    case comms::VerifyResult::kUnauthenticated: return DecodeResult::kUnauthenticated;
    case comms::VerifyResult::kBadMac: return DecodeResult::kBadMac;
    case comms::VerifyResult::kReplayed: return DecodeResult::kReplayed;
    case comms::VerifyResult::kStale: return DecodeResult::kStale;
    case comms::VerifyResult::kTooManySenders: return DecodeResult::kTooManySenders;
  }
  return DecodeResult::kInternalError;
}

std::uint64_t LcmInputCounters::rejected() const noexcept {
  std::uint64_t n = 0;
  for (std::size_t i = 1; i < kNumDecodeResults; ++i) n += counts_[i].load(std::memory_order_relaxed);
  return n;
}

namespace {

/// Big-endian reader over a packet that never reads past its end.
class Reader {
 public:
  Reader(const void* data, std::size_t size) : p_(static_cast<const std::uint8_t*>(data)), n_(size) {}
  bool u64(std::uint64_t& v) noexcept {
    if (n_ - pos_ < 8 || pos_ > n_) return false;
    v = 0;
    for (int i = 0; i < 8; ++i) v = (v << 8) | p_[pos_ + static_cast<std::size_t>(i)];
    pos_ += 8;
    return true;
  }
  bool f64(double& v) noexcept {
    std::uint64_t u;
    if (!u64(u)) return false;
    std::memcpy(&v, &u, sizeof v);
    return true;
  }
  bool i32(std::int32_t& v) noexcept {
    if (pos_ > n_ || n_ - pos_ < 4) return false;
    std::uint32_t u = 0;
    for (int i = 0; i < 4; ++i) u = (u << 8) | p_[pos_ + static_cast<std::size_t>(i)];
    pos_ += 4;
    v = static_cast<std::int32_t>(u);
    return true;
  }
  bool i8(std::int8_t& v) noexcept {
    if (pos_ >= n_) return false;
    v = static_cast<std::int8_t>(p_[pos_++]);
    return true;
  }
  /// LCM string: int32 length including the NUL, then the bytes.
  DecodeResult string() noexcept {
    std::int32_t len = 0;
    if (!i32(len)) return DecodeResult::kTruncated;
    if (len <= 0 || len > kMaxSourceBytes) return DecodeResult::kBadString;
    const auto L = static_cast<std::size_t>(len);
    if (n_ - pos_ < L) return DecodeResult::kTruncated;
    if (p_[pos_ + L - 1] != 0 || std::memchr(p_ + pos_, 0, L - 1) != nullptr) return DecodeResult::kBadString;
    pos_ += L;
    return DecodeResult::kAccepted;
  }
  bool atEnd() const noexcept { return pos_ == n_; }

 private:
  const std::uint8_t* p_;
  std::size_t n_;
  std::size_t pos_ = 0;
};

DecodeResult checkHeader(Reader& r, std::int64_t expected_hash) noexcept {
  std::uint64_t hash = 0, utime = 0;
  if (!r.u64(hash)) return DecodeResult::kTruncated;
  if (static_cast<std::int64_t>(hash) != expected_hash) return DecodeResult::kBadFingerprint;
  if (!r.u64(utime)) return DecodeResult::kTruncated;
  return DecodeResult::kAccepted;
}

DecodeResult finish(Reader& r) noexcept {
  const DecodeResult s = r.string();
  if (s != DecodeResult::kAccepted) return s;
  return r.atEnd() ? DecodeResult::kAccepted : DecodeResult::kTrailingBytes;
}

DecodeResult decodeVelocity(Reader& r, Command& u) noexcept {
  DecodeResult h = checkHeader(r, pmg_lcm::velocity_command_t::getHash());
  if (h != DecodeResult::kAccepted) return h;
  double v[3];
  for (double& x : v)
    if (!r.f64(x)) return DecodeResult::kTruncated;
  if (const DecodeResult e = finish(r); e != DecodeResult::kAccepted) return e;
  for (double x : v)
    if (!std::isfinite(x)) return DecodeResult::kNonFinite;
  u.vx = v[0];
  u.vy = v[1];
  u.wz = v[2];
  return DecodeResult::kAccepted;
}

DecodeResult decodePosture(Reader& r, Command& u) noexcept {
  DecodeResult h = checkHeader(r, pmg_lcm::posture_command_t::getHash());
  if (h != DecodeResult::kAccepted) return h;
  double pitch = 0, roll = 0, height = 0;
  std::int8_t has_height = 0;
  if (!r.f64(pitch) || !r.f64(roll) || !r.i8(has_height) || !r.f64(height)) return DecodeResult::kTruncated;
  if (const DecodeResult e = finish(r); e != DecodeResult::kAccepted) return e;
  if (!std::isfinite(pitch) || !std::isfinite(roll) || (has_height && !std::isfinite(height)))
    return DecodeResult::kNonFinite;
  u.pitch = pitch;
  u.roll = roll;
  u.height.reset();
  if (has_height) u.height = height;
  return DecodeResult::kAccepted;
}

DecodeResult decodeMode(Reader& r, ModeRequest& request) noexcept {
  DecodeResult h = checkHeader(r, pmg_lcm::mode_command_t::getHash());
  if (h != DecodeResult::kAccepted) return h;
  std::int8_t code = 0;
  if (!r.i8(code)) return DecodeResult::kTruncated;
  if (const DecodeResult e = finish(r); e != DecodeResult::kAccepted) return e;
  if (!modeRequestFromWire(code, request)) return DecodeResult::kUnknownMode;
  return DecodeResult::kAccepted;
}

/// Decodes PMG_VR_POSE (lcmtypes/vr_pose_t.lcm, field order) into @p out.
DecodeResult decodeVrPose(Reader& r, teleop::VrSample& out) noexcept {
  DecodeResult h = checkHeader(r, pmg_lcm::vr_pose_t::getHash());
  if (h != DecodeResult::kAccepted) return h;
  teleop::VrSample v;
  std::uint64_t xr_time = 0, frame = 0;
  if (!r.u64(xr_time) || !r.u64(frame)) return DecodeResult::kTruncated;
  v.xr_time_us = static_cast<std::int64_t>(xr_time);
  v.frame = static_cast<std::int64_t>(frame);
  // Every double of the message, in wire order, into its VrSample field.
  const auto f64s = [&r](double* p, int n) noexcept {
    for (int i = 0; i < n; ++i)
      if (!r.f64(p[i])) return false;
    return true;
  };
  std::int8_t valid[2] = {0, 0};
  std::int32_t buttons[2] = {0, 0};
  if (!f64s(v.head_position.data(), 3) || !f64s(v.head_quat.data(), 4) || !r.i8(valid[0]) || !r.i8(valid[1]))
    return DecodeResult::kTruncated;
  for (auto& p : v.hand_position)
    if (!f64s(p.data(), 3)) return DecodeResult::kTruncated;
  for (auto& q : v.hand_quat)
    if (!f64s(q.data(), 4)) return DecodeResult::kTruncated;
  if (!f64s(v.grip.data(), 2) || !f64s(v.trigger.data(), 2) || !r.i32(buttons[0]) || !r.i32(buttons[1]))
    return DecodeResult::kTruncated;
  for (auto& t : v.thumbstick)
    if (!f64s(t.data(), 2)) return DecodeResult::kTruncated;
  if (const DecodeResult e = finish(r); e != DecodeResult::kAccepted) return e;

  // Finite first (a NaN is "non-finite", not "out of range"), then the ranges.
  bool finite = true;
  const auto all = [&finite](const double* p, std::size_t n) noexcept {
    for (std::size_t i = 0; i < n; ++i) finite = finite && std::isfinite(p[i]);
  };
  all(v.head_position.data(), 3);
  all(v.head_quat.data(), 4);
  for (int k = 0; k < 2; ++k) {
    all(v.hand_position[k].data(), 3);
    all(v.hand_quat[k].data(), 4);
    all(v.thumbstick[k].data(), 2);
  }
  all(v.grip.data(), 2);
  all(v.trigger.data(), 2);
  if (!finite) return DecodeResult::kNonFinite;
  const auto unit = [](const std::array<double, 4>& q) noexcept {
    const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    return std::fabs(n - 1.0) <= kVrQuaternionTolerance;
  };
  const auto in = [](double x, double lo, double hi) noexcept { return x >= lo && x <= hi; };
  constexpr std::uint32_t kKnownButtons =
      teleop::kVrButtonLower | teleop::kVrButtonUpper | teleop::kVrButtonThumbstick | teleop::kVrButtonMenu;
  bool ok = unit(v.head_quat);
  for (int k = 0; k < 2; ++k) {
    ok = ok && unit(v.hand_quat[k]) && in(v.grip[k], 0.0, 1.0) && in(v.trigger[k], 0.0, 1.0) &&
         in(v.thumbstick[k][0], -1.0, 1.0) && in(v.thumbstick[k][1], -1.0, 1.0) && (valid[k] == 0 || valid[k] == 1) &&
         (static_cast<std::uint32_t>(buttons[k]) & ~kKnownButtons) == 0;
    v.hand_valid[k] = valid[k] == 1;
    v.buttons[k] = static_cast<std::uint32_t>(buttons[k]);
  }
  if (!ok) return DecodeResult::kOutOfRange;
  out = v;
  return DecodeResult::kAccepted;
}

}  // namespace

LcmCommandDecoder::LcmCommandDecoder() = default;
LcmCommandDecoder::~LcmCommandDecoder() = default;

void LcmCommandDecoder::requireAuthentication(const comms::AuthKey& key, const comms::VerifierOptions& options,
                                              comms::MessageVerifier::WallClock clock, const void* clock_context) {
  verifier_ = std::make_unique<comms::MessageVerifier>(key, options, clock, clock_context);
}

DecodeResult LcmCommandDecoder::decode(std::string_view channel, const void* data, std::size_t size,
                                       double receive_time_s, CommandSample& sample) noexcept {
  DecodeResult result = DecodeResult::kUnknownChannel;
  if (data == nullptr) size = 0;
  const bool known = channel == kVelocityChannel || channel == kPostureChannel || channel == kModeChannel ||
                     channel == kVrPoseChannel;
  if (known && verifier_) {
    // Authentication before anything is decoded; the raw checks then see the payload alone (its
    // exact size excludes the trailer).
    std::size_t payload_size = 0;
    result = toDecodeResult(verifier_->verify(channel, data, size, payload_size));
    if (result != DecodeResult::kAccepted) {
      counters_.add(result);
      return result;
    }
    size = payload_size;
    result = DecodeResult::kUnknownChannel;
  } else if (known && comms::hasTrailerHeader(data, size)) {
    size -= comms::kAuthTrailerBytes;  // no key configured: a signed message's trailer is ignored
  }
  Reader r(data, size);
  Command u = sample.command;
  if (!known) {
    // counted below as kUnknownChannel
  } else if (channel == kVelocityChannel) {
    result = decodeVelocity(r, u);
    if (result == DecodeResult::kAccepted) {
      sample.command.vx = u.vx;
      sample.command.vy = u.vy;
      sample.command.wz = u.wz;
      sample.velocity_time = receive_time_s;
    }
  } else if (channel == kPostureChannel) {
    result = decodePosture(r, u);
    if (result == DecodeResult::kAccepted) {
      sample.command.pitch = u.pitch;
      sample.command.roll = u.roll;
      sample.command.height = u.height;
      sample.posture_time = receive_time_s;
    }
  } else if (channel == kModeChannel) {
    ModeRequest request = ModeRequest::kNone;
    result = decodeMode(r, request);
    if (result == DecodeResult::kAccepted) {
      sample.mode_request = request;
      ++sample.mode_request_seq;
    }
  } else if (channel == kVrPoseChannel) {
    result = decodeVrPose(r, sample.vr);  // writes sample.vr only when accepted
    if (result == DecodeResult::kAccepted) sample.vr_time = receive_time_s;
  }
  counters_.add(result);
  return result;
}

// ------------------------------------------------------------------------------ receive thread

LcmCommandSource::LcmCommandSource(const std::string& url, Sink sink, void* sink_context, Clock clock,
                                   const void* clock_context)
    : lcm_(std::make_unique<lcm::LCM>(url)),
      sink_(sink),
      sink_context_(sink_context),
      clock_(clock),
      clock_context_(clock_context) {
  if (!lcm_->good()) throw std::runtime_error("LCM provider '" + url + "' not available for command input");
  if (sink_ == nullptr || clock_ == nullptr) throw std::invalid_argument("LcmCommandSource: null sink or clock");
  struct Raw {
    static void handle(const lcm::ReceiveBuffer* rbuf, const std::string& channel, LcmCommandSource* self) noexcept {
      // noexcept: nothing may escape into LCM's dispatch; the decoder itself does not throw.
      const double now = self->clock_(self->clock_context_);
      if (self->decoder_.decode(channel, rbuf->data, rbuf->data_size, now, self->sample_) == DecodeResult::kAccepted)
        self->sink_(self->sink_context_, self->sample_);
    }
  };
  for (const char* ch : {kVelocityChannel, kPostureChannel, kModeChannel, kVrPoseChannel}) {
    lcm::Subscription* sub = lcm_->subscribeFunction(ch, &Raw::handle, this);
    if (sub == nullptr) throw std::runtime_error(std::string("LCM: cannot subscribe to ") + ch);
    sub->setQueueCapacity(kLcmQueueCapacity);
  }
}

LcmCommandSource::~LcmCommandSource() { stop(); }

void LcmCommandSource::requireAuthentication(const comms::AuthKey& key, const comms::VerifierOptions& options) {
  if (running_.load()) throw std::logic_error("LcmCommandSource::requireAuthentication after start()");
  decoder_.requireAuthentication(key, options);
}

void LcmCommandSource::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] { threadMain(); });
}

void LcmCommandSource::stop() {
  running_ = false;
  if (thread_.joinable()) thread_.join();
}

void LcmCommandSource::threadMain() noexcept {
  while (running_.load()) {
    try {
      lcm_->handleTimeout(20);
    } catch (...) {
      // Unreachable by design (the handler is noexcept, LCM's C core does not throw); counted if
      // it ever happens, and the thread keeps serving.
      decoder_.countInternalError();
    }
  }
}

}  // namespace pmg
