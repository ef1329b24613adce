#pragma once
/// @file vr_protocol.hpp
/// The WebXR page ↔ pmg_vr_bridge protocol (JSON text messages over a secure WebSocket) and its
/// conversion into pmg::teleop::VrSample / `pmg_lcm::vr_pose_t` (channel pmg::kVrPoseChannel,
/// "PMG_VR_POSE").
///
/// Page → bridge, one message per XR frame (docs/teleop.md, data/vr/web/vr.js):
///
///     {"type":"pose","frame":N,"t":xr_time_ms,
///      "head":{"p":[x,y,z],"q":[x,y,z,w]},
///      "hands":[{"valid":b,"p":[x,y,z],"q":[x,y,z,w],"grip":g,"trigger":t,"buttons":bits,"stick":[ax2,ax3]},
///               {...right...}]}
///
///  - frame F_xr (WebXR `local-floor` reference space): x right, y up, −z forward [m];
///    quaternions in WebXR's DOMPoint order x, y, z, w;
///  - `frame`: integer page frame counter, 0 ≤ frame ≤ 2^53 − 1, strictly increasing per connection;
///  - `t`: XRFrame time [ms] (DOMHighResTimeStamp), finite, 0 ≤ t ≤ 1e12;
///  - `hands[0]` is the left controller, `hands[1]` the right one; every key is always present
///    (an untracked controller sends valid:false and any finite pose);
///  - `grip` = xr-standard buttons[1].value, `trigger` = buttons[0].value, both in [0, 1];
///  - `buttons`: pmg::teleop::VrButton bits (0 … 15; other bits are refused);
///  - `stick` = xr-standard gamepad axes [2], [3] as the Gamepad API reports them (x right,
///    y *down/back*), each in [−1, 1].
///
/// Everything is checked: at most kVrMaxMessageBytes bytes, valid JSON, no duplicate or unknown
/// key, every key present with its type, finite numbers, positions within ±kVrMaxPositionAbs,
/// unit quaternions (|‖q‖ − 1| ≤ kVrQuatNormTolerance; accepted ones are renormalised). A refused
/// message changes nothing and yields a VrReject reason plus a one-line detail naming the key.
///
/// Conversion F_xr → V (include/pmg/teleop/vr_sample.hpp; x forward, y left, z up):
/// p_V = (−z, −x, y); the quaternion's vector part maps the same way (a proper rotation, det = +1),
/// w is kept, and the order becomes w, x, y, z. The thumbstick becomes (x right, y forward) =
/// (axes[2], −axes[3]); `t` [ms] becomes xr_time_us = round(t · 1000).
///
/// Setup/receive-thread code: allocates (JSON parsing), never throws out of these functions.

#include <array>
#include <cstddef>
#include <cstdint>
#include <pmg_lcm/vr_pose_t.hpp>
#include <string>
#include <string_view>

#include "pmg/teleop/vr_sample.hpp"

namespace pmg::teleop {

/// `vr_pose_t::source` the bridge writes (the LCM channel is pmg::kVrPoseChannel,
/// include/pmg/comms/channels.hpp).
inline constexpr const char* kVrSource = "vr";
/// Largest message the parser accepts [bytes]; a real pose message is ≈ 450 bytes.
inline constexpr std::size_t kVrMaxMessageBytes = 4096;
/// Bound on every position coordinate [m] (a room-scale space is a few metres).
inline constexpr double kVrMaxPositionAbs = 100.0;
/// Allowed |‖q‖ − 1| of a quaternion (the same tolerance as the controller's decoder).
inline constexpr double kVrQuatNormTolerance = 1e-3;
/// Largest frame counter (JavaScript's Number.MAX_SAFE_INTEGER).
inline constexpr std::int64_t kVrMaxFrame = (std::int64_t{1} << 53) - 1;
/// Largest XR time [ms] (≈ 31 years of session time).
inline constexpr double kVrMaxTimeMs = 1e12;

/// Why a message from the page was refused. kAccepted is 0; the rest are counted per reason.
enum class VrReject : int {
  kAccepted = 0,
  kTooLarge,            ///< more than kVrMaxMessageBytes bytes
  kBinaryFrame,         ///< a binary WebSocket message (the protocol is text only)
  kBadJson,             ///< not valid JSON (includes NaN/Infinity literals, trailing garbage)
  kDuplicateKey,        ///< the same key twice in one object
  kNotObject,           ///< top level is not an object
  kUnknownType,         ///< "type" is not "pose"
  kUnknownKey,          ///< a key the protocol does not define
  kMissingKey,          ///< a required key is absent
  kWrongType,           ///< a value of the wrong JSON type (string for number, 2 hands != array of 2 ...)
  kNonFinite,           ///< a number that is not finite (checkVrPoseMessage; JSON text cannot carry one:
                        ///< NaN/Infinity and overflowing literals such as 1e999 are kBadJson)
  kOutOfRange,          ///< a number outside its range (grip > 1, |p| > 100 m, frame < 0 ...)
  kNotUnitQuaternion,   ///< |‖q‖ − 1| > kVrQuatNormTolerance
  kUnknownButtonBits,   ///< `buttons` has bits outside VrButton
  kFrameNotIncreasing,  ///< session check: frame ≤ the previous accepted frame of this connection
  kRateLimited,         ///< session check: more messages per second than the server allows
  kCount
};
inline constexpr int kVrRejectCount = static_cast<int>(VrReject::kCount);

/// Snake-case name of @p r ("accepted", "too_large", "bad_json", ...), as shown in stats and on
/// the page.
const char* toString(VrReject r) noexcept;

/// F_xr (x right, y up, −z forward) position → frame V (x forward, y left, z up): (−z, −x, y).
std::array<double, 3> webxrToV(const std::array<double, 3>& p_xr) noexcept;
/// F_xr orientation (x, y, z, w order) → frame V orientation (w, x, y, z order).
std::array<double, 4> webxrQuatToV(const std::array<double, 4>& q_xr_xyzw) noexcept;

/// Parses and checks one page message and converts it into @p out (frame V). On any error
/// @p out is unchanged, the reason is returned and, if @p detail is given, a one-line
/// explanation naming the key (e.g. "hands[1].q: norm 0.930, expected 1 ± 0.001").
/// Never throws (an allocation failure is reported as kBadJson).
VrReject parseVrMessage(std::string_view text, VrSample& out, std::string* detail = nullptr) noexcept;

/// The LCM message for @p s: frame V values copied, `utime` = @p receive_utime [µs, bridge wall
/// clock], `source` = "vr".
pmg_lcm::vr_pose_t toVrPoseMessage(const VrSample& s, std::int64_t receive_utime);

/// Checks a decoded `vr_pose_t` (e.g. read back from a log file, which is outside input too):
/// finite values, positions within ±kVrMaxPositionAbs, unit quaternions, grip/trigger in [0, 1],
/// thumbsticks in [−1, 1], known button bits, `source` at most 63 bytes. Returns kAccepted or the
/// first failed check with @p detail.
VrReject checkVrPoseMessage(const pmg_lcm::vr_pose_t& m, std::string* detail = nullptr) noexcept;

}  // namespace pmg::teleop
