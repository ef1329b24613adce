// MIT-mode codec: every field round-trips at its range ends, malformed replies are rejected.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "pmg/hal/bus/mit_protocol.hpp"

using namespace pmg::hal::bus;

namespace {

MotorSpec makeMotor() {
  MotorSpec m;
  m.name = "left_knee_joint";
  m.joint_index = 3;
  m.motor_id = 4;
  m.command_can_id = 4;
  m.reply_can_id = 0;
  // Deliberately asymmetric ranges so a min/max mix-up shows.
  m.ranges = MotorRanges{-12.5, 11.0, -30.0, 45.0, 0.0, 500.0, 0.5, 10.0, -150.0, 120.0};
  return m;
}

double step(double lo, double hi, int bits) { return (hi - lo) / ((1 << bits) - 1); }

MotorCommand roundTrip(const MotorSpec& m, const MotorCommand& c) {
  MitProtocol p;
  CanFrame f;
  EXPECT_TRUE(p.encodeCommand(m, c, f));
  EXPECT_EQ(f.len, 8);
  EXPECT_EQ(f.id, m.command_can_id);
  MotorCommand out;
  EXPECT_TRUE(MitProtocol::decodeCommand(m, f, out));
  return out;
}

}  // namespace

TEST(MitProtocol, CommandFieldsRoundTripAtRangeEnds) {
  const MotorSpec m = makeMotor();
  const MotorRanges& r = m.ranges;
  // Each field at its low end, then at its high end, others mid-range.
  const double qs[] = {r.q_min, r.q_max};
  const double vs[] = {r.qd_min, r.qd_max};
  const double kps[] = {r.kp_min, r.kp_max};
  const double kds[] = {r.kd_min, r.kd_max};
  const double ts[] = {r.tau_min, r.tau_max};
  for (int i = 0; i < 2; ++i) {
    MotorCommand c{qs[i], vs[i], kps[i], kds[i], ts[i]};
    MotorCommand o = roundTrip(m, c);
    EXPECT_NEAR(o.q, c.q, 1e-9);
    EXPECT_NEAR(o.qd, c.qd, 1e-9);
    EXPECT_NEAR(o.kp, c.kp, 1e-9);
    EXPECT_NEAR(o.kd, c.kd, 1e-9);
    EXPECT_NEAR(o.tau_ff, c.tau_ff, 1e-9);
  }
  // Mixed: low q with high everything else and vice versa (catches field overlap in packed bytes).
  MotorCommand a{r.q_min, r.qd_max, r.kp_min, r.kd_max, r.tau_min};
  MotorCommand oa = roundTrip(m, a);
  EXPECT_NEAR(oa.q, a.q, 1e-9);
  EXPECT_NEAR(oa.qd, a.qd, 1e-9);
  EXPECT_NEAR(oa.kp, a.kp, 1e-9);
  EXPECT_NEAR(oa.kd, a.kd, 1e-9);
  EXPECT_NEAR(oa.tau_ff, a.tau_ff, 1e-9);
  MotorCommand b{r.q_max, r.qd_min, r.kp_max, r.kd_min, r.tau_max};
  MotorCommand ob = roundTrip(m, b);
  EXPECT_NEAR(ob.q, b.q, 1e-9);
  EXPECT_NEAR(ob.qd, b.qd, 1e-9);
  EXPECT_NEAR(ob.kp, b.kp, 1e-9);
  EXPECT_NEAR(ob.kd, b.kd, 1e-9);
  EXPECT_NEAR(ob.tau_ff, b.tau_ff, 1e-9);
}

TEST(MitProtocol, CommandBitLayoutMatchesWireFormat) {
  const MotorSpec m = makeMotor();
  const MotorRanges& r = m.ranges;
  MitProtocol p;
  CanFrame f;
  // q at max (0xFFFF), qd at min (0x000), kp at max (0xFFF), kd at min (0x000), tau at max (0xFFF).
  ASSERT_TRUE(p.encodeCommand(m, MotorCommand{r.q_max, r.qd_min, r.kp_max, r.kd_min, r.tau_max}, f));
  const std::uint8_t expected[8] = {0xFF, 0xFF, 0x00, 0x0F, 0xFF, 0x00, 0x0F, 0xFF};
  for (int i = 0; i < 8; ++i) EXPECT_EQ(f.data[i], expected[i]) << "byte " << i;
}

TEST(MitProtocol, CommandRoundTripWithinHalfStep) {
  const MotorSpec m = makeMotor();
  const MotorRanges& r = m.ranges;
  std::mt19937 rng(7);
  auto u = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  for (int i = 0; i < 2000; ++i) {
    MotorCommand c{u(r.q_min, r.q_max), u(r.qd_min, r.qd_max), u(r.kp_min, r.kp_max), u(r.kd_min, r.kd_max),
                   u(r.tau_min, r.tau_max)};
    MotorCommand o = roundTrip(m, c);
    EXPECT_LE(std::fabs(o.q - c.q), 0.5 * step(r.q_min, r.q_max, 16) + 1e-12);
    EXPECT_LE(std::fabs(o.qd - c.qd), 0.5 * step(r.qd_min, r.qd_max, 12) + 1e-12);
    EXPECT_LE(std::fabs(o.kp - c.kp), 0.5 * step(r.kp_min, r.kp_max, 12) + 1e-12);
    EXPECT_LE(std::fabs(o.kd - c.kd), 0.5 * step(r.kd_min, r.kd_max, 12) + 1e-12);
    EXPECT_LE(std::fabs(o.tau_ff - c.tau_ff), 0.5 * step(r.tau_min, r.tau_max, 12) + 1e-12);
  }
}

TEST(MitProtocol, CommandOutsideRangeIsClampedAndNonFiniteRefused) {
  const MotorSpec m = makeMotor();
  MotorCommand o = roundTrip(m, MotorCommand{100.0, -100.0, 1e4, -3.0, 1e3});
  EXPECT_NEAR(o.q, m.ranges.q_max, 1e-9);
  EXPECT_NEAR(o.qd, m.ranges.qd_min, 1e-9);
  EXPECT_NEAR(o.kp, m.ranges.kp_max, 1e-9);
  EXPECT_NEAR(o.kd, m.ranges.kd_min, 1e-9);
  EXPECT_NEAR(o.tau_ff, m.ranges.tau_max, 1e-9);

  MitProtocol p;
  CanFrame f;
  f.id = 0x123;
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_FALSE(p.encodeCommand(m, MotorCommand{nan, 0, 0, 0, 0}, f));
  EXPECT_FALSE(p.encodeCommand(m, MotorCommand{0, 0, 0, 0, inf}, f));
  EXPECT_FALSE(p.encodeCommand(m, MotorCommand{0, 0, -inf, 0, 0}, f));
  EXPECT_EQ(f.id, 0x123u) << "frame must be untouched on refusal";
}

TEST(MitProtocol, ControlFrames) {
  const MotorSpec m = makeMotor();
  MitProtocol p;
  const std::pair<ControlRequest, std::uint8_t> cases[] = {
      {ControlRequest::kEnable, 0xFC}, {ControlRequest::kDisable, 0xFD}, {ControlRequest::kZero, 0xFE}};
  for (auto [req, last] : cases) {
    CanFrame f;
    p.encodeControl(m, req, f);
    EXPECT_EQ(f.id, m.command_can_id);
    ASSERT_EQ(f.len, 8);
    for (int i = 0; i < 7; ++i) EXPECT_EQ(f.data[i], 0xFF);
    EXPECT_EQ(f.data[7], last);
    ControlRequest back{};
    ASSERT_TRUE(MitProtocol::decodeControl(f, back));
    EXPECT_EQ(back, req);
    MotorCommand c;
    EXPECT_FALSE(MitProtocol::decodeCommand(m, f, c)) << "a control frame is not a PD command";
  }
  CanFrame cmd;
  ASSERT_TRUE(p.encodeCommand(m, MotorCommand{}, cmd));
  ControlRequest back{};
  EXPECT_FALSE(MitProtocol::decodeControl(cmd, back));
}

TEST(MitProtocol, ReplyFieldsRoundTripAtRangeEnds) {
  const MotorSpec m = makeMotor();
  const MotorRanges& r = m.ranges;
  MitProtocol p;
  const MotorFeedback cases[] = {{4, r.q_min, r.qd_min, r.tau_min}, {4, r.q_max, r.qd_max, r.tau_max},
                                 {4, r.q_min, r.qd_max, r.tau_min}, {4, r.q_max, r.qd_min, r.tau_max}};
  for (const MotorFeedback& in : cases) {
    CanFrame f;
    MitProtocol::encodeReply(m, in, f);
    EXPECT_EQ(f.len, 6);
    EXPECT_EQ(f.id, m.reply_can_id);
    EXPECT_EQ(p.replyMotorId(f), 4);
    MotorFeedback out;
    ASSERT_EQ(p.decodeReply(m, f, out), ReplyStatus::kOk);
    EXPECT_EQ(out.motor_id, 4);
    EXPECT_NEAR(out.q, in.q, 1e-9);
    EXPECT_NEAR(out.qd, in.qd, 1e-9);
    EXPECT_NEAR(out.tau, in.tau, 1e-9);
  }
}

TEST(MitProtocol, RejectsMalformedReplies) {
  const MotorSpec m = makeMotor();
  MitProtocol p;
  CanFrame good;
  MitProtocol::encodeReply(m, MotorFeedback{4, 0.3, -1.0, 5.0}, good);
  MotorFeedback out;
  out.q = 42.0;
  ASSERT_EQ(p.decodeReply(m, good, out), ReplyStatus::kOk);

  auto expect = [&](CanFrame f, ReplyStatus s, const char* what) {
    MotorFeedback o;
    o.q = 42.0;
    EXPECT_EQ(p.decodeReply(m, f, o), s) << what;
    EXPECT_EQ(o.q, 42.0) << what << ": output must be untouched";
  };
  for (int len : {0, 5, 7, 8}) {
    CanFrame f = good;
    f.len = static_cast<std::uint8_t>(len);
    expect(f, ReplyStatus::kWrongLength, "length");
  }
  {
    CanFrame f = good;
    f.data[0] = 5;
    expect(f, ReplyStatus::kWrongId, "motor id of a neighbour");
  }
  {
    CanFrame f = good;
    f.id = 0x7FF;
    expect(f, ReplyStatus::kWrongCanId, "arbitration id");
  }
  {
    CanFrame f = good;
    f.error = true;
    expect(f, ReplyStatus::kNotData, "error frame");
  }
  {
    CanFrame f = good;
    f.fd = true;
    expect(f, ReplyStatus::kNotData, "FD frame on a classic bus");
  }
  {
    CanFrame f = good;
    f.extended = true;
    expect(f, ReplyStatus::kNotData, "29-bit id");
  }
  // Range: a reply outside the joint's plausibility window (corrupted position bytes).
  MotorSpec narrow = m;
  narrow.reply_limits.q_min = -0.2;
  narrow.reply_limits.q_max = 3.0;
  narrow.reply_limits.qd_abs_max = 25.0;
  narrow.reply_limits.tau_abs_max = 140.0;
  {
    CanFrame f = good;
    f.data[1] = 0xFF;  // q near +11 rad
    MotorFeedback o;
    EXPECT_EQ(p.decodeReply(narrow, f, o), ReplyStatus::kOutOfRange);
    EXPECT_EQ(p.decodeReply(narrow, good, o), ReplyStatus::kOk);
  }
  {
    CanFrame f;
    MitProtocol::encodeReply(narrow, MotorFeedback{4, 0.3, 40.0, 0.0}, f);
    MotorFeedback o;
    EXPECT_EQ(p.decodeReply(narrow, f, o), ReplyStatus::kOutOfRange) << "velocity";
    MitProtocol::encodeReply(narrow, MotorFeedback{4, 0.3, 0.0, -149.0}, f);
    EXPECT_EQ(p.decodeReply(narrow, f, o), ReplyStatus::kOutOfRange) << "torque";
  }
  EXPECT_EQ(p.replyMotorId(CanFrame{}), -1);
}

TEST(MitProtocol, JointMotorMappingIsInvertible) {
  MotorSpec m = makeMotor();
  m.direction = -1.0;
  m.offset = 0.25;
  MotorCommand j{0.5, -2.0, 30.0, 1.0, 4.0};
  MotorCommand mc = toMotorSide(m, j);
  EXPECT_DOUBLE_EQ(mc.q, -0.25);
  EXPECT_DOUBLE_EQ(mc.qd, 2.0);
  EXPECT_DOUBLE_EQ(mc.kp, 30.0);
  EXPECT_DOUBLE_EQ(mc.tau_ff, -4.0);
  MotorFeedback back = toJointSide(m, MotorFeedback{4, mc.q, mc.qd, mc.tau_ff});
  EXPECT_DOUBLE_EQ(back.q, j.q);
  EXPECT_DOUBLE_EQ(back.qd, j.qd);
  EXPECT_DOUBLE_EQ(back.tau, j.tau_ff);
}

TEST(MitProtocol, FactoryAndRangeValidation) {
  EXPECT_STREQ(makeMotorProtocol("mit")->name(), "mit");
  try {
    makeMotorProtocol("canopen");
    FAIL() << "expected throw";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("canopen"), std::string::npos);
  }
  MotorRanges r;
  EXPECT_EQ(r.validate(), "");
  r.kd_min = -1.0;
  EXPECT_NE(r.validate().find("kd_min"), std::string::npos);
  r = MotorRanges{};
  r.q_max = r.q_min;
  EXPECT_NE(r.validate().find("q_min"), std::string::npos);
}
