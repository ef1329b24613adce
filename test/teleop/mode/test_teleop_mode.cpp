// The teleoperation stage (teleop_mode.hpp) on the G1 model: engage/disengage, the headset as a
// joystick (dead bands, gains), the deadman grip, the stale-stream watchdog (locomotion zero at
// once, arms hold, then return to the PMG reference), arms that reproduce a pose stream generated
// from the robot's own forward kinematics, bounded arm reference speed, and no allocation.
#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/teleop/teleop_mode.hpp"

namespace pmg::teleop {
namespace {

constexpr double kDt = 0.01;
constexpr double kStanding = 0.78;

VrSample neutralSample() {
  VrSample s;
  s.head_position = {0.0, 0.0, 1.6};
  s.head_quat = {1, 0, 0, 0};
  s.hand_valid = {true, true};
  s.hand_position = {{{0.25, 0.2, 1.2}, {0.25, -0.2, 1.2}}};
  return s;
}

std::array<double, 4> yawQuat(double yaw) { return {std::cos(yaw / 2), 0, 0, std::sin(yaw / 2)}; }

// A loop around TeleopMode as the controller's tick uses it: the PMG reference stays at the
// robot's default pose; returns the reference the loop would send.
class TeleopHarness {
 public:
  explicit TeleopHarness(TeleopConfig c = enabledConfig()) : robot_(test::g1Robot()), mode_(robot_, c) {
    n_ = static_cast<int>(robot_.numJoints());
    pmg_q_.resize(static_cast<std::size_t>(n_));
    for (int i = 0; i < n_; ++i) pmg_q_[static_cast<std::size_t>(i)] = robot_.joints[static_cast<std::size_t>(i)].default_position;
    q_ = pmg_q_;
    qd_.assign(pmg_q_.size(), 0.0);
  }
  static TeleopConfig enabledConfig() {
    TeleopConfig c;
    c.enabled = true;
    return c;
  }
  // One tick at time now_ with sample s received now (or `age` seconds ago).
  const TeleopStatus& tick(const VrSample& s, double age = 0.0, bool send = true) {
    CommandSample in;
    if (send) {
      in.vr = s;
      in.vr_time = now_ - age;
      last_receive_ = in.vr_time;
    } else {
      in.vr = s;
      in.vr_time = last_receive_;
    }
    mode_.updateCommand(in, now_, kStanding);
    q_ = pmg_q_;
    std::fill(qd_.begin(), qd_.end(), 0.0);
    mode_.applyArms(q_.data(), qd_.data(), n_, kDt);
    now_ += kDt;
    return mode_.status();
  }
  void engage(VrSample s) {
    s.buttons[kRightHand] |= kVrButtonLower;
    tick(s);
    s.buttons[kRightHand] &= ~static_cast<std::uint32_t>(kVrButtonLower);
    tick(s);
  }
  double armRef(int hand, int k) const { return q_[static_cast<std::size_t>(mode_.ik().jointIndices(hand)[static_cast<std::size_t>(k)])]; }
  double pmgRef(int hand, int k) const { return pmg_q_[static_cast<std::size_t>(mode_.ik().jointIndices(hand)[static_cast<std::size_t>(k)])]; }
  TeleopMode& mode() { return mode_; }
  const std::vector<double>& q() const { return q_; }
  double now() const { return now_; }

 private:
  const RobotConfig& robot_;
  TeleopMode mode_;
  int n_ = 0;
  std::vector<double> pmg_q_, q_, qd_;
  double now_ = 1.0, last_receive_ = -1.0;
};

TEST(TeleopMode, NoOverrideUntilEngagedByTheAButton) {
  TeleopHarness h;
  VrSample s = neutralSample();
  s.head_position[0] += 0.4;  // leaning forward before engaging does nothing
  for (int i = 0; i < 5; ++i) EXPECT_FALSE(h.tick(s).command_override);
  h.engage(s);
  const TeleopStatus& st = h.tick(s);
  EXPECT_TRUE(st.engaged);
  EXPECT_TRUE(st.command_override);
  EXPECT_EQ(st.engagements, 1u);
  // The origin is where the headset was at engage time: no motion.
  EXPECT_EQ(st.command.vx, 0.0);
  EXPECT_EQ(st.command.vy, 0.0);
  EXPECT_EQ(st.command.wz, 0.0);
  EXPECT_FALSE(st.command.height.has_value());
  // A second press disengages.
  h.engage(s);
  EXPECT_FALSE(h.tick(s).engaged);
}

TEST(TeleopMode, HeadsetDisplacementYawHeightAndPitchBecomeCommands) {
  TeleopHarness h;
  const TeleopConfig& c = h.mode().config();
  VrSample s = neutralSample();
  s.head_quat = yawQuat(0.7);  // the operator faces 0.7 rad left of V's x axis at engage time
  h.engage(s);
  // Inside the dead bands: nothing.
  VrSample in = s;
  in.head_position[0] += 0.03 * std::cos(0.7);
  in.head_position[1] += 0.03 * std::sin(0.7);
  in.head_position[2] -= 0.02;
  EXPECT_EQ(h.tick(in).command.vx, 0.0);
  // A step of 0.3 m in the operator's forward direction (frame O) → v_x only.
  in = s;
  in.head_position[0] += 0.3 * std::cos(0.7);
  in.head_position[1] += 0.3 * std::sin(0.7);
  TeleopStatus st = h.tick(in);
  EXPECT_NEAR(st.command.vx, c.velocity_gain[0] * (0.3 - c.position_deadband_m), 1e-9);
  EXPECT_NEAR(st.command.vy, 0.0, 1e-9);
  // 0.2 m to the operator's left → v_y > 0 only.
  in = s;
  in.head_position[0] += -0.2 * std::sin(0.7);
  in.head_position[1] += 0.2 * std::cos(0.7);
  st = h.tick(in);
  EXPECT_NEAR(st.command.vy, c.velocity_gain[1] * (0.2 - c.position_deadband_m), 1e-9);
  EXPECT_NEAR(st.command.vx, 0.0, 1e-9);
  // Turning the head 0.5 rad counter-clockwise → ω > 0.
  in = s;
  in.head_quat = yawQuat(0.7 + 0.5);
  st = h.tick(in);
  EXPECT_NEAR(st.command.wz, c.velocity_gain[2] * (0.5 - c.yaw_deadband_rad), 1e-9);
  // Crouching 0.15 m → pelvis height command below standing.
  in = s;
  in.head_position[2] -= 0.15;
  st = h.tick(in);
  ASSERT_TRUE(st.command.height.has_value());
  EXPECT_NEAR(*st.command.height, kStanding - c.height_gain * (0.15 - c.height_deadband_m), 1e-9);
  // Looking down 0.6 rad → forward bend.
  in = s;
  const Eigen::Quaterniond q = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitY());
  in.head_quat = {q.w(), q.x(), q.y(), q.z()};
  st = h.tick(in);
  EXPECT_NEAR(st.command.pitch, c.pitch_gain * (0.6 - c.pitch_deadband_rad), 1e-6);
  EXPECT_NEAR(st.command.wz, 0.0, 1e-6);
}

TEST(TeleopMode, StaleStreamStopsAtOnceThenLetsGo) {
  TeleopHarness h;
  const TeleopConfig& c = h.mode().config();
  VrSample s = neutralSample();
  h.engage(s);
  VrSample fwd = s;
  fwd.head_position[0] += 0.4;
  EXPECT_GT(h.tick(fwd).command.vx, 0.3);
  // The stream stops: the same sample ages.
  int ticks_to_zero = -1, ticks_to_release = -1;
  for (int k = 0; k < 300; ++k) {
    const TeleopStatus& st = h.tick(fwd, 0.0, false);
    if (ticks_to_zero < 0 && st.command_override && st.command.vx == 0.0) ticks_to_zero = k;
    if (ticks_to_release < 0 && !st.engaged) ticks_to_release = k;
  }
  // Zero within the stale timeout (+1 tick), let go after the hold time.
  EXPECT_GE(ticks_to_zero, 0);
  EXPECT_LE(ticks_to_zero * kDt, c.stale_timeout_s + kDt + 1e-9);
  EXPECT_NEAR(ticks_to_release * kDt, c.stale_timeout_s + c.arm_hold_s, 0.03);
  EXPECT_EQ(h.mode().status().stale_events, 1u);
  // A fresh stream does not re-engage by itself.
  EXPECT_FALSE(h.tick(fwd).engaged);
}

// Builds the VR sample whose right-hand target is X_TH (the inverse of the mapping, head at
// the origin facing V's x axis): checks itself against TeleopMode::armTarget.
VrSample sampleForTarget(const TeleopMode& mode, int hand, const ArmPose& target) {
  VrSample s = neutralSample();
  const TeleopConfig& c = mode.config();
  // Probe the mapping's affine parts with two samples: p_T = a + scale * p_rel, R_T = R_hand R_fwd.
  const ArmPose at0 = mode.armTarget(s, hand);  // hand at s.hand_position, identity orientation
  const auto hh = static_cast<std::size_t>(hand);
  const Eigen::Vector3d p0(s.hand_position[hh][0], s.hand_position[hh][1], s.hand_position[hh][2]);
  const Eigen::Vector3d p = p0 + (target.position - at0.position) / c.arm_scale;
  const Eigen::Quaterniond r_fwd = at0.orientation;  // identity controller ↦ R_fwd
  const Eigen::Quaterniond r_hand = (target.orientation * r_fwd.conjugate()).normalized();
  s.hand_position[hh] = {p.x(), p.y(), p.z()};
  s.hand_quat[hh] = {r_hand.w(), r_hand.x(), r_hand.y(), r_hand.z()};
  return s;
}

TEST(TeleopMode, ArmsReproduceAPoseStreamFromTheRobotsOwnForwardKinematics) {
  TeleopConfig config = TeleopHarness::enabledConfig();
  config.orientation = HandOrientation::kAbsolute;  // the stream carries absolute hand poses
  TeleopHarness h(config);
  const ArmIk& ik = h.mode().ik();
  const int hand = kRightHand;
  // A smooth arm trajectory around a reachable, collision-free pose in front of the robot.
  ArmJoints base = ik.nominal(hand);
  base[0] = -0.6;  // shoulder pitch: arm forward
  base[3] = 0.6;   // elbow bent (away from the inner workspace shell, which ArmIk clamps with a margin)
  const auto trajectory = [&](double t) {
    ArmJoints q = base;
    q[0] += 0.25 * std::sin(1.3 * t);
    q[1] += -0.15 * std::sin(0.9 * t);
    q[3] += 0.2 * std::sin(1.1 * t);
    q[5] += 0.2 * std::sin(0.7 * t);
    return q;
  };
  VrSample s = sampleForTarget(h.mode(), hand, ik.forwardKinematics(hand, trajectory(0.0)));
  h.engage(s);
  s.grip[hand] = 1.0;
  double worst_after_settle = 0.0, sum = 0.0, worst_pos = 0.0, worst_ori = 0.0;
  int count = 0;
  for (int k = 0; k < 600; ++k) {
    const double t = k * kDt;
    const ArmJoints q_true = trajectory(t);
    VrSample in = sampleForTarget(h.mode(), hand, ik.forwardKinematics(hand, q_true));
    in.grip[hand] = 1.0;
    // The mapping is exact: the target it computes is the FK pose.
    const ArmPose tgt = h.mode().armTarget(in, hand);
    const ArmPose fk = ik.forwardKinematics(hand, q_true);
    ASSERT_NEAR((tgt.position - fk.position).norm(), 0.0, 1e-9);
    const TeleopStatus& st = h.tick(in);
    ASSERT_EQ(st.arm[hand], ArmMode::kFollowing);
    if (t > 1.0) {
      ArmJoints q_out{};
      for (int j = 0; j < 7; ++j) q_out[static_cast<std::size_t>(j)] = h.armRef(hand, j);
      const ArmPose got = ik.forwardKinematics(hand, q_out);
      worst_pos = std::max(worst_pos, (got.position - fk.position).norm());
      worst_ori = std::max(worst_ori, got.orientation.angularDistance(fk.orientation));
      for (int j = 0; j < 7; ++j) {
        const double e = std::fabs(h.armRef(hand, j) - q_true[static_cast<std::size_t>(j)]);
        worst_after_settle = std::max(worst_after_settle, e);
        sum += e;
        ++count;
      }
    }
  }
  // The hand follows the stream's poses (one tick behind at most), and as the 7-DoF arm is
  // redundant (elbow swivel), the null-space pull keeps the solution near the generating joints.
  std::printf("[ IK ] FK pose stream through teleop: worst hand error %.2f mm / %.2f mrad; joints: mean %.4f rad, worst %.3f rad\n",
              1e3 * worst_pos, 1e3 * worst_ori, sum / count, worst_after_settle);
  EXPECT_LT(worst_pos, 0.001) << "hand position error [m]";
  EXPECT_LT(worst_ori, 0.01) << "hand orientation error [rad]";
  EXPECT_LT(sum / count, 0.02) << "mean |q_ik - q_true| [rad]";
  EXPECT_LT(worst_after_settle, 0.08);
  // The other arm never moved off the PMG reference.
  EXPECT_EQ(h.mode().status().arm[kLeftHand], ArmMode::kPmg);
  for (int j = 0; j < 7; ++j) EXPECT_EQ(h.armRef(kLeftHand, j), h.pmgRef(kLeftHand, j));
}

TEST(TeleopMode, DeadmanHoldsArmsAndAStaleStreamReturnsThemWithoutJumps) {
  TeleopConfig config = TeleopHarness::enabledConfig();
  config.orientation = HandOrientation::kAbsolute;
  TeleopHarness h(config);
  const TeleopConfig& c = h.mode().config();
  const ArmIk& ik = h.mode().ik();
  ArmJoints q_goal = ik.nominal(kLeftHand);
  q_goal[0] = -1.0;
  q_goal[3] = 0.5;
  VrSample s = sampleForTarget(h.mode(), kLeftHand, ik.forwardKinematics(kLeftHand, q_goal));
  h.engage(s);
  // Grip below the threshold: the arm stays on PMG.
  s.grip[kLeftHand] = c.grip_threshold - 0.05;
  EXPECT_EQ(h.tick(s).arm[kLeftHand], ArmMode::kPmg);
  s.grip[kLeftHand] = 1.0;
  std::vector<double> prev = h.q();
  double max_step = 0.0;
  const auto track_steps = [&] {
    for (int j = 0; j < 7; ++j) {
      const auto i = static_cast<std::size_t>(ik.jointIndices(kLeftHand)[static_cast<std::size_t>(j)]);
      max_step = std::max(max_step, std::fabs(h.q()[i] - prev[i]));
    }
    prev = h.q();
  };
  for (int k = 0; k < 150; ++k) {
    h.tick(s);
    track_steps();
  }
  EXPECT_EQ(h.mode().status().arm[kLeftHand], ArmMode::kFollowing);
  EXPECT_NEAR(h.armRef(kLeftHand, 0), q_goal[0], 0.05);
  // Release the grip: the arm holds exactly.
  s.grip[kLeftHand] = 0.2;
  h.tick(s);
  track_steps();
  const double held = h.armRef(kLeftHand, 0);
  for (int k = 0; k < 50; ++k) {
    EXPECT_EQ(h.tick(s).arm[kLeftHand], ArmMode::kHolding);
    track_steps();
    EXPECT_EQ(h.armRef(kLeftHand, 0), held);
  }
  // Grip again, then the stream drops: hold for the stale timeout + hold time, then return.
  s.grip[kLeftHand] = 1.0;
  h.tick(s);
  track_steps();
  int returning_at = -1, pmg_at = -1;
  for (int k = 0; k < 800; ++k) {
    const TeleopStatus& st = h.tick(s, 0.0, false);
    track_steps();
    if (returning_at < 0 && st.arm[kLeftHand] == ArmMode::kReturning) returning_at = k;
    if (pmg_at < 0 && st.arm[kLeftHand] == ArmMode::kPmg) pmg_at = k;
  }
  EXPECT_NEAR(returning_at * kDt, c.stale_timeout_s + c.arm_hold_s, 0.03);
  ASSERT_GT(pmg_at, returning_at);
  // Settled on the PMG reference, and never faster than the IK's step bound or the return speed.
  for (int j = 0; j < 7; ++j) EXPECT_NEAR(h.armRef(kLeftHand, j), h.pmgRef(kLeftHand, j), 1e-9);
  EXPECT_LE(max_step, std::max(ik.options().max_joint_step, c.arm_return_speed * kDt) + 1e-9);
}

TEST(TeleopMode, TickAllocatesNothing) {
  TeleopHarness h;
  VrSample s = neutralSample();
  h.engage(s);
  s.grip = {1.0, 1.0};
  for (int k = 0; k < 5; ++k) h.tick(s);
  test::AllocationGuard guard;
  for (int k = 0; k < 200; ++k) {
    VrSample in = s;
    in.hand_position[0][0] += 0.1 * std::sin(0.05 * k);
    in.head_position[0] += 0.2;
    h.tick(in, 0.0, k < 100);
  }
  EXPECT_EQ(guard.count(), 0u);
}

TEST(TeleopMode, ConfigValidationNamesTheField) {
  TeleopConfig c;
  EXPECT_EQ(c.validate(), "");
  c.grip_threshold = 1.5;
  EXPECT_NE(c.validate().find("teleop.grip_threshold"), std::string::npos);
  c = TeleopConfig{};
  c.velocity_gain[2] = std::nan("");
  EXPECT_NE(c.validate().find("teleop.velocity_gain"), std::string::npos);
}

}  // namespace
}  // namespace pmg::teleop
