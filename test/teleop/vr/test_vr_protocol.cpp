// The page → bridge protocol (vr_protocol.cpp): every malformed message is refused with its cause
// and changes nothing; the WebXR → V frame conversion; the synthetic pattern passes the checks.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "pmg/teleop/vr_protocol.hpp"
#include "pmg/teleop/vr_synthetic.hpp"

namespace pmg::teleop {
namespace {

constexpr double kPi = 3.14159265358979323846;

/// A valid message with one substitution: @p from → @p to (must occur in the text).
std::string valid() { return toWireJson(syntheticWirePose(100)); }
std::string with(const std::string& from, const std::string& to) {
  std::string s = valid();
  const auto at = s.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) s.replace(at, from.size(), to);
  return s;
}

/// Rotates v by the unit quaternion q (w x y z).
std::array<double, 3> rotate(const std::array<double, 4>& q, const std::array<double, 3>& v) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)},
                          {2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)},
                          {2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)}};
  return {r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2], r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2],
          r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2]};
}

struct Bad {
  const char* name;
  std::string text;
  VrReject expected;
  const char* detail_mentions;  // the detail names the key
};

std::vector<Bad> badMessages() {
  const std::string v = valid();
  std::vector<Bad> c;
  c.push_back({"empty", "", VrReject::kBadJson, "JSON"});
  c.push_back({"not JSON", "hello", VrReject::kBadJson, "JSON"});
  c.push_back({"truncated", v.substr(0, v.size() / 2), VrReject::kBadJson, "JSON"});
  c.push_back({"trailing garbage", v + "x", VrReject::kBadJson, "JSON"});
  c.push_back({"two messages", v + v, VrReject::kBadJson, "JSON"});
  c.push_back({"NaN literal", with("\"grip\":1", "\"grip\":NaN"), VrReject::kBadJson, "JSON"});
  c.push_back({"Infinity literal", with("\"grip\":1", "\"grip\":Infinity"), VrReject::kBadJson, "JSON"});
  c.push_back({"overflowing number", with("\"grip\":1", "\"grip\":1e999"), VrReject::kBadJson, "JSON"});
  c.push_back({"array top level", "[" + v + "]", VrReject::kNotObject, "object"});
  c.push_back({"string top level", "\"pose\"", VrReject::kNotObject, "object"});
  c.push_back({"oversize", std::string(5000, ' ') + v, VrReject::kTooLarge, "bytes"});
  c.push_back({"duplicate key", with("\"frame\":", "\"frame\":1,\"frame\":"), VrReject::kDuplicateKey, "frame"});
  c.push_back({"type missing", with("\"type\":\"pose\",", ""), VrReject::kMissingKey, "type"});
  c.push_back({"type not a string", with("\"type\":\"pose\"", "\"type\":1"), VrReject::kWrongType, "type"});
  c.push_back({"unknown type", with("\"type\":\"pose\"", "\"type\":\"hello\""), VrReject::kUnknownType, "hello"});
  c.push_back({"unknown top key", with("\"frame\":", "\"extra\":0,\"frame\":"), VrReject::kUnknownKey, "extra"});
  c.push_back({"unknown head key", with("\"head\":{", "\"head\":{\"v\":[0,0,0],"), VrReject::kUnknownKey, "head.v"});
  c.push_back({"unknown hand key", with("\"valid\":true", "\"valid\":true,\"pinch\":1"), VrReject::kUnknownKey,
               "hands[0].pinch"});
  c.push_back({"frame missing", with("\"frame\":100,", ""), VrReject::kMissingKey, "frame"});
  c.push_back({"frame a float", with("\"frame\":100", "\"frame\":100.5"), VrReject::kWrongType, "frame"});
  c.push_back({"frame a string", with("\"frame\":100", "\"frame\":\"100\""), VrReject::kWrongType, "frame"});
  c.push_back({"frame negative", with("\"frame\":100", "\"frame\":-1"), VrReject::kOutOfRange, "frame"});
  c.push_back(
      {"frame above 2^53", with("\"frame\":100", "\"frame\":9007199254740993"), VrReject::kOutOfRange, "frame"});
  c.push_back(
      {"frame above int64", with("\"frame\":100", "\"frame\":18446744073709551615"), VrReject::kOutOfRange, "frame"});
  c.push_back({"head.p of 2", with("\"head\":{\"p\":[0,", "\"head\":{\"p\":["), VrReject::kWrongType, "head.p"});
  c.push_back({"head.p string element", with("\"head\":{\"p\":[0,", "\"head\":{\"p\":[\"0\","), VrReject::kWrongType,
               "head.p[0]"});
  c.push_back(
      {"head.p null", with("\"head\":{\"p\":[0,", "\"head\":{\"p\":[null,"), VrReject::kWrongType, "head.p[0]"});
  c.push_back(
      {"head far away", with("\"head\":{\"p\":[0,", "\"head\":{\"p\":[1000,"), VrReject::kOutOfRange, "head.p[0]"});
  c.push_back({"head.q not unit", with("\"q\":[0,", "\"q\":[0.3,"), VrReject::kNotUnitQuaternion, "head.q"});
  {
    VrWirePose p = syntheticWirePose(100);
    p.head_q = {0.0, 0.0, 0.0, 0.0};
    c.push_back({"head.q zero", toWireJson(p), VrReject::kNotUnitQuaternion, "head.q"});
    p = syntheticWirePose(100);
    p.hand_q[1] = {1.0, 1.0, 0.0, 0.0};
    c.push_back({"right hand q not unit", toWireJson(p), VrReject::kNotUnitQuaternion, "hands[1].q"});
    p = syntheticWirePose(100);
    p.hand_p[0][2] = -150.0;
    c.push_back({"hand far away", toWireJson(p), VrReject::kOutOfRange, "hands[0].p[2]"});
  }
  c.push_back({"hands an object", v.substr(0, v.find("\"hands\":")) + "\"hands\":{}}", VrReject::kWrongType, "hands"});
  c.push_back({"hands missing", v.substr(0, v.find(",\"hands\":")) + "}", VrReject::kMissingKey, "hands"});
  c.push_back({"one hand", with("\"hands\":[{", "\"hands\":[0,{"), VrReject::kWrongType, "hands"});
  c.push_back({"valid not bool", with("\"valid\":true", "\"valid\":1"), VrReject::kWrongType, "hands[0].valid"});
  c.push_back({"grip above 1", with("\"grip\":1", "\"grip\":1.5"), VrReject::kOutOfRange, "hands[0].grip"});
  c.push_back({"grip negative", with("\"grip\":1", "\"grip\":-0.1"), VrReject::kOutOfRange, "hands[0].grip"});
  c.push_back({"grip string", with("\"grip\":1", "\"grip\":\"1\""), VrReject::kWrongType, "hands[0].grip"});
  c.push_back({"unknown button bits", with("\"buttons\":0", "\"buttons\":16"), VrReject::kUnknownButtonBits,
               "hands[0].buttons"});
  c.push_back({"negative buttons", with("\"buttons\":0", "\"buttons\":-1"), VrReject::kOutOfRange, "hands[0].buttons"});
  c.push_back({"stick out of range", with("\"stick\":[0,-0.5]", "\"stick\":[0,-1.5]"), VrReject::kOutOfRange,
               "hands[1].stick[1]"});
  c.push_back({"stick of 3", with("\"stick\":[0,-0.5]", "\"stick\":[0,0,0]"), VrReject::kWrongType, "hands[1].stick"});
  c.push_back({"deep nesting", with("\"grip\":1", "\"grip\":[[[[1]]]]"), VrReject::kWrongType, "nested"});
  return c;
}

TEST(VrProtocol, MalformedMessagesAreRefusedWithTheirCauseAndChangeNothing) {
  for (const Bad& b : badMessages()) {
    VrSample s;
    s.frame = -77;  // marker: must stay
    std::string detail;
    const VrReject r = parseVrMessage(b.text, s, &detail);
    EXPECT_EQ(r, b.expected) << b.name << ": got " << toString(r) << " (" << detail << ")";
    EXPECT_NE(detail.find(b.detail_mentions), std::string::npos) << b.name << ": detail '" << detail << "'";
    EXPECT_EQ(s.frame, -77) << b.name << ": output changed";
  }
}

TEST(VrProtocol, RangeChecksOfTimeAndQuaternions) {
  VrSample s;
  std::string d;
  const std::string v = valid();
  const auto t_at = v.find("\"t\":") + 4;
  const auto t_end = v.find(',', t_at);
  for (const char* t : {"-1", "1e13"}) {
    std::string m = v;
    m.replace(t_at, t_end - t_at, t);
    EXPECT_EQ(parseVrMessage(m, s, &d), VrReject::kOutOfRange) << t << ": " << d;
  }
  // A quaternion off by 2e-3 in norm is refused, one off by 5e-4 accepted and renormalised.
  VrWirePose p = syntheticWirePose(5);
  p.head_q = {0.0, 0.0, 0.0, 1.002};
  EXPECT_EQ(parseVrMessage(toWireJson(p), s, &d), VrReject::kNotUnitQuaternion) << d;
  p.head_q = {0.0, 0.0, 0.0, 1.0005};
  ASSERT_EQ(parseVrMessage(toWireJson(p), s, &d), VrReject::kAccepted) << d;
  EXPECT_DOUBLE_EQ(s.head_quat[0], 1.0);
}

TEST(VrProtocol, EveryRejectReasonHasAName) {
  for (int r = 0; r < kVrRejectCount; ++r) EXPECT_STRNE(toString(static_cast<VrReject>(r)), "unknown") << r;
}

TEST(VrProtocol, ForwardStepInWebXrIsPlusXInV) {
  // WebXR: the user steps 0.5 m forward (−z), 0.2 m right (+x), head at 1.7 m (y).
  const auto p = webxrToV({0.2, 1.7, -0.5});
  EXPECT_DOUBLE_EQ(p[0], 0.5) << "forward";
  EXPECT_DOUBLE_EQ(p[1], -0.2) << "right is −y (y left)";
  EXPECT_DOUBLE_EQ(p[2], 1.7) << "up";
  // Through the parser: head p (0, 1.6, −walked) at frame 144 (t = 2 s, walked 0.6 m).
  VrSample s;
  ASSERT_EQ(parseVrMessage(toWireJson(syntheticWirePose(144)), s), VrReject::kAccepted);
  EXPECT_NEAR(s.head_position[0], 0.6, 1e-12);
  EXPECT_NEAR(s.head_position[1], 0.0, 1e-12);
  EXPECT_NEAR(s.head_position[2], 1.6, 1e-12);
  EXPECT_EQ(s.xr_time_us, 2000000);
  EXPECT_EQ(s.frame, 144);
}

TEST(VrProtocol, YawLeftInWebXrIsPositiveYawAboutZInV) {
  // Turning the head 30° to the left is a rotation about WebXR +y (up).
  const double a = 30.0 * kPi / 180.0;
  const auto q = webxrQuatToV({0.0, std::sin(a / 2), 0.0, std::cos(a / 2)});
  EXPECT_NEAR(q[0], std::cos(a / 2), 1e-15);
  EXPECT_NEAR(q[1], 0.0, 1e-15);
  EXPECT_NEAR(q[2], 0.0, 1e-15);
  EXPECT_NEAR(q[3], std::sin(a / 2), 1e-15) << "yaw about V's +z";
  const auto fwd = rotate(q, {1.0, 0.0, 0.0});
  EXPECT_NEAR(fwd[0], std::cos(a), 1e-12);
  EXPECT_NEAR(fwd[1], std::sin(a), 1e-12) << "the gaze turns to +y, the left";
  // A pitch down (about WebXR +x, which is V's −y): the gaze goes to −z in V.
  const auto qp = webxrQuatToV({std::sin(-0.2), 0.0, 0.0, std::cos(-0.2)});
  const auto g = rotate(qp, {1.0, 0.0, 0.0});
  EXPECT_LT(g[2], -0.3) << "looking down";
  // The conversion agrees with converting vectors: R_V(q) · (p in V) = convert(R_xr(q) · p_xr).
  const std::array<double, 4> q_xr = {0.1, -0.3, 0.2, std::sqrt(1 - 0.01 - 0.09 - 0.04)};
  const std::array<double, 3> p_xr = {0.3, -0.7, 0.4};
  const std::array<double, 4> q_xr_wxyz = {q_xr[3], q_xr[0], q_xr[1], q_xr[2]};
  const auto lhs = rotate(webxrQuatToV(q_xr), webxrToV(p_xr));
  const auto rhs = webxrToV(rotate(q_xr_wxyz, p_xr));
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(lhs[i], rhs[i], 1e-12) << i;
}

TEST(VrProtocol, ThumbstickYIsForwardAndButtonsAndGripCarryOver) {
  VrSample s;
  ASSERT_EQ(parseVrMessage(toWireJson(syntheticWirePose(72)), s), VrReject::kAccepted);  // t = 1 s: odd second
  EXPECT_DOUBLE_EQ(s.thumbstick[kRightHand][1], 0.5) << "Gamepad axes[3] = −0.5 (pushed forward) → y forward +0.5";
  EXPECT_EQ(s.buttons[kRightHand], kVrButtonLower);
  EXPECT_EQ(s.buttons[kLeftHand], 0u);
  EXPECT_DOUBLE_EQ(s.grip[kLeftHand], 1.0);
  EXPECT_TRUE(s.hand_valid[kLeftHand]);
  EXPECT_GT(s.hand_position[kLeftHand][1], 0.1) << "left hand is at +y (left) in V";
  EXPECT_LT(s.hand_position[kRightHand][1], -0.1);
}

TEST(VrProtocol, SyntheticPatternIsValidThroughout) {
  for (std::int64_t f = 0; f < 72 * 45; f += 7) {
    VrSample s;
    std::string d;
    ASSERT_EQ(parseVrMessage(toWireJson(syntheticWirePose(f)), s, &d), VrReject::kAccepted) << f << ": " << d;
    EXPECT_GE(s.head_position[0], -1e-12);
    EXPECT_LE(s.head_position[0], 6.0 + 1e-9) << "walks 20 s at 0.3 m/s, then back";
  }
  EXPECT_LT(toWireJson(syntheticWirePose(123456)).size(), 1000u) << "a pose message is far below the size limit";
}

TEST(VrProtocol, LcmMessageCarriesTheSampleAndChecksBack) {
  const VrSample s = syntheticSample(200);
  const pmg_lcm::vr_pose_t m = toVrPoseMessage(s, 1234567);
  EXPECT_EQ(m.utime, 1234567);
  EXPECT_EQ(m.frame, 200);
  EXPECT_EQ(m.source, "vr");
  EXPECT_DOUBLE_EQ(m.head_position[0], s.head_position[0]);
  EXPECT_DOUBLE_EQ(m.hand_quat[1][3], s.hand_quat[1][3]);
  std::string d;
  EXPECT_EQ(checkVrPoseMessage(m, &d), VrReject::kAccepted) << d;
  pmg_lcm::vr_pose_t bad = m;
  bad.head_quat[0] = 0.5;
  EXPECT_EQ(checkVrPoseMessage(bad, &d), VrReject::kNotUnitQuaternion);
  bad = m;
  bad.grip[1] = std::nan("");
  EXPECT_EQ(checkVrPoseMessage(bad, &d), VrReject::kNonFinite);
  bad = m;
  bad.buttons[0] = 1 << 7;
  EXPECT_EQ(checkVrPoseMessage(bad, &d), VrReject::kUnknownButtonBits);
  bad = m;
  bad.hand_position[0][2] = -500.0;
  EXPECT_EQ(checkVrPoseMessage(bad, &d), VrReject::kOutOfRange);
}

}  // namespace
}  // namespace pmg::teleop
