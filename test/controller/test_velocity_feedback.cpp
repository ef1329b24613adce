// Velocity feedback (velocity_feedback.hpp): leg odometry against an independent finite-difference
// computation on the G1's leg chains, and the integral correction on a plant that achieves only a
// share of its command (the measured shortfall of the trained actor, docs/policy.md).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

#include <vector>

#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "g1_fixture.hpp"
#include "pmg/common/config_error.hpp"
#include "pmg/controller/controller_config.hpp"
#include "pmg/controller/velocity_feedback.hpp"

namespace pmg {
namespace {

std::vector<std::string> robotJointNames() {
  std::vector<std::string> names;
  for (const JointConfig& j : test::g1Robot().joints) names.push_back(j.name);
  return names;
}

struct Legs {
  std::shared_ptr<const gco::LegModel> model = gco::LegModel::fromRobotConfig(test::g1Robot());
  gco::LegJointIndex idx = model->jointIndices(robotJointNames());
};

Eigen::Matrix3d rotZ(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

// A state with the given leg joints, IMU orientation R_WB and gyro (B).
LowState makeState(const Legs& legs, const gco::LegVector (&q)[2], const gco::LegVector (&qd)[2],
                   const Eigen::Matrix3d& R_WB, const Eigen::Vector3d& w_B) {
  LowState s;
  s.num_motors = static_cast<int>(test::g1Robot().numJoints());
  for (std::size_t f = 0; f < 2; ++f)
    for (int j = 0; j < gco::kLegDofs; ++j) {
      const auto m = static_cast<std::size_t>(legs.idx[f][static_cast<std::size_t>(j)]);
      s.motors[m].q = q[f][j];
      s.motors[m].qd = qd[f][j];
    }
  const Eigen::Quaterniond qWB(R_WB);
  s.imu.quat_wxyz = {qWB.w(), qWB.x(), qWB.y(), qWB.z()};
  s.imu.gyro = {w_B.x(), w_B.y(), w_B.z()};
  s.imu.valid = true;
  return s;
}

TEST(LegOdometry, MatchesTheFiniteDifferenceOfTheStanceSoleInTheWorld) {
  Legs legs;
  gco::LegKinematics kin(legs.model);
  // Left leg nearly straight (the lower sole: stance), right knee bent (its sole 5+ cm higher: swing).
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] << -0.9, -0.05, 0.0, 1.6, -0.5, 0.02;
  qd[0] << 0.4, -0.2, 0.1, -0.5, 0.3, 0.15;
  qd[1] << 2.0, 1.0, -1.0, 3.0, 2.0, -1.0;  // a fast swing leg must not enter the estimate
  const Eigen::Matrix3d R_WB = rotZ(0.7) * Eigen::AngleAxisd(0.12, Eigen::Vector3d::UnitY()).toRotationMatrix() *
                               Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitX()).toRotationMatrix();
  const Eigen::Vector3d w_B(0.05, -0.1, 0.3);
  LegOdometry odo(legs.model, legs.idx, 0.02);
  const BaseVelocityEstimate est = odo.estimate(makeState(legs, q, qd, R_WB, w_B));
  ASSERT_TRUE(est.valid);
  EXPECT_EQ(est.stance_feet, 1);

  // Independent: the pelvis velocity (world) that keeps the left sole's world position fixed while
  // the joints move by qd dt and the pelvis turns by w_B dt, by central differences; then into H.
  const double h = 1e-6;
  Eigen::Isometry3d X_plus, X_minus;
  const Eigen::Matrix3d dR_plus = Eigen::AngleAxisd(w_B.norm() * h, w_B.normalized()).toRotationMatrix();
  const Eigen::Matrix3d dR_minus = dR_plus.transpose();
  ASSERT_TRUE(kin.forward(Foot::kLeft, q[0] + qd[0] * h, &X_plus));
  ASSERT_TRUE(kin.forward(Foot::kLeft, q[0] - qd[0] * h, &X_minus));
  const Eigen::Vector3d v_W =
      -((R_WB * dR_plus) * X_plus.translation() - (R_WB * dR_minus) * X_minus.translation()) / (2 * h);
  const double yaw = std::atan2(R_WB(1, 0), R_WB(0, 0));
  const Eigen::Vector3d v_H = rotZ(-yaw) * v_W;
  std::printf("leg odometry %.5f %.5f, finite difference %.5f %.5f m/s; yaw rate %.5f vs %.5f\n", est.v_x, est.v_y,
              v_H.x(), v_H.y(), est.yaw_rate, (R_WB * w_B).z());
  EXPECT_NEAR(est.v_x, v_H.x(), 1e-6);
  EXPECT_NEAR(est.v_y, v_H.y(), 1e-6);
  EXPECT_NEAR(est.yaw_rate, (R_WB * w_B).z(), 1e-12);
  EXPECT_GT(std::hypot(est.v_x, est.v_y), 0.05) << "a non-trivial velocity was tested";

  // Both soles level (same joints on both legs, mirrored): both count, the estimate is their mean.
  gco::LegVector qs[2] = {q[0], q[0]}, qds[2] = {qd[0], qd[0]};
  qs[1][1] = -q[0][1];
  qs[1][2] = -q[0][2];
  qs[1][5] = -q[0][5];
  const BaseVelocityEstimate both = odo.estimate(makeState(legs, qs, qds, Eigen::Matrix3d::Identity(), w_B));
  ASSERT_TRUE(both.valid);
  EXPECT_EQ(both.stance_feet, 2);

  // Non-finite joint state or an invalid IMU: no estimate.
  gco::LegVector qn[2] = {q[0], q[1]};
  qn[0][3] = std::nan("");
  EXPECT_FALSE(odo.estimate(makeState(legs, qn, qd, R_WB, w_B)).valid);
  LowState no_imu = makeState(legs, q, qd, R_WB, w_B);
  no_imu.imu.valid = false;
  EXPECT_FALSE(odo.estimate(no_imu).valid);
}

VelocityFeedbackConfig enabledConfig() {
  VelocityFeedbackConfig c;
  c.enabled = true;
  c.ki = {1.5, 1.5, 1.5};
  c.max_ratio = 0.6;
  c.odometry_time_s = 0.1;
  return c;
}

// First-order plant that achieves `gain` of its command (time constant tau), as the actor does.
struct Plant {
  std::array<double, 3> gain, v{};
  double tau = 0.3;
  BaseVelocityEstimate step(const VelocityCommand& u_fb, double dt) {
    for (std::size_t i = 0; i < 3; ++i) v[i] += dt / tau * (gain[i] * u_fb[i] - v[i]);
    BaseVelocityEstimate e;
    e.valid = true;
    e.stance_feet = 1;
    e.v_x = v[0];
    e.v_y = v[1];
    e.yaw_rate = v[2];
    return e;
  }
};

TEST(VelocityFeedback, BringsAnUnderachievingPlantToTheCommandWithinTheBound) {
  Legs legs;
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, {1.0, 0.4, 0.8});
  Plant plant{{0.7, 0.8, 0.75}};
  const VelocityCommand u{-0.3, 0.2, 0.5};
  BaseVelocityEstimate est;
  double max_step = 0.0;
  VelocityCommand prev = u;
  for (int k = 0; k < 1000; ++k) {
    const VelocityCommand& out = fb.correct(u, est, 0.01);
    for (std::size_t i = 0; i < 3; ++i) {
      EXPECT_LE(std::fabs(out[i] - u[i]), 0.6 * std::fabs(u[i]) + 1e-12) << "axis " << i << " tick " << k;
      max_step = std::max(max_step, std::fabs(out[i] - prev[i]));
    }
    prev = out;
    est = plant.step(out, 0.01);
  }
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_NEAR(plant.v[i], u[i], 0.01 * std::fabs(u[i])) << "axis " << i << ": achieved " << plant.v[i];
    EXPECT_NEAR(fb.command()[i], u[i] / plant.gain[i], 0.01) << "axis " << i;
  }
  EXPECT_LT(max_step, 1.5 * 0.5 * 0.01 + 1e-9) << "u_fb moves at most k_i |e| per second";
}

// A plant with a dead band, a stand-in for the default actor's slow start walking backward upright:
// sent |u| ≤ d it barely moves (it achieves 0.3 |u|), beyond it 0.3 d + 1.5 (|u| − d). Returns the
// achieved v_x after 20 s of a command u_x, and the largest |u_fb − u| / |u| over the run.
double deadBandWalk(const VelocityFeedbackConfig& config, double u_x, double* max_share) {
  Legs legs;
  VelocityFeedback fb(config, legs.model, legs.idx, {1.0, 0.4, 0.8});
  const double d = 0.15, tau = 0.3, dt = 0.01;
  double v = 0.0;
  *max_share = 0.0;
  BaseVelocityEstimate est;
  for (int k = 0; k < 2000; ++k) {
    const VelocityCommand& out = fb.correct(VelocityCommand{u_x, 0.0, 0.0}, est, dt);
    *max_share = std::max(*max_share, std::fabs(out.vx - u_x) / std::fabs(u_x));
    const double a = std::fabs(out.vx);
    const double target = std::copysign(a <= d ? 0.3 * a : 0.3 * d + (a - d) * 1.5, out.vx);
    v += dt / tau * (target - v);
    est.valid = true;
    est.stance_feet = 1;
    est.v_x = v;
  }
  return v;
}

TEST(VelocityFeedback, SmallCommandBoundCrossesADeadBandWhereTheRatioCannot) {
  VelocityFeedbackConfig c = enabledConfig();
  double share = 0.0;
  // The ratio bound alone: told -0.1, at most -0.16 is sent and the plant creeps at about -0.06.
  const double v_ratio = deadBandWalk(c, -0.1, &share);
  EXPECT_LE(share, 0.6 + 1e-12);
  EXPECT_GT(v_ratio, -0.07) << "the dead band holds the ratio-bounded command back";
  // With b = 0.1 the correction may reach |u| = 0.1: -0.2 is allowed and the plant reaches -0.1.
  c.small_command_bound = {0.1, 0.0, 0.0};
  const double v_small = deadBandWalk(c, -0.1, &share);
  EXPECT_NEAR(v_small, -0.1, 0.005);
  EXPECT_GT(share, 0.6) << "the correction went beyond r |u|";
  EXPECT_LE(share, 1.0 + 1e-12) << "but never beyond |u| itself";
  // A command large enough that r |u| >= b is bounded exactly as before: -0.3 under the same plant.
  double share_ratio = 0.0, share_small = 0.0;
  VelocityFeedbackConfig r = enabledConfig();
  const double v_big_ratio = deadBandWalk(r, -0.3, &share_ratio);
  const double v_big_small = deadBandWalk(c, -0.3, &share_small);
  EXPECT_DOUBLE_EQ(v_big_ratio, v_big_small);
  EXPECT_DOUBLE_EQ(share_ratio, share_small);
  // At zero the bound is zero: nothing is steered while standing.
  Legs legs;
  VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
  BaseVelocityEstimate moving;
  moving.valid = true;
  moving.stance_feet = 1;
  moving.v_x = 0.2;
  for (int k = 0; k < 300; ++k) EXPECT_EQ(fb.correct(VelocityCommand{0.0, 0.0, 0.0}, moving, 0.01).vx, 0.0);
}

// The controller's path (Controller::tick) with velocity_feedback.within_posture_envelopes: the
// shaper's command, the feedback on a plant that achieves 80 % of what it is sent, then scaleDown by
// the shaper's envelope scale of u_fb. Returns the largest envelope scale of u_fb over the ticks.
double walkCrouchedAndBent(bool within, CommandShaper* shaper, VelocityFeedback* fb, int ticks, double* max_step) {
  Plant plant{{0.8, 0.8, 0.8}};
  BaseVelocityEstimate est;
  CommandSample s;
  s.command = Command{0.6, 0.0, 0.0, 0.3, 0.0, 0.66};  // told 0.6 m/s, bent 0.3 rad, crouched to 0.66 m
  const double dt = 0.01;
  double worst = 0.0;
  VelocityCommand prev{};
  for (int k = 0; k < ticks; ++k) {
    const double t = k * dt;
    if (t >= 8.0) s.command = Command{0.6, 0.0, 0.0, 0.0, 0.0, std::nullopt};  // straightened: the envelopes lift
    s.velocity_time = s.posture_time = t;
    shaper->update(s, t, dt);
    const VelocityCommand* u_fb = &fb->correct(shaper->velocity(), est, dt);
    if (within) u_fb = &fb->scaleDown(shaper->envelopeScale(*u_fb));
    if (t < 8.0) worst = std::max(worst, shaper->envelopeScale(*u_fb));
    for (std::size_t i = 0; i < 3; ++i) {
      *max_step = std::max(*max_step, std::fabs((*u_fb)[i] - prev[i]));
      // No windup: what the command carries is the feed-forward plus the correction, exactly.
      EXPECT_NEAR((*u_fb)[i], fb->feedforward()[i] + fb->correction()[i], 1e-12) << "axis " << i << " at " << t;
    }
    prev = *u_fb;
    est = plant.step(*u_fb, dt);
  }
  return worst;
}

// The shaper's limits with the crouched (0.62 m) and bent (0.4 rad) velocity envelopes on.
CommandLimits envelopeLimits() {
  CommandLimits limits;
  limits.max_velocity = {1.0, 0.5, 1.0};
  limits.max_acceleration = {1.0, 1.0, 2.0};
  limits.standing_height = 0.78;
  limits.crouched_height = 0.62;
  limits.crouched_max_velocity = {0.3, 0.3, 0.6};
  limits.bent_pitch = 0.4;
  limits.bent_max_velocity = {0.8, 0.4, 0.8};
  return limits;
}

TEST(VelocityFeedback, WithinPostureEnvelopesKeepsTheCorrectedCommandOnTheEnvelopeWithoutWindup) {
  Legs legs;
  const CommandLimits limits = envelopeLimits();
  // Open (the default): the integrator lifts the slowed command back beyond the envelope.
  CommandShaper open_shaper(limits);
  VelocityFeedback open_fb(enabledConfig(), legs.model, legs.idx, limits.max_velocity);
  double open_step = 0.0;
  const double open_worst = walkCrouchedAndBent(false, &open_shaper, &open_fb, 800, &open_step);
  EXPECT_GT(open_worst, 1.15) << "the correction carries the crouched bent walk beyond its envelope";
  // Within: never beyond the envelope's edge, the shaped command itself on it, and continuous.
  CommandShaper shaper(limits);
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, limits.max_velocity);
  double max_step = 0.0, worst = 0.0;
  EXPECT_EQ(test::allocationsDuring([&] { worst = walkCrouchedAndBent(true, &shaper, &fb, 1500, &max_step); }), 0u);
  EXPECT_LE(worst, 1.0 + 1e-9);
  EXPECT_GT(fb.envelopeTicks(), 300u) << "it acted while crouched and bent";
  EXPECT_LT(max_step, 0.02) << "u_fb stays continuous (the shaper's slew and k_i |e| dt per tick)";
  // Upright again (from 8 s), the envelopes lift and the correction, not wound up, brings the plant
  // to the command as without the bound.
  EXPECT_EQ(shaper.envelopeScale(fb.command()), 0.0) << "upright at the standing height no envelope acts";
  EXPECT_NEAR(fb.command().vx, 0.6 / 0.8, 0.01);
  // The scale of the shaped command alone: it is what the shaper applied to its target.
  CommandShaper probe(limits);
  CommandSample s;
  s.command = Command{0.6, 0.0, 0.0, 0.3, 0.0, 0.66};
  for (int k = 0; k < 500; ++k) {
    s.velocity_time = s.posture_time = k * 0.01;
    probe.update(s, k * 0.01, 0.01);
  }
  const double scale = probe.envelopeScale({0.6, 0.0, 0.0});
  EXPECT_GT(scale, 1.0);
  EXPECT_NEAR(probe.velocity().vx, 0.6 / scale, 1e-9);
  EXPECT_NEAR(probe.envelopeScale(probe.velocity()), 1.0, 1e-9);
  EXPECT_EQ(probe.envelopeScale({}), 0.0);
  // scaleDown by a scale of at most 1 changes nothing.
  const VelocityCommand before = fb.command();
  EXPECT_EQ(fb.scaleDown(1.0).vx, before.vx);
  EXPECT_EQ(fb.scaleDown(0.5).vx, before.vx);
}

// velocity_feedback.headroom_in_envelopes passes min_limit = |u_i| + h_i to the envelope scale: an
// axis's limit is never below it, so a command at the crouched envelope's edge may be corrected up
// to h beyond it, and one further inside is bound exactly as before.
TEST(VelocityFeedback, EnvelopeMinLimitOpensAnAxisOnlyAsFarAsItAsks) {
  CommandLimits limits = envelopeLimits();
  limits.crouched_per_axis = true;
  CommandShaper shaper(limits);
  CommandSample s;
  s.command = Command{0.0, 0.3, 0.0, 0.0, 0.0, 0.62};  // fully crouched, lateral at the edge (0.3)
  for (int k = 0; k < 500; ++k) {
    s.velocity_time = s.posture_time = k * 0.01;
    shaper.update(s, k * 0.01, 0.01);
  }
  ASSERT_NEAR(shaper.crouchFraction(), 1.0, 1e-12);
  ASSERT_NEAR(shaper.velocity().vy, 0.3, 1e-9);
  const VelocityCommand corrected{0.0, 0.4, 0.0};
  EXPECT_NEAR(shaper.envelopeScale(corrected), 0.4 / 0.3, 1e-12) << "without: bound at the edge";
  EXPECT_NEAR(shaper.envelopeScale(corrected, {0.0, 0.3 + 0.1, 0.0}), 1.0, 1e-12) << "h = 0.1: up to 0.4";
  EXPECT_NEAR(shaper.envelopeScale(corrected, {0.0, 0.35, 0.0}), 0.4 / 0.35, 1e-12);
  // Below the limit min_limit changes nothing, on this axis or the others.
  EXPECT_EQ(shaper.envelopeScale({0.2, 0.2, 0.3}, {0.1, 0.25, 0.5}), shaper.envelopeScale({0.2, 0.2, 0.3}));
  // The other axes keep their limits: v_x 0.6 against the crouched 0.3.
  EXPECT_NEAR(shaper.envelopeScale({0.6, 0.4, 0.0}, {0.0, 0.4, 0.0}), 2.0, 1e-12);
  // Beside yaw, the same.
  EXPECT_NEAR(shaper.envelopeScaleBesideYaw(corrected, {0.0, 0.4, 0.0}), 1.0, 1e-9);
  EXPECT_NEAR(shaper.envelopeScaleBesideYaw(corrected), 0.4 / 0.3, 1e-9);
}

// velocity_feedback.yaw_beyond_envelopes: crouched to 0.66 m, a turn with a slow forward walk on a
// plant that turns at half of what it is sent (the default actor crouched: 0.36 rad/s for 0.63).
// Within the envelopes, all axes together, the turn's correction stops at the envelope's edge; with ω
// beyond them it brings the plant to the command, while v_x with the shaped ω stays inside them, no
// windup, continuous, no allocation. A crouched bent walk straight ahead (no turn) is the same either way.
// (The plant's ω gain is 0.7 here so that the command it needs stays inside envelope_max.)
struct CrouchedRun {
  double worst_beside_yaw = 0.0, worst_all = 0.0, max_step = 0.0;
  VelocityCommand u_fb{}, shaped{};
  std::array<double, 3> achieved{};
  std::vector<double> vx;  // u_fb.vx per tick
};

CrouchedRun walkCrouched(const CommandLimits& limits, const Command& command, const std::array<double, 3>& gain,
                         bool keep_yaw, int ticks) {
  Legs legs;
  CommandShaper shaper(limits);
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, limits.max_velocity);
  Plant plant{gain};
  BaseVelocityEstimate est;
  CommandSample s;
  s.command = command;
  CrouchedRun r;
  r.vx.reserve(static_cast<std::size_t>(ticks));
  VelocityCommand prev{};
  const double dt = 0.01;
  const std::size_t allocations = test::allocationsDuring([&] {
    for (int k = 0; k < ticks; ++k) {
      s.velocity_time = s.posture_time = k * dt;
      shaper.update(s, k * dt, dt);
      const VelocityCommand* u_fb = &fb.correct(shaper.velocity(), est, dt);
      u_fb = &fb.scaleDown(keep_yaw ? shaper.envelopeScaleBesideYaw(*u_fb) : shaper.envelopeScale(*u_fb), keep_yaw);
      const double limit = std::max(1.0, shaper.envelopeScale({0.0, 0.0, shaper.velocity().wz})) + 1e-9;
      r.worst_beside_yaw = std::max(r.worst_beside_yaw, shaper.envelopeScale({u_fb->vx, u_fb->vy, shaper.velocity().wz}) - limit);
      r.worst_all = std::max(r.worst_all, shaper.envelopeScale(*u_fb));
      for (std::size_t i = 0; i < 3; ++i) {
        r.max_step = std::max(r.max_step, std::fabs((*u_fb)[i] - prev[i]));
        EXPECT_NEAR((*u_fb)[i], fb.feedforward()[i] + fb.correction()[i], 1e-12) << "axis " << i << " tick " << k;
      }
      prev = *u_fb;
      if (r.vx.size() < r.vx.capacity()) r.vx.push_back(u_fb->vx);
      est = plant.step(*u_fb, dt);
    }
  });
  EXPECT_EQ(allocations, 0u);
  r.u_fb = fb.command();
  r.shaped = shaper.velocity();
  r.achieved = plant.v;
  return r;
}

TEST(VelocityFeedback, YawBeyondEnvelopesLetsTheTurnCorrectionPastTheCrouchedEnvelopeAndKeepsVxWithin) {
  const CommandLimits limits = envelopeLimits();
  const Command turn{0.2, 0.0, 0.6, 0.0, 0.0, 0.66};
  const std::array<double, 3> gain{0.9, 0.9, 0.7};
  const CrouchedRun within = walkCrouched(limits, turn, gain, false, 1500);
  const CrouchedRun beyond = walkCrouched(limits, turn, gain, true, 1500);
  // The shaper slowed the command along its direction; within, the corrected turn stays on that edge.
  EXPECT_LT(within.shaped.wz, 0.8 - 0.1);
  EXPECT_LE(within.worst_all, 1.0 + 1e-9);
  EXPECT_LT(within.achieved[2], 0.8 * within.shaped.wz) << "the plant turns at 70 % of the edge";
  // Beyond: the turn's correction goes past the edge and the plant reaches the shaped ω; v_x with the
  // shaped ω is never beyond the envelope.
  EXPECT_GT(beyond.u_fb.wz, within.u_fb.wz + 0.2);
  EXPECT_NEAR(beyond.achieved[2], beyond.shaped.wz, 0.02 * beyond.shaped.wz);
  EXPECT_LE(beyond.worst_beside_yaw, 0.0);
  EXPECT_GT(beyond.worst_all, 1.2) << "the bound on ω is off";
  EXPECT_LT(beyond.max_step, 0.03) << "u_fb stays continuous";
  EXPECT_LE(beyond.u_fb.wz, limits.max_velocity[2] + 1e-12) << "still inside max_velocity";
  // Straight ahead, crouched and bent (the walk that ran on): ω has nothing to correct, the same u_fb.
  const Command bent_walk{0.6, 0.0, 0.0, 0.3, 0.0, 0.66};
  const CrouchedRun a = walkCrouched(limits, bent_walk, {0.8, 0.8, 0.8}, false, 800);
  const CrouchedRun b = walkCrouched(limits, bent_walk, {0.8, 0.8, 0.8}, true, 800);
  ASSERT_EQ(a.vx.size(), b.vx.size());
  for (std::size_t k = 0; k < a.vx.size(); ++k) ASSERT_NEAR(a.vx[k], b.vx[k], 1e-9) << "tick " << k;
  EXPECT_LE(b.worst_all, 1.0 + 1e-9);
}

// Told the shaper's largest yaw rate, a plant that turns at 85 % of its command: without headroom the
// corrected command stops at max_velocity and the plant stays short; with it the correction goes on to
// what the plant needs, never beyond the envelope, and the other axes keep max_velocity.
TEST(VelocityFeedback, HeadroomLetsTheTurnCorrectionPastMaxVelocityUpToTheEnvelope) {
  Legs legs;
  const std::array<double, 3> max_velocity{1.0, 0.4, 0.8};
  VelocityFeedbackConfig c = enabledConfig();
  c.envelope_min = {-0.65, -0.5, -1.0};
  c.envelope_max = {1.0, 0.5, 1.0};
  struct Run {
    VelocityCommand u_fb;
    std::array<double, 3> achieved;
    double max_step;
  };
  const auto run = [&](const std::array<double, 3>& headroom, const VelocityCommand& u, double gain = 0.85) {
    VelocityFeedbackConfig h = c;
    h.max_velocity_headroom = headroom;
    VelocityFeedback fb(h, legs.model, legs.idx, max_velocity);
    Plant plant{{gain, gain, gain}};
    BaseVelocityEstimate est;
    Run r{u, {}, 0.0};
    VelocityCommand prev = u;
    for (int k = 0; k < 2000; ++k) {
      const VelocityCommand& out = fb.correct(u, est, 0.01);
      for (std::size_t i = 0; i < 3; ++i) r.max_step = std::max(r.max_step, std::fabs(out[i] - prev[i]));
      prev = out;
      est = plant.step(out, 0.01);
    }
    r.u_fb = fb.command();
    r.achieved = plant.v;
    return r;
  };
  const VelocityCommand turn{0.9, 0.0, 0.8};
  const Run none = run({0.0, 0.0, 0.0}, turn);
  const Run yaw = run({0.0, 0.0, 0.2}, turn);
  EXPECT_NEAR(none.u_fb.wz, 0.8, 1e-12) << "without headroom: at max_velocity";
  EXPECT_LT(none.achieved[2], 0.7);
  EXPECT_GT(yaw.u_fb.wz, 0.9);
  EXPECT_LE(yaw.u_fb.wz, 1.0 + 1e-12);
  EXPECT_NEAR(yaw.achieved[2], 0.8, 0.01) << "the plant turns as commanded";
  EXPECT_LT(yaw.max_step, 0.03) << "u_fb stays continuous";
  // v_x has no headroom: both stop at its max_velocity, 1.0 (the plant needs 0.9 / 0.85 = 1.06).
  EXPECT_NEAR(none.u_fb.vx, 1.0, 1e-12);
  EXPECT_NEAR(yaw.u_fb.vx, 1.0, 1e-12);
  // A headroom past the envelope: the envelope (the actor's training range) still bounds it.
  const Run wide = run({0.0, 0.0, 1.0}, {0.0, 0.0, 0.8});
  EXPECT_GT(wide.u_fb.wz, 0.9);
  EXPECT_LE(wide.u_fb.wz, 1.0 + 1e-12);
  // The limit opens only as the command nears it, |u_fb| <= max(0.8, |u| + 0.2): a plant that turns at half
  // its command gets 0.8 for 0.6 rad/s with or without headroom, 0.9 for 0.7 (continuous in u).
  EXPECT_NEAR(run({0.0, 0.0, 0.2}, {0.0, 0.0, 0.6}, 0.5).u_fb.wz, 0.8, 1e-9);
  EXPECT_NEAR(run({0.0, 0.0, 0.0}, {0.0, 0.0, 0.6}, 0.5).u_fb.wz, 0.8, 1e-9);
  EXPECT_NEAR(run({0.0, 0.0, 0.2}, {0.0, 0.0, 0.7}, 0.5).u_fb.wz, 0.9, 1e-9);
  EXPECT_NEAR(run({0.0, 0.0, 0.2}, {0.0, 0.0, 0.8}, 0.5).u_fb.wz, 1.0, 1e-9);
  // Right turns alike.
  const Run right = run({0.0, 0.0, 0.2}, {0.0, 0.0, -0.8});
  EXPECT_NEAR(right.achieved[2], -0.8, 0.01);
  EXPECT_GE(right.u_fb.wz, -1.0 - 1e-12);
  // Validation names the field and the range.
  VelocityFeedbackConfig bad = c;
  bad.max_velocity_headroom = {0.0, 0.0, 1.5};
  EXPECT_NE(bad.validate().find("max_velocity_headroom[2]"), std::string::npos) << bad.validate();
  bad.max_velocity_headroom = {std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0};
  EXPECT_NE(bad.validate().find("max_velocity_headroom[0]"), std::string::npos) << bad.validate();
  bad.max_velocity_headroom = {0.0, -0.1, 0.0};
  EXPECT_NE(bad.validate().find("max_velocity_headroom[1]"), std::string::npos) << bad.validate();
}

TEST(VelocityFeedback, IntegratesOnceTheCommandIsSteadyAndAStickJitterIsSteady) {
  Legs legs;
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, {1.0, 0.4, 0.8});
  Plant plant{{0.7, 0.7, 0.7}};
  BaseVelocityEstimate est;
  // A ramp of 0.01 per tick (the shaper's 1 m/s^2 slew): the robot lags by design; nothing integrates.
  for (int k = 1; k <= 50; ++k) est = plant.step(fb.correct({0.01 * k, 0.0, 0.0}, est, 0.01), 0.01);
  EXPECT_EQ(fb.correction()[0], 0.0);
  // Held: nothing for settle_time_s (0.5 s), then it integrates.
  for (int k = 0; k < 49; ++k) est = plant.step(fb.correct({0.5, 0.0, 0.0}, est, 0.01), 0.01);
  EXPECT_EQ(fb.correction()[0], 0.0);
  for (int k = 0; k < 20; ++k) est = plant.step(fb.correct({0.5, 0.0, 0.0}, est, 0.01), 0.01);
  EXPECT_GT(fb.correction()[0], 0.0);
  // A gamepad stick jittering +-0.01 m/s around 0.3: steady, so it settles and integrates.
  fb.reset();
  Plant p2{{0.7, 0.7, 0.7}};
  est = BaseVelocityEstimate{};
  for (int k = 0; k < 500; ++k) est = p2.step(fb.correct({0.3 + ((k % 7) - 3) * 0.0033, 0.0, 0.0}, est, 0.01), 0.01);
  EXPECT_GT(fb.correction()[0], 0.05);
}

TEST(VelocityFeedback, SaturatesAtTheRatioAndTheLimitsAndVanishesWithTheCommand) {
  Legs legs;
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, {1.0, 0.4, 0.8});
  Plant weak{{0.3, 0.3, 0.3}};
  BaseVelocityEstimate est;
  for (int k = 0; k < 1000; ++k) est = weak.step(fb.correct({0.5, -0.2, 0.4}, est, 0.01), 0.01);
  EXPECT_NEAR(fb.command().vx, 0.8, 1e-9) << "1.6 x 0.5: the ratio bound";
  EXPECT_NEAR(fb.command().vy, -0.32, 1e-9);
  EXPECT_NEAR(fb.command().wz, 0.64, 1e-9);
  // Near the limits: the anti-windup keeps the correction at what the limits let through.
  for (int k = 0; k < 1000; ++k) est = weak.step(fb.correct({0.9, 0.0, -0.7}, est, 0.01), 0.01);
  EXPECT_NEAR(fb.command().vx, 1.0, 1e-12);
  EXPECT_NEAR(fb.command().wz, -0.8, 1e-12);
  EXPECT_NEAR(fb.correction()[0], 0.1, 1e-12);
  EXPECT_EQ(fb.command().vy, 0.0) << "no command, no correction, whatever the drift";
  // Backward: the training envelope ends at -0.5 m/s (the shaper would allow -1.0): no correction
  // pushes beyond it, and a command already beyond it is passed on uncorrected.
  for (int k = 0; k < 1000; ++k) est = weak.step(fb.correct({-0.45, 0.0, 0.0}, est, 0.01), 0.01);
  EXPECT_NEAR(fb.command().vx, -0.5, 1e-12);
  for (int k = 0; k < 100; ++k) est = weak.step(fb.correct({-0.8, 0.0, 0.0}, est, 0.01), 0.01);
  EXPECT_EQ(fb.command().vx, -0.8);
  for (int k = 0; k < 1000; ++k) est = weak.step(fb.correct({0.9, 0.0, -0.7}, est, 0.01), 0.01);
  // The command ramps to zero (as the shaper slews it): the correction follows it to zero.
  for (int k = 0; k <= 100; ++k) {
    const double s = 1.0 - k / 100.0;
    const VelocityCommand& out = fb.correct({0.9 * s, 0.0, -0.7 * s}, est, 0.01);
    EXPECT_LE(std::fabs(out.vx - 0.9 * s), 0.6 * 0.9 * s + 1e-12);
    est = weak.step(out, 0.01);
  }
  EXPECT_EQ(fb.command().vx, 0.0);
  EXPECT_EQ(fb.command().wz, 0.0);
}

TEST(VelocityFeedback, HoldsWithoutAnEstimateResetsAndPassesThroughWhenDisabled) {
  Legs legs;
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, {1.0, 0.4, 0.8});
  Plant plant{{0.7, 0.7, 0.7}};
  BaseVelocityEstimate est;
  for (int k = 0; k < 300; ++k) est = plant.step(fb.correct({0.4, 0.0, 0.0}, est, 0.01), 0.01);
  const double held = fb.correction()[0];
  EXPECT_GT(held, 0.05);
  for (int k = 0; k < 100; ++k) fb.correct({0.4, 0.0, 0.0}, BaseVelocityEstimate{}, 0.01);
  EXPECT_EQ(fb.correction()[0], held) << "no foot in stance: the correction holds";
  fb.reset();
  EXPECT_EQ(fb.correction()[0], 0.0);
  EXPECT_EQ(fb.correct({0.4, 0.0, 0.0}, BaseVelocityEstimate{}, 0.01).vx, 0.4);

  VelocityFeedbackConfig off = enabledConfig();
  off.enabled = false;
  VelocityFeedback pass(off, legs.model, legs.idx, {1.0, 0.4, 0.8});
  LowState s;
  EXPECT_EQ(pass.update({0.3, -0.1, 0.2}, s, 0.01).vy, -0.1);
}

TEST(VelocityFeedback, HoldsWhileTheEstimatorRejectsAndDecaysWhenTheRobotTilts) {
  Legs legs;
  VelocityFeedback fb(enabledConfig(), legs.model, legs.idx, {1.0, 0.4, 0.8});
  Plant plant{{0.7, 0.7, 0.7}};
  BaseVelocityEstimate est;
  for (int k = 0; k < 300; ++k) est = plant.step(fb.correct({0.4, 0.0, 0.5}, est, 0.01), 0.01);
  const auto held = fb.correction();
  ASSERT_GT(held[0], 0.05);
  BaseVelocityEstimate wild = est;
  wild.v_x = -1.0;  // what a confused estimate reads while its measurements are rejected
  for (int k = 0; k < 50; ++k) fb.correct({0.4, 0.0, 0.5}, wild, 0.01, /*hold=*/true);
  EXPECT_EQ(fb.correction()[0], held[0]);
  EXPECT_EQ(fb.correction()[2], held[2]);
  EXPECT_EQ(fb.heldTicks(), 50u);
  // Tilted beyond max_tilt_rad: the correction decays to zero (time constant decay_time_s 0.5 s).
  for (int k = 0; k < 50; ++k) fb.correct({0.4, 0.0, 0.5}, wild, 0.01, false, /*decay=*/true);
  EXPECT_NEAR(fb.correction()[0], held[0] * std::pow(1.0 - 0.01 / 0.5, 50), 1e-12);
  for (int k = 0; k < 450; ++k) fb.correct({0.4, 0.0, 0.5}, wild, 0.01, false, true);
  EXPECT_LT(std::fabs(fb.correction()[0]), 1e-4);
  EXPECT_LT(std::fabs(fb.command().wz - 0.5), 1e-4) << "the user's command, nothing added";
  EXPECT_EQ(fb.decayedTicks(), 500u);
}

// Braking steps (VelocityFeedbackConfig::brake_ratio): the command stops at the shaper's 1 m/s^2
// while the robot runs on (its velocity falls at 0.3 m/s^2). Without the floor u_fb goes to zero
// with the command; with it the generator keeps a gait under the robot, never above the previous
// u_fb minus brake_decel dt, continuous, and at zero once the robot has stopped.
TEST(VelocityFeedback, BrakingFloorKeepsAGaitUnderARobotThatRunsOnAndStaysContinuous) {
  Legs legs;
  const auto run = [&](double brake_ratio, std::vector<double>* out, double* raised_ticks) {
    VelocityFeedbackConfig c = enabledConfig();
    c.ki = {0.0, 0.0, 0.0};  // the floor alone
    c.brake_ratio = brake_ratio;
    VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
    BaseVelocityEstimate est;
    est.valid = true;
    est.stance_feet = 1;
    for (int k = 0; k < 600; ++k) {  // 2 s at 1.0, then the ramp to zero over 1 s, then 3 s standing
      const double t = 0.01 * k;
      const double u = t < 2.0 ? 1.0 : std::max(0.0, 1.0 - (t - 2.0));
      est.v_x = t < 2.0 ? 1.0 : std::max(0.0, 1.0 - 0.3 * (t - 2.0));
      out->push_back(fb.correct({u, 0.0, 0.0}, est, 0.01).vx);
    }
    *raised_ticks = static_cast<double>(fb.brakingTicks());
  };
  std::vector<double> off, on;
  double raised_off = 0, raised_on = 0;
  run(0.0, &off, &raised_off);
  run(0.8, &on, &raised_on);
  EXPECT_EQ(off[300], 0.0) << "no floor: u_fb is the stopped command";
  EXPECT_EQ(raised_off, 0.0);
  EXPECT_GT(raised_on, 50.0);
  EXPECT_GT(on[300], 0.3) << "the command is zero, the robot still moves at 0.7 m/s: a gait is kept";
  double largest_rise = -1.0, largest_fall = 0.0;
  for (std::size_t k = 1; k < on.size(); ++k) {
    largest_rise = std::max(largest_rise, on[k] - on[k - 1]);
    largest_fall = std::max(largest_fall, on[k - 1] - on[k]);
    if (on[k] > off[k]) {
      EXPECT_LE(on[k], on[k - 1] - VelocityFeedbackConfig{}.brake_decel * 0.01 + 1e-12) << "tick " << k << ": raised, it still falls";
    }
    EXPECT_GE(on[k], off[k]);
  }
  EXPECT_LE(largest_rise, 1e-12) << "the floor never raises u_fb above where it was";
  EXPECT_LE(largest_fall, 0.01 + 1e-12) << "continuous: no step beyond the shaper's 0.01 per tick";
  EXPECT_EQ(on.back(), 0.0) << "stopped robot, zero command: standing";

  // The command turns against the motion, or the estimate is lost: the floor goes to zero at
  // brake_rate (1 m/s^2), not at once.
  VelocityFeedbackConfig c = enabledConfig();
  c.ki = {0.0, 0.0, 0.0};
  c.brake_ratio = 0.8;
  VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
  BaseVelocityEstimate est;
  est.valid = true;
  est.stance_feet = 1;
  est.v_y = -0.5;
  for (int k = 0; k < 100; ++k) fb.correct({0.0, -0.5, 0.0}, est, 0.01);
  EXPECT_EQ(fb.command().vy, -0.5) << "the floor (0.8 x 0.5) lies under the command";
  for (int k = 1; k <= 25; ++k) fb.correct({0.0, -0.5 + 0.02 * k, 0.0}, est, 0.01);  // stops at 2 m/s^2
  const double floor = fb.brakeFloor()[1];
  EXPECT_NEAR(fb.command().vy, floor, 1e-12);
  ASSERT_LT(floor, -0.05);
  fb.correct({0.0, 0.0, 0.0}, BaseVelocityEstimate{}, 0.01);
  EXPECT_NEAR(fb.brakeFloor()[1], floor + 0.01, 1e-12);
  EXPECT_NEAR(fb.command().vy, floor + 0.01, 1e-12);
  for (int k = 0; k < 100; ++k) fb.correct({0.0, 0.1, 0.0}, est, 0.01);
  EXPECT_EQ(fb.brakeFloor()[1], 0.0);
  EXPECT_EQ(fb.command().vy, 0.1);
  fb.reset();
  EXPECT_EQ(fb.brakeFloor()[1], 0.0);
}

// brake_crouch_scaled: the floor's share is brake_ratio x the weight the controller gives (how
// crouched the shaped posture is). Weight 0 (standing height) is no braking at all, weight 1 is the
// unscaled floor, in between the share scales; a weight that drops mid-stop lets the floor go at
// brake_rate, not at once.
TEST(VelocityFeedback, CrouchScaledBrakingFloorScalesWithTheWeightAndIsOffAtStandingHeight) {
  Legs legs;
  std::vector<double> commands;
  // 2 s at 1.0, the command ramps to zero over 1 s while the robot slows at 0.3 m/s^2; the weight
  // switches to weight_after at tick switch_at.
  const auto run = [&](bool scaled, double weight, std::vector<double>* out, double weight_after = -1.0, int switch_at = -1) {
    VelocityFeedbackConfig c = enabledConfig();
    c.ki = {0.0, 0.0, 0.0};  // the floor alone
    c.brake_ratio = 0.8;
    c.brake_crouch_scaled = scaled;
    VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
    BaseVelocityEstimate est;
    est.valid = true;
    est.stance_feet = 1;
    for (int k = 0; k < 600; ++k) {
      const double t = 0.01 * k;
      fb.setBrakeWeight(k >= switch_at && switch_at >= 0 ? weight_after : weight);
      est.v_x = t < 2.0 ? 1.0 : std::max(0.0, 1.0 - 0.3 * (t - 2.0));
      const double u = t < 2.0 ? 1.0 : std::max(0.0, 1.0 - (t - 2.0));
      if (commands.size() < 600) commands.push_back(u);
      out->push_back(fb.correct({u, 0.0, 0.0}, est, 0.01).vx);
    }
    return fb.brakingTicks();
  };
  std::vector<double> unscaled, w0, w05, w1, not_scaled, nan_w, dropped;
  run(false, 1.0, &unscaled);
  EXPECT_EQ(run(true, 0.0, &w0), 0u) << "at the standing height: no braking";
  run(true, 0.5, &w05);
  run(true, 1.0, &w1);
  run(false, 0.0, &not_scaled);  // the weight is ignored unless brake_crouch_scaled
  EXPECT_EQ(run(true, std::nan(""), &nan_w), 0u) << "a NaN weight is 0";
  run(true, 1.0, &dropped, 0.0, 300);
  ASSERT_EQ(w0.size(), 600u);
  for (std::size_t k = 0; k < w0.size(); ++k) {
    EXPECT_EQ(w1[k], unscaled[k]) << "tick " << k;
    EXPECT_EQ(not_scaled[k], unscaled[k]) << "tick " << k;
    EXPECT_EQ(w0[k], commands[k]) << "tick " << k << ": the command";
    EXPECT_LE(w05[k], w1[k] + 1e-12);
    EXPECT_GE(w05[k], w0[k] - 1e-12);
  }
  // Where the half-weight floor raises the command it is at most 0.5 x 0.8 x the robot's velocity.
  int raised = 0;
  for (std::size_t k = 0; k < w05.size(); ++k) {
    const double t = 0.01 * static_cast<double>(k), v = t < 2.0 ? 1.0 : std::max(0.0, 1.0 - 0.3 * (t - 2.0));
    if (w05[k] > commands[k]) {
      ++raised;
      EXPECT_LE(w05[k], 0.5 * 0.8 * v + 1e-12) << "tick " << k;
    }
  }
  EXPECT_GT(raised, 50);
  // At 3 s the robot still moves at 0.7 m/s: a gait is kept, slower than the full floor's.
  EXPECT_GT(w05[300], 0.2);
  EXPECT_GT(w1[300], w05[300] + 0.1);
  // The weight drops to 0 at tick 300: the floor goes at brake_rate (1 m/s^2 = 0.01 per tick).
  EXPECT_EQ(dropped[299], w1[299]);
  for (std::size_t k = 300; k < dropped.size(); ++k) {
    EXPECT_LE(std::fabs(dropped[k] - dropped[k - 1]), 0.01 + 1e-12) << "tick " << k;
  }
  EXPECT_GT(dropped[305], w0[305]) << "not at once";
  EXPECT_EQ(dropped.back(), 0.0);
}

// A response model of the kind scripts/fit_command_response.py fits: backward and sideways slower
// than commanded, a turn that slows a side-step and a forward walk (more so when they point
// opposite ways), a turn that drifts sideways.
CommandResponseModel coupledModel() {
  CommandResponseModel m;
  m.enabled = true;
  m.axes[0] = {0.95, 0.8, {0.0, 0.0, -0.25}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
  m.axes[1] = {0.9, 0.85, {-0.2, 0.0, -0.4}, {0.0, 0.0, 0.1}, {0.0, 0.0, 0.05}};
  m.axes[2] = {0.9, 0.9, {-0.2, 0.0, 0.0}, {0.0, -0.15, 0.0}, {0.0, 0.0, 0.0}};
  m.max_correction = {0.3, 0.25, 0.4};
  m.iterations = 12;
  return m;
}

TEST(CommandResponseModel, InverseAchievesTheCommandIsContinuousAndStandsStill) {
  const CommandResponseModel m = coupledModel();
  ASSERT_EQ(m.validate(), "");
  const std::array<double, 3> zero = m.invert({0.0, 0.0, 0.0});
  EXPECT_EQ(zero, (std::array<double, 3>{0.0, 0.0, 0.0})) << "a robot told to stand is not moved";
  // Over the issue-12 envelope (steps of 0.1 m/s, 0.2 rad/s): where no bound acts, the model
  // achieves exactly the command; where one acts, the feed-forward sits on it.
  int exact = 0, bounded = 0;
  for (double vx = -0.5; vx <= 1.0 + 1e-9; vx += 0.1)
    for (double vy = -0.4; vy <= 0.4 + 1e-9; vy += 0.1)
      for (double wz = -0.8; wz <= 0.8 + 1e-9; wz += 0.2) {
        const std::array<double, 3> u{vx, vy, wz};
        const std::array<double, 3> x = m.invert(u);
        const std::array<double, 3> v = m.achieved(x);
        bool at_bound = false;
        for (std::size_t i = 0; i < 3; ++i) {
          ASSERT_LE(std::fabs(x[i] - u[i]), m.max_correction[i] + 1e-12);
          at_bound = at_bound || std::fabs(std::fabs(x[i] - u[i]) - m.max_correction[i]) < 1e-9;
          // The other bound: a modelled gain below min_gain is taken as min_gain.
          const CommandResponseAxis& a = m.axes[i];
          double gain = x[i] >= 0.0 ? a.gain_positive : a.gain_negative;
          for (std::size_t j = 0; j < 3; ++j) gain += a.gain_per_magnitude[j] * std::fabs(x[j]) + a.gain_per_command[j] * x[j];
          at_bound = at_bound || gain < m.min_gain + 1e-9;
        }
        if (at_bound) {
          ++bounded;
          continue;
        }
        ++exact;
        for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(v[i], u[i], 1e-4) << vx << " " << vy << " " << wz << " axis " << i;
      }
  EXPECT_GT(exact, 500);
  EXPECT_GT(bounded, 0) << "the grid reaches the bound somewhere (fast diagonal turns)";
  // Continuous: a command swept finely through zero and through sign changes of every axis moves
  // the feed-forward by a bounded multiple of its own step (the model's gain is at least min_gain).
  const int n = 4000;
  const auto sweep = [n](int k) {
    const double s = -1.0 + 2.0 * k / n;
    return std::array<double, 3>{0.5 * s + 0.25 * (s > 0 ? s : 0.0), 0.4 * s, -0.8 * s};
  };
  std::array<double, 3> prev = m.invert(sweep(0));
  for (int k = 1; k <= n; ++k) {
    const std::array<double, 3> x = m.invert(sweep(k));
    for (std::size_t i = 0; i < 3; ++i) EXPECT_LT(std::fabs(x[i] - prev[i]), 10.0 * (2.0 / n)) << "k " << k << " axis " << i;
    prev = x;
  }
  // Identity model: the feed-forward is the command.
  CommandResponseModel id;
  id.enabled = true;
  EXPECT_EQ(id.invert({0.3, -0.2, 0.5}), (std::array<double, 3>{0.3, -0.2, 0.5}));
  // Validation names the field.
  CommandResponseModel bad = m;
  bad.axes[1].gain_per_magnitude[1] = 0.1;
  EXPECT_NE(bad.validate().find("vy.gain_per_magnitude[1]"), std::string::npos) << bad.validate();
  bad = m;
  bad.iterations = 0;
  EXPECT_NE(bad.validate().find("iterations"), std::string::npos);
}

// The crouch terms: the gains are taken at the crouch (a robot that undershoots backward walks upright
// and overshoots them crouched), the inverse stays exact and continuous as the crouch is slewed, the
// crouch is clamped, a zero command still stands, and the feedback passes its crouch to the inverse.
TEST(CommandResponseModel, CrouchTermsTakeTheGainsAtTheCrouchContinuously) {
  CommandResponseModel m = coupledModel();
  m.axes[0].gain_negative = 0.84;
  m.axes[0].gain_negative_per_crouch = 6.0;  // 1.2 at 0.06 m
  m.axes[1].gain_positive_per_crouch = -1.0;
  ASSERT_EQ(m.validate(), "");
  const std::array<double, 3> back{-0.5, 0.0, 0.0};
  EXPECT_NEAR(m.invert(back, 0.0)[0], -0.5 / 0.84, 1e-9) << "upright: the upright gain";
  EXPECT_NEAR(m.invert(back, 0.06)[0], -0.5 / 1.2, 1e-9) << "crouched 0.06 m: the crouched gain";
  EXPECT_NEAR(m.achieved(m.invert(back, 0.06), 0.06)[0], -0.5, 1e-9);
  EXPECT_NEAR(m.achieved({-0.5, 0.0, 0.0}, 0.06)[0], -0.6, 1e-9) << "the uncorrected command overshoots by 20 %";
  EXPECT_EQ(m.invert({0.0, 0.0, 0.0}, 0.1), (std::array<double, 3>{0.0, 0.0, 0.0}));
  // Clamped: NaN and a negative crouch are upright, beyond 0.5 m it is 0.5 m.
  EXPECT_EQ(m.invert(back, std::nan("")), m.invert(back, 0.0));
  EXPECT_EQ(m.invert(back, -0.2), m.invert(back, 0.0));
  EXPECT_EQ(m.achieved(back, 3.0), m.achieved(back, 0.5));
  // A combined command over the crouch's range: exact where no bound acts, and continuous in the crouch.
  const std::array<double, 3> u{-0.3, 0.2, 0.3};
  std::array<double, 3> prev = m.invert(u, 0.0);
  const int n = 1200;
  for (int k = 1; k <= n; ++k) {
    const double c = 0.12 * k / n;
    const std::array<double, 3> x = m.invert(u, c);
    for (std::size_t i = 0; i < 3; ++i) {
      ASSERT_LE(std::fabs(x[i] - u[i]), m.max_correction[i] + 1e-12);
      EXPECT_LT(std::fabs(x[i] - prev[i]), 0.01) << "crouch " << c << " axis " << i;
    }
    const std::array<double, 3> v = m.achieved(x, c);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(v[i], u[i], 1e-4) << "crouch " << c << " axis " << i;
    prev = x;
  }
  // Validation names the field and its range.
  CommandResponseModel bad = m;
  bad.axes[2].gain_positive_per_crouch = 11.0;
  EXPECT_NE(bad.validate().find("wz.gain_positive_per_crouch: expected -10..10"), std::string::npos) << bad.validate();
  bad.axes[2].gain_positive_per_crouch = std::nan("");
  EXPECT_NE(bad.validate().find("wz.gain_positive_per_crouch"), std::string::npos) << bad.validate();
  // The feedback's feed-forward uses the crouch it was given.
  Legs legs;
  VelocityFeedbackConfig c = enabledConfig();
  c.envelope_min = {-0.65, -0.5, -1.0};  // the upright feed-forward of -0.5 (-0.595) lies inside
  c.feedforward = m;
  VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
  BaseVelocityEstimate est;
  fb.correct({-0.5, 0.0, 0.0}, est, 0.01);
  EXPECT_NEAR(fb.feedforward()[0], m.invert(back, 0.0)[0], 1e-12);
  fb.setCrouch(0.06);
  EXPECT_DOUBLE_EQ(fb.crouch(), 0.06);
  fb.correct({-0.5, 0.0, 0.0}, est, 0.01);
  EXPECT_NEAR(fb.feedforward()[0], -0.5 / 1.2, 1e-9);
  fb.setCrouch(std::nan(""));
  EXPECT_EQ(fb.crouch(), 0.0);
}

// combined_max_correction_ratio: on a command that moves all three axes the feed-forward's bound
// shrinks (to nothing at ratio 0); a command with any axis at 0 keeps the full bound; the shrink grows
// continuously with the third axis, so the feed-forward never jumps; 1 is the model as before.
TEST(CommandResponseModel, CombinedRatioShrinksTheBoundOnThreeAxisCommandsOnlyAndContinuously) {
  CommandResponseModel full = coupledModel();
  CommandResponseModel cut = full;
  cut.combined_max_correction_ratio = 0.0;
  cut.combined_full = {0.2, 0.15, 0.25};
  ASSERT_EQ(cut.validate(), "");
  EXPECT_DOUBLE_EQ(CommandResponseModel{}.combined_max_correction_ratio, 1.0) << "off unless configured";
  // The mirror image's diag_turn: every axis at least its full value, kappa 1, the command itself.
  const std::array<double, 3> diag{0.5, -0.3, -0.5};
  EXPECT_DOUBLE_EQ(cut.combination(diag), 1.0);
  EXPECT_EQ(cut.invert(diag), diag) << "ratio 0: no feed-forward on a three-axis command";
  const std::array<double, 3> x_full = full.invert(diag);
  double moved = 0.0;
  for (std::size_t i = 0; i < 3; ++i) moved = std::max(moved, std::fabs(x_full[i] - diag[i]));
  EXPECT_GT(moved, 0.05) << "the full model moves this command (the test would pass vacuously otherwise)";
  // Half the bound at ratio 0.5: each axis within half of max_correction.
  CommandResponseModel half = cut;
  half.combined_max_correction_ratio = 0.5;
  const std::array<double, 3> x_half = half.invert(diag);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_LE(std::fabs(x_half[i] - diag[i]), 0.5 * half.max_correction[i] + 1e-12);
  // Two-axis commands (a forward turn, a side-step while turning) keep the model's full inverse.
  for (const std::array<double, 3>& u : {std::array<double, 3>{0.5, 0.0, 0.5}, std::array<double, 3>{0.0, 0.3, -0.6},
                                         std::array<double, 3>{1.0, 0.0, 0.0}}) {
    EXPECT_DOUBLE_EQ(cut.combination(u), 0.0);
    EXPECT_EQ(cut.invert(u), full.invert(u));
  }
  // Continuous: the side-step of a forward turn grows from 0 through combined_full; the feed-forward
  // moves by a bounded multiple of the command's step.
  const int n = 3000;
  std::array<double, 3> prev = cut.invert({0.5, 0.0, 0.5});
  for (int k = 1; k <= n; ++k) {
    const std::array<double, 3> u{0.5, 0.3 * k / n, 0.5};
    const std::array<double, 3> x = cut.invert(u);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_LT(std::fabs(x[i] - prev[i]), 10.0 * (0.3 / n)) << "k " << k << " axis " << i;
    prev = x;
  }
  EXPECT_EQ(prev, (std::array<double, 3>{0.5, 0.3, 0.5})) << "at the full side-step: the command";
  // Validation names the field.
  CommandResponseModel bad = cut;
  bad.combined_max_correction_ratio = 1.5;
  EXPECT_NE(bad.validate().find("combined_max_correction_ratio: expected 0..1"), std::string::npos) << bad.validate();
  bad = cut;
  bad.combined_full[2] = 0.0;
  EXPECT_NE(bad.validate().find("combined_full[2]"), std::string::npos) << bad.validate();
}

// The model shipped in the default config (a re-fit must keep these): over the issue-12 envelope,
// every inverse within its bound and where no bound acts exact, no modelled gain below min_gain
// (the fit's coefficients describe the actor, not the floor), 0 -> 0, and continuous along lines
// through the envelope's corners.
TEST(CommandResponseModel, ShippedModelIsWellConditionedOverTheEnvelope) {
  const ControllerConfig config = loadControllerConfig(test::sourcePath("config/controller/g1_sil_policy.yaml"));
  const CommandResponseModel& shipped = config.velocity_feedback.feedforward;
  ASSERT_TRUE(config.velocity_feedback.enabled);
  ASSERT_TRUE(shipped.enabled);
  // The fitted model's conditioning is judged with its full bound; the shipped shrink on three-axis
  // commands (combined_max_correction_ratio) is checked against it below.
  CommandResponseModel m = shipped;
  m.combined_max_correction_ratio = 1.0;
  EXPECT_EQ(m.invert({0.0, 0.0, 0.0}), (std::array<double, 3>{0.0, 0.0, 0.0}));
  int exact = 0, total = 0, shrunk = 0;
  double largest_move[3] = {0.0, 0.0, 0.0};
  for (double vx = -0.5; vx <= 1.0 + 1e-9; vx += 0.05)
    for (double vy = -0.4; vy <= 0.4 + 1e-9; vy += 0.05)
      for (double wz = -0.8; wz <= 0.8 + 1e-9; wz += 0.1) {
        const std::array<double, 3> u{vx, vy, wz};
        const std::array<double, 3> x = m.invert(u);
        bool bounded = false;
        for (std::size_t i = 0; i < 3; ++i) {
          ASSERT_LE(std::fabs(x[i] - u[i]), m.max_correction[i] + 1e-12);
          bounded = bounded || std::fabs(std::fabs(x[i] - u[i]) - m.max_correction[i]) < 1e-9;
          largest_move[i] = std::max(largest_move[i], std::fabs(x[i] - u[i]));
          const CommandResponseAxis& a = m.axes[i];
          double gain = x[i] >= 0.0 ? a.gain_positive : a.gain_negative;
          for (std::size_t j = 0; j < 3; ++j) gain += a.gain_per_magnitude[j] * std::fabs(x[j]) + a.gain_per_command[j] * x[j];
          EXPECT_GT(gain, m.min_gain) << "modelled gain of axis " << i << " at u " << vx << " " << vy << " " << wz;
        }
        ++total;
        const double k = shipped.combination(u);
        const std::array<double, 3> xs = shipped.invert(u);
        for (std::size_t i = 0; i < 3; ++i)
          ASSERT_LE(std::fabs(xs[i] - u[i]), shipped.max_correction[i] * (1.0 - (1.0 - shipped.combined_max_correction_ratio) * k) + 1e-12)
              << "the shipped bound, shrunk on a combined command: u " << vx << " " << vy << " " << wz;
        if (k < 1e-9) {  // an axis at 0 (the grid's zeros carry rounding)
          for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(xs[i], x[i], 1e-9) << "a command with an axis at 0 keeps the full inverse";
        } else if (k >= 1.0) {
          ++shrunk;
          if (shipped.combined_max_correction_ratio == 0.0) {
            EXPECT_EQ(xs, u) << "a full three-axis command is sent as told";
          }
        }
        if (bounded) continue;
        ++exact;
        const std::array<double, 3> v = m.achieved(x);
        for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(v[i], u[i], 1e-4) << vx << " " << vy << " " << wz << " axis " << i;
      }
  EXPECT_GT(exact, total / 2) << "the bound acts on most of the envelope: the model is far from the robot";
  std::printf("shipped feed-forward: %d of %d envelope commands inverted exactly; largest move %.3f %.3f %.3f; "
              "%d full three-axis commands (combined_max_correction_ratio %.2f)\n",
              exact, total, largest_move[0], largest_move[1], largest_move[2], shrunk, shipped.combined_max_correction_ratio);
  // Continuous: along the diagonals through the envelope's corners, no jump.
  const int n = 2000;
  for (const std::array<double, 3>& dir : {std::array<double, 3>{1.0, 0.4, 0.8}, std::array<double, 3>{1.0, -0.4, 0.8},
                                           std::array<double, 3>{-0.5, 0.4, 0.8}, std::array<double, 3>{-0.5, -0.4, -0.8}}) {
    std::array<double, 3> prev = shipped.invert({0.0, 0.0, 0.0});
    for (int k = 1; k <= n; ++k) {
      const double s = static_cast<double>(k) / n;
      const std::array<double, 3> x = shipped.invert({dir[0] * s, dir[1] * s, dir[2] * s});
      for (std::size_t i = 0; i < 3; ++i) EXPECT_LT(std::fabs(x[i] - prev[i]), 4.0 * std::fabs(dir[i]) / n + 1e-9) << k;
      prev = x;
    }
  }
}

// A plant whose steady response is the coupled model, with the integrator held throughout (as in
// the grid's diag_turn, where the estimator rejects or the pelvis tilts for most of the segment):
// the feedback alone leaves the side-step short, the feed-forward brings it to the command.
TEST(VelocityFeedback, FeedforwardReachesACoupledCommandWhileTheIntegratorIsHeld) {
  Legs legs;
  const CommandResponseModel model = coupledModel();
  const auto run = [&](bool feedforward, bool hold) {
    VelocityFeedbackConfig c = enabledConfig();
    c.envelope_min = {-0.65, -0.5, -1.0};
    c.envelope_max = {1.0, 0.5, 1.0};
    c.feedforward = model;
    c.feedforward.enabled = feedforward;
    VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
    std::array<double, 3> v{};
    BaseVelocityEstimate est;
    const VelocityCommand u{0.4, 0.25, 0.4};
    for (int k = 0; k < 800; ++k) {
      const VelocityCommand& out = fb.correct(u, est, 0.01, hold);
      const std::array<double, 3> target = model.achieved({out.vx, out.vy, out.wz});
      for (std::size_t i = 0; i < 3; ++i) v[i] += 0.01 / 0.3 * (target[i] - v[i]);
      est.valid = true;
      est.stance_feet = 1;
      est.v_x = v[0];
      est.v_y = v[1];
      est.yaw_rate = v[2];
    }
    return std::make_pair(v, fb.feedforward());
  };
  const auto [held_off, ff_off] = run(false, true);
  EXPECT_LT(held_off[1], 0.2) << "without the feed-forward the side-step is short: " << held_off[1];
  EXPECT_EQ(ff_off, (std::array<double, 3>{0.4, 0.25, 0.4}));
  const auto [held_on, ff_on] = run(true, true);
  const std::array<double, 3> u{0.4, 0.25, 0.4};
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(held_on[i], u[i], 0.005) << i;
  EXPECT_GT(ff_on[1], 0.3);
  EXPECT_LE(ff_on[1], 0.5) << "inside envelope_max";
  // Integrating as well: still the command, no overshoot from the two together.
  const auto [both, ff_both] = run(true, false);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(both[i], u[i], 0.005) << i;
}

// decay_feedforward: tilted beyond max_tilt_rad, the feed-forward's share decays with the
// correction, so the robot gets the user's command; upright again it returns at the same rate,
// without a jump. Without the key the model's command stays whole while tilted (the behaviour the
// slippery floor's falls came with, docs/controller.md "Slippery floors").
TEST(VelocityFeedback, DecayFeedforwardGivesATiltedRobotTheUsersCommandAndReturnsContinuously) {
  Legs legs;
  const CommandResponseModel model = coupledModel();
  const VelocityCommand u{0.4, 0.25, 0.4};
  const std::array<double, 3> inv = model.invert({u.vx, u.vy, u.wz});
  ASSERT_GT(std::fabs(inv[1] - u.vy), 0.05) << "the model moves the command";
  const auto make = [&](bool decay_ff) {
    VelocityFeedbackConfig c = enabledConfig();
    c.envelope_min = {-0.65, -0.5, -1.0};
    c.envelope_max = {1.0, 0.5, 1.0};
    c.feedforward = model;
    c.feedforward.enabled = true;
    c.decay_feedforward = decay_ff;
    return std::make_unique<VelocityFeedback>(c, legs.model, legs.idx, std::array<double, 3>{1.0, 0.4, 0.8});
  };
  BaseVelocityEstimate est;  // invalid: the integrator is not fed; only the feed-forward acts
  for (const bool decay_ff : {false, true}) {
    auto fb = make(decay_ff);
    for (int k = 0; k < 100; ++k) fb->correct(u, est, 0.01);
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(fb->feedforward()[i], inv[i], 1e-12) << "upright: the model's command";
    EXPECT_EQ(fb->feedforwardShare(), 1.0);
    for (int k = 0; k < 50; ++k) fb->correct(u, est, 0.01, false, /*decay=*/true);
    const double share = decay_ff ? std::pow(1.0 - 0.01 / 0.5, 50) : 1.0;
    EXPECT_NEAR(fb->feedforwardShare(), share, 1e-12);
    for (std::size_t i = 0; i < 3; ++i)
      EXPECT_NEAR(fb->feedforward()[i], u[i] + share * (inv[i] - u[i]), 1e-12) << "axis " << i << " decay_ff " << decay_ff;
    for (int k = 0; k < 450; ++k) fb->correct(u, est, 0.01, false, true);
    if (!decay_ff) {
      EXPECT_NEAR(fb->command().vy, inv[1], 1e-12) << "without the key the model's command stays whole while tilted";
      continue;
    }
    for (std::size_t i = 0; i < 3; ++i) EXPECT_LT(std::fabs(fb->command()[i] - u[i]), 1e-4) << "the user's command, axis " << i;
    // Upright again: back to the model's command at dt / decay_time_s per tick, never a jump.
    VelocityCommand prev = fb->command();
    const double step = 0.01 / 0.5;
    double prev_share = fb->feedforwardShare();
    for (int k = 1; k <= 60; ++k) {
      const VelocityCommand& now = fb->correct(u, est, 0.01);
      EXPECT_NEAR(fb->feedforwardShare(), std::min(1.0, prev_share + step), 1e-12) << "linear return, tick " << k;
      prev_share = fb->feedforwardShare();
      for (std::size_t i = 0; i < 3; ++i)
        EXPECT_LE(std::fabs(now[i] - prev[i]), step * std::fabs(inv[i] - u[i]) + 1e-12) << "tick " << k << " axis " << i;
      prev = now;
    }
    EXPECT_EQ(fb->feedforwardShare(), 1.0) << "50 ticks of 0.02 bring it back";
    for (std::size_t i = 0; i < 3; ++i) EXPECT_NEAR(fb->feedforward()[i], inv[i], 1e-12);
    // reset(): whole again.
    for (int k = 0; k < 20; ++k) fb->correct(u, est, 0.01, false, true);
    ASSERT_LT(fb->feedforwardShare(), 1.0);
    fb->reset();
    EXPECT_EQ(fb->feedforwardShare(), 1.0);
  }
  // feedforward_return_s: a slower return than the decay; a tilted moment every 0.5 s keeps the share low.
  {
    VelocityFeedbackConfig c = enabledConfig();
    c.feedforward = model;
    c.feedforward.enabled = true;
    c.envelope_min = {-0.65, -0.5, -1.0};
    c.envelope_max = {1.0, 0.5, 1.0};
    c.decay_feedforward = true;
    c.feedforward_return_s = 2.0;
    VelocityFeedback slow(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
    for (int k = 0; k < 1000; ++k) slow.correct(u, est, 0.01, false, true);
    ASSERT_LT(slow.feedforwardShare(), 1e-6);
    for (int k = 0; k < 50; ++k) slow.correct(u, est, 0.01);
    EXPECT_NEAR(slow.feedforwardShare(), 0.25, 1e-6) << "0.5 s of a 2 s return";
    // Tilted 0.45 s in every second (diag_turn's share): with the 2 s return the share stays below a
    // half, with decay_time_s's return (0.5 s) it is back at 1 before each tilt.
    c.feedforward_return_s = 0.0;
    VelocityFeedback fast(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
    double slow_max = 0.0, fast_min_before_tilt = 1.0;
    for (int k = 0; k < 3000; ++k) {
      const bool tilted = k % 100 < 45;
      if (k % 100 == 0 && k > 0) fast_min_before_tilt = std::min(fast_min_before_tilt, fast.feedforwardShare());
      slow.correct(u, est, 0.01, false, tilted);
      fast.correct(u, est, 0.01, false, tilted);
      if (k > 2000) slow_max = std::max(slow_max, slow.feedforwardShare());
    }
    EXPECT_LT(slow_max, 0.5);
    EXPECT_GT(slow_max, 0.3) << "not gone: the share rises between the tilts";
    EXPECT_EQ(fast_min_before_tilt, 1.0);
    c.feedforward_return_s = 31.0;
    EXPECT_NE(c.validate().find("feedforward_return_s"), std::string::npos);
  }
  // The key is read from the controller config.
  EXPECT_FALSE(VelocityFeedbackConfig{}.decay_feedforward) << "off unless configured";
}

TEST(BaseVelocityEstimator, GatesOutlyingLegOdometryAndFollowsTheAccelerometer) {
  Legs legs;
  VelocityFeedbackConfig c = enabledConfig();
  BaseVelocityEstimator est(legs.model, legs.idx, c);
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] << -0.9, -0.05, 0.0, 1.6, -0.5, 0.02;  // right foot lifted: the left is the stance foot
  qd[0].setZero();
  qd[1].setZero();
  LowState s = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  s.imu.acc = {0.0, 0.0, 9.81};  // standing still: the specific force is gravity's reaction
  for (int k = 0; k < 20; ++k) est.update(s, 0.01);
  EXPECT_NEAR(est.update(s, 0.01).v_x, 0.0, 1e-9);
  // A stance leg whose knee and hip suddenly read a fast motion (a touchdown transient): rejected.
  LegOdometry odo(legs.model, legs.idx, c.stance_band_m);
  qd[0] << 3.0, 0.0, 0.0, -4.0, 1.0, 0.0;
  LowState spike = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  spike.imu.acc = s.imu.acc;
  ASSERT_GT(std::fabs(odo.estimate(spike).v_x), 0.3) << "the spike is an outlier";
  const std::uint64_t rejected_before = est.rejected();
  const BaseVelocityEstimate during = est.update(spike, 0.01);
  EXPECT_NEAR(during.v_x, 0.0, 1e-9);
  EXPECT_TRUE(est.rejecting());
  EXPECT_EQ(est.rejected(), rejected_before + 1);
  // The accelerometer reads 1 m/s^2 forward for 0.2 s: the estimate follows it (0.2 m/s) while leg
  // odometry, which still reads the outlier, stays rejected.
  spike.imu.acc = {1.0, 0.0, 9.81};
  BaseVelocityEstimate e;
  for (int k = 0; k < 20; ++k) e = est.update(spike, 0.01);
  EXPECT_NEAR(e.v_x, 0.21, 0.011);
  // Rejections beyond max_rejected_s (0.3 s): the estimate restarts from the legs' measurement.
  for (int k = 0; k < 10; ++k) e = est.update(spike, 0.01);
  EXPECT_FALSE(est.rejecting());
  EXPECT_NEAR(e.v_x, odo.estimate(spike).v_x, 1e-9);
}

TEST(BaseVelocityEstimator, MedianRestartIsNotTakenByOneGlitchAndEqualsTheSampleWhenTheLegsAgree) {
  // After max_rejected_s (0.3 s) of rejections the estimate restarts. The rejected window holds a
  // real motion the IMU prediction missed (2 of 3 samples, +0.5 m/s forward) and glitches (1 of 3,
  // -1.8 m/s: a lifting foot counted in stance), and the restart tick itself brings a glitch.
  Legs legs;
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] << -0.9, -0.05, 0.0, 1.6, -0.5, 0.02;  // the left foot is the lower: stance
  qd[0].setZero();
  qd[1].setZero();
  LowState still = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  still.imu.acc = {0.0, 0.0, 9.81};
  // Leg odometry is linear in the stance leg's joint speeds (no rotation): scale one pattern.
  LegOdometry odo(legs.model, legs.idx, enabledConfig().stance_band_m);
  qd[0] << 3.0, 0.0, 0.0, -4.0, 1.0, 0.0;
  const double unit = odo.estimate(makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero())).v_x;
  ASSERT_GT(std::fabs(unit), 0.1);
  auto sample = [&](double v_x) {
    gco::LegVector qs[2] = {qd[0] * (v_x / unit), gco::LegVector::Zero()};
    LowState s = makeState(legs, q, qs, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
    s.imu.acc = still.imu.acc;
    return s;
  };
  const LowState good = sample(0.5), glitch = sample(-1.8);
  ASSERT_NEAR(odo.estimate(good).v_x, 0.5, 1e-9);
  const double good_v_y = odo.estimate(good).v_y;

  auto run = [&](bool median, bool agree, std::size_t* allocations) {
    VelocityFeedbackConfig c = enabledConfig();
    c.restart_median = median;
    c.max_rejected_s = 0.295;  // the 31st sample after 30 rejections (away from 30 x 0.01's rounding)
    BaseVelocityEstimator est(legs.model, legs.idx, c);
    for (int k = 0; k < 20; ++k) est.update(still, 0.01);
    BaseVelocityEstimate e;
    test::AllocationGuard alloc;
    for (int k = 0; k < 30; ++k) e = est.update(agree || k % 3 != 2 ? good : glitch, 0.01);
    EXPECT_TRUE(est.rejecting());
    EXPECT_NEAR(e.v_x, 0.0, 1e-9) << "the prediction, without the legs";
    EXPECT_EQ(est.restarts(), 0u);
    // The restart tick: a glitch, unless the legs agree.
    e = est.update(agree ? good : glitch, 0.01);
    *allocations = alloc.count();
    EXPECT_EQ(est.restarts(), 1u);
    EXPECT_FALSE(est.rejecting());
    return e;
  };
  std::size_t n = 0;
  const BaseVelocityEstimate sample_restart = run(false, false, &n);
  EXPECT_NEAR(sample_restart.v_x, -1.8, 1e-6) << "the restart from the next sample takes the glitch";
  const BaseVelocityEstimate median_restart = run(true, false, &n);
  EXPECT_EQ(n, 0u);
  EXPECT_NEAR(median_restart.v_x, 0.5, 1e-6) << "the median of the window is a good sample";
  EXPECT_NEAR(median_restart.v_y, good_v_y, 1e-6);
  // Where the legs agree, both restarts give the legs' measurement.
  EXPECT_NEAR(run(true, true, &n).v_x, 0.5, 1e-6);
  EXPECT_NEAR(run(false, true, &n).v_x, 0.5, 1e-6);
}

TEST(BaseVelocityEstimator, UngatedYawRateFollowsTheGyroWhileTheLegsAreRejected) {
  Legs legs;
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] << -0.9, -0.05, 0.0, 1.6, -0.5, 0.02;
  qd[0].setZero();
  qd[1].setZero();
  LowState still = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  still.imu.acc = {0.0, 0.0, 9.81};
  // A stance-leg spike the gate rejects, while the robot turns at 0.5 rad/s (gyro).
  qd[0] << 3.0, 0.0, 0.0, -4.0, 1.0, 0.0;
  LowState turning = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 0.5));
  turning.imu.acc = still.imu.acc;
  double yaw[2] = {0.0, 0.0};
  for (int gated = 0; gated < 2; ++gated) {
    VelocityFeedbackConfig c = enabledConfig();
    c.yaw_rate_gated = gated == 1;
    c.max_rejected_s = 5.0;  // no restart within the test
    BaseVelocityEstimator est(legs.model, legs.idx, c);
    for (int k = 0; k < 20; ++k) est.update(still, 0.01);
    BaseVelocityEstimate e;
    for (int k = 0; k < 50; ++k) e = est.update(turning, 0.01);
    ASSERT_TRUE(est.rejecting());
    yaw[gated] = e.yaw_rate;
  }
  EXPECT_NEAR(yaw[0], 0.5, 0.01) << "ungated: the gyro's 0.5 rad/s after 5 time constants";
  EXPECT_NEAR(yaw[1], 0.0, 1e-9) << "gated (the default): held at the last accepted value";
}

// stance_foot_nearest: both soles level (inside the stance band), the left foot in stance carrying the
// robot forward at v, the right a swing foot skimming the floor whose sample reads -1.4 v (H10a's
// shuffle: docs/controller.md "A swing foot inside the stance band"). The robot speeds up at 2.5 m/s^2
// to 0.5 m/s (the accelerometer says so) and walks on for 1 s. With the key the estimator takes the left
// foot's sample (nearer its prediction) and follows the robot; with the mean of the two feet (the
// default) the gate rejects the samples, the restarts take the mean, and the estimate is far off. With
// one foot in the band the key changes nothing. Allocation-free either way.
TEST(BaseVelocityEstimator, StanceFootNearestIgnoresASwingFootInsideTheStanceBand) {
  Legs legs;
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] = q[0];  // mirrored: both soles at the same height
  q[1][1] = -q[0][1];
  q[1][2] = -q[0][2];
  q[1][5] = -q[0][5];
  gco::LegVector pattern[2];
  pattern[0] << 3.0, 0.0, 0.0, -4.0, 1.0, 0.0;  // hip pitch, knee, ankle pitch: a sagittal motion
  pattern[1] = pattern[0];
  LegOdometry odo(legs.model, legs.idx, enabledConfig().stance_band_m);
  auto state = [&](double v_left, double v_right, double acc_x) {
    qd[0] = pattern[0] * v_left;
    qd[1] = pattern[1] * v_right;
    LowState s = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
    s.imu.acc = {acc_x, 0.0, 9.81};
    return s;
  };
  const BaseVelocityEstimate unit = odo.estimate(state(1.0, 0.0, 0.0));
  ASSERT_EQ(unit.stance_feet, 2) << "both soles are in the band";
  ASSERT_GT(std::fabs(unit.foot_v_x[0]), 0.1);
  ASSERT_NEAR(unit.foot_v_x[0], odo.estimate(state(0.0, 1.0, 0.0)).foot_v_x[1], 1e-9) << "mirrored legs";
  const double k = 1.0 / unit.foot_v_x[0];  // joint speed scale per m/s of the sample
  auto run = [&](bool nearest, std::size_t* allocations, double* final_error, std::uint64_t* rejected) {
    VelocityFeedbackConfig c = enabledConfig();
    c.stance_foot_nearest = nearest;
    BaseVelocityEstimator est(legs.model, legs.idx, c);
    for (int i = 0; i < 20; ++i) est.update(state(0.0, 0.0, 0.0), 0.01);
    test::AllocationGuard alloc;
    double v = 0.0;
    BaseVelocityEstimate e;
    for (int i = 0; i < 120; ++i) {
      const double acc = i < 20 ? 2.5 : 0.0;
      v += acc * 0.01;
      e = est.update(state(k * v, -1.4 * k * v, acc), 0.01);
    }
    *allocations = alloc.count();
    *final_error = e.v_x - v;
    *rejected = est.rejected();
    return est.lastLegOdometry();
  };
  std::size_t n_on = 0, n_off = 0;
  double err_on = 0.0, err_off = 0.0;
  std::uint64_t rej_on = 0, rej_off = 0;
  const BaseVelocityEstimate leg_on = run(true, &n_on, &err_on, &rej_on);
  run(false, &n_off, &err_off, &rej_off);
  std::printf("estimate - truth at 0.5 m/s: nearest foot %.4f (rejected %llu), mean of the feet %.4f (rejected %llu)\n",
              err_on, static_cast<unsigned long long>(rej_on), err_off, static_cast<unsigned long long>(rej_off));
  EXPECT_NEAR(err_on, 0.0, 1e-3) << "the nearest foot is the stance foot";
  EXPECT_EQ(rej_on, 0u);
  EXPECT_EQ(leg_on.stance_feet, 1);
  EXPECT_TRUE(leg_on.foot_in_stance[0]);
  EXPECT_FALSE(leg_on.foot_in_stance[1]);
  EXPECT_NEAR(leg_on.v_x, 0.5, 1e-6);
  EXPECT_GT(std::fabs(err_off), 0.3) << "the mean of a stance and a swing foot is far from the robot";
  EXPECT_GT(rej_off, 10u);
  EXPECT_EQ(n_on, 0u);
  EXPECT_EQ(n_off, 0u);

  // One sole in the band (the right foot lifted): the key changes nothing.
  q[1] << -0.9, -0.05, 0.0, 1.6, -0.5, 0.02;
  double e1 = 0.0, e0 = 0.0;
  std::uint64_t r1 = 0, r0 = 0;
  const BaseVelocityEstimate l1 = run(true, &n_on, &e1, &r1);
  const BaseVelocityEstimate l0 = run(false, &n_off, &e0, &r0);
  EXPECT_EQ(l1.stance_feet, 1);
  EXPECT_DOUBLE_EQ(e1, e0);
  EXPECT_EQ(r1, r0);
  EXPECT_DOUBLE_EQ(l1.v_x, l0.v_x);
}

TEST(UpsetGuard, OwnEstimateJudgesTheRobotStateWithoutAllocating) {
  Legs legs;
  UpsetGuardConfig g;
  g.enabled = true;
  g.max_error = {0.8, 0.4, 0.3};
  g.trigger_s = 0.3;
  UpsetGuard guard(g, legs.model, legs.idx, enabledConfig());
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] << -0.9, -0.05, 0.0, 1.6, -0.5, 0.02;
  qd[0].setZero();
  qd[1].setZero();
  // Standing still but spinning at 1 rad/s (gyro) while told to stand: the yaw axis is 1 rad/s off.
  LowState s = makeState(legs, q, qd, Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.0, 0.0, 1.0));
  s.imu.acc = {0.0, 0.0, 9.81};
  bool held = false;
  std::size_t n = 0;
  {
    test::AllocationGuard alloc;
    for (int k = 0; k < 60 && !held; ++k) held = guard.update(VelocityCommand{}, VelocityCommand{}, s, 0.01);
    n = alloc.count();
  }
  EXPECT_EQ(n, 0u);
  EXPECT_TRUE(held);
  EXPECT_TRUE(guard.lastEstimate().valid);
  EXPECT_NEAR(guard.lastEstimate().yaw_rate, 1.0, 0.1);
  // Judging on given estimates only (the first constructor), a LowState is not enough: never holds.
  UpsetGuard plain(g);
  for (int k = 0; k < 60; ++k) EXPECT_FALSE(plain.update(VelocityCommand{}, VelocityCommand{}, s, 0.01));
  guard.reset();
  EXPECT_FALSE(guard.latched());
  EXPECT_FALSE(guard.lastEstimate().valid);
}

TEST(VelocityFeedback, UpdateDoesNotAllocate) {
  Legs legs;
  VelocityFeedbackConfig c = enabledConfig();
  c.brake_ratio = 0.8;  // the braking floor's path too
  c.feedforward = coupledModel();  // and the feed-forward's inverse, with its crouch terms
  c.feedforward.axes[0].gain_negative_per_crouch = 4.0;
  c.decay_feedforward = true;  // and its share's decay while tilted
  c.feedforward.combined_max_correction_ratio = 0.5;  // and its bound shrunk on combined commands
  VelocityFeedback fb(c, legs.model, legs.idx, {1.0, 0.4, 0.8});
  fb.setCrouch(0.05);
  gco::LegVector q[2], qd[2];
  q[0] << -0.3, 0.05, 0.02, 0.6, -0.3, -0.03;
  q[1] << -0.35, -0.05, 0.0, 0.7, -0.35, 0.02;
  qd[0] << 0.4, -0.2, 0.1, -0.5, 0.3, 0.15;
  qd[1] << 0.2, 0.1, -0.1, 0.3, 0.2, -0.1;
  const LowState s = makeState(legs, q, qd, rotZ(0.3), Eigen::Vector3d(0.0, 0.0, 0.2));
  fb.update({0.3, 0.1, 0.2}, s, 0.01);
  std::size_t n = 0;
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 100; ++k) fb.update({0.3 - 0.003 * k, 0.1, 0.2}, s, 0.01);  // a stop: the floor acts
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
  EXPECT_TRUE(fb.lastEstimate().valid);
  EXPECT_TRUE(fb.estimator().lastLegOdometry().valid);
  // The floor acting: walking at 0.8 m/s, then the command stops while the robot runs on.
  BaseVelocityEstimate moving;
  moving.valid = true;
  moving.stance_feet = 1;
  moving.v_x = 0.8;
  const std::uint64_t braked_before = fb.brakingTicks();
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 100; ++k) fb.correct({0.8, 0.0, 0.0}, moving, 0.01);
    for (int k = 0; k < 20; ++k) fb.correct({0.0, 0.0, 0.0}, moving, 0.01);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
  EXPECT_EQ(fb.brakingTicks() - braked_before, 20u) << "the floor acted on every tick of the stop";
  {  // tilted: the feed-forward's share decays (decay_feedforward)
    test::AllocationGuard guard;
    for (int k = 0; k < 20; ++k) fb.correct({0.5, 0.1, 0.3}, moving, 0.01, false, /*decay=*/true);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
  EXPECT_LT(fb.feedforwardShare(), 1.0);
}

int jointIndex(const std::string& name) {
  const auto names = robotJointNames();
  return static_cast<int>(std::find(names.begin(), names.end(), name) - names.begin());
}

LowState uprightState(double imu_pitch, double waist_pitch) {
  LowState s;
  s.num_motors = static_cast<int>(test::g1Robot().numJoints());
  for (int i = 0; i < s.num_motors; ++i) s.motors[static_cast<std::size_t>(i)].q = 0.0;
  s.motors[static_cast<std::size_t>(jointIndex("waist_pitch_joint"))].q = waist_pitch;
  const Eigen::Quaterniond q(Eigen::AngleAxisd(imu_pitch, Eigen::Vector3d::UnitY()));
  s.imu.quat_wxyz = {q.w(), q.x(), q.y(), q.z()};
  s.imu.valid = true;
  return s;
}

TEST(PostureFeedback, MeasuresTheTorsoFromTheImuAndTheWaistAndClosesTheLoop) {
  PostureFeedbackConfig c;
  c.enabled = true;
  c.ki = {1.0, 1.0};
  c.max_correction_rad = 0.15;
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  double pitch = 0, roll = 0, tilt = 0;
  ASSERT_TRUE(fb.torsoAttitude(uprightState(0.1, 0.2), &pitch, &roll, &tilt));
  EXPECT_NEAR(pitch, 0.3, 1e-9) << "pelvis pitch + waist pitch";
  EXPECT_NEAR(roll, 0.0, 1e-9);
  EXPECT_NEAR(tilt, 0.1, 1e-9);
  // A robot whose torso reaches 60 % of the commanded bend (the actor's shortfall on the bend):
  // the command is raised until the torso is where the user asked, within the bound.
  double torso = 0.0;
  for (int k = 0; k < 2000; ++k) {
    const PostureCommand& out = fb.update({0.15, 0.0, 0.78}, {}, uprightState(0.0, torso), 0.01);
    torso += 0.01 / 0.3 * (0.6 * out.pitch - torso);
  }
  EXPECT_NEAR(torso, 0.15, 0.002);
  EXPECT_NEAR(fb.command().pitch, 0.25, 0.005);
  EXPECT_NEAR(fb.correction()[0], 0.10, 0.005);
  // A bigger bend: the correction stops at max_correction_rad.
  for (int k = 0; k < 2000; ++k) {
    const PostureCommand& out = fb.update({0.3, 0.0, 0.78}, {}, uprightState(0.0, torso), 0.01);
    torso += 0.01 / 0.3 * (0.6 * out.pitch - torso);
  }
  EXPECT_NEAR(fb.correction()[0], 0.15, 1e-12);
  // Tilted pelvis beyond max_tilt_rad (0.5): the correction decays to zero.
  for (int k = 0; k < 500; ++k) fb.update({0.3, 0.0, 0.78}, {}, uprightState(0.7, 0.0), 0.01);
  EXPECT_LT(std::fabs(fb.correction()[0]), 1e-3);
  // Walking: no integration, the correction built while standing decays.
  for (int k = 0; k < 500; ++k) fb.update({0.3, 0.0, 0.78}, {}, uprightState(0.0, 0.1), 0.01);
  EXPECT_NEAR(fb.correction()[0], 0.15, 1e-12);
  for (int k = 0; k < 500; ++k) fb.update({0.3, 0.0, 0.78}, {0.0, 0.3, 0.0}, uprightState(0.0, 0.1), 0.01);
  EXPECT_LT(std::fabs(fb.correction()[0]), 1e-3);
  std::size_t n = 0;
  const LowState bent = uprightState(0.05, 0.1);
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 100; ++k) fb.update({0.3, 0.1, 0.78}, {}, bent, 0.01);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
}

/// The walking pitch feedback of g1_sil_policy_wh6g.yaml: pitch gain 0.5, bound 0.08 rad, 1 s low-pass
/// and settling, upright walks (|u| < 0.05 rad) gated out; standing gains @p ki.
PostureFeedbackConfig walkingPitchConfig(double ki) {
  PostureFeedbackConfig c;
  c.enabled = true;
  c.ki = {ki, ki};
  c.walking_ki = {0.5, 0.0};
  c.walking_max_correction_rad = 0.08;
  c.walking_filter_time_s = 1.0;
  c.walking_settle_s = 1.0;
  c.walking_min_command_rad = 0.05;
  return c;
}

// Walking posture feedback (walking_ki): a bent walk whose torso sways about 60 % of the commanded
// pitch. The walking integrator waits for the command to settle, closes the loop on the
// gait-averaged pitch within its own bound, leaves an upright walk alone (walking_min_command_rad)
// and decays when the robot is told to stand, so that the lean is not held into the stop.
TEST(PostureFeedback, WalkingIntegratorClosesABentWalkAndLetsGoAtTheStop) {
  const PostureFeedbackConfig c = walkingPitchConfig(1.0);
  ASSERT_EQ(c.validate(), "");
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  const VelocityCommand walk{0.3, 0.0, 0.0};
  double torso = 0.0, t = 0.0;
  auto step = [&](double u_pitch, const VelocityCommand& v) {
    // The actor achieves 80 % of the pitch it is given, plus a 0.05 rad sway at 1.4 Hz (a gait cycle).
    const double sway = 0.05 * std::sin(2.0 * M_PI * 1.4 * t);
    const PostureCommand& out = fb.update({u_pitch, 0.0, 0.78}, v, uprightState(0.0, torso + sway), 0.01);
    torso += 0.01 / 0.3 * (0.8 * out.pitch - torso);
    t += 0.01;
  };
  // Settling: the first second after the command reaches 0.25 rad nothing is integrated.
  for (int k = 0; k < 90; ++k) step(0.25, walk);
  EXPECT_EQ(fb.correction()[0], 0.0) << "integrated before the command settled";
  double peak = 0.0;
  for (int k = 0; k < 3000; ++k) {
    step(0.25, walk);
    peak = std::max(peak, fb.correction()[0]);
  }
  EXPECT_NEAR(torso, 0.25, 0.01) << "the bent walk reaches the commanded pitch";
  EXPECT_NEAR(fb.correction()[0], 0.0625, 0.01);
  EXPECT_LE(peak, 0.08 + 1e-12) << "the walking bound";
  // A bigger bend: the correction stops at walking_max_correction_rad, below max_correction_rad.
  for (int k = 0; k < 3000; ++k) step(0.45, walk);
  EXPECT_NEAR(fb.correction()[0], 0.08, 1e-12);
  // Walking upright (|u| < walking_min_command_rad): the gait's pitch is left alone.
  fb.reset();
  torso = 0.0;
  for (int k = 0; k < 3000; ++k) {
    const PostureCommand& out = fb.update({0.0, 0.0, 0.78}, walk, uprightState(0.0, 0.04), 0.01);
    EXPECT_EQ(out.pitch, 0.0);
  }
  // The walking roll gain is 0: a walking lean is not corrected.
  fb.reset();
  for (int k = 0; k < 3000; ++k) fb.update({0.25, 0.1, 0.78}, walk, uprightState(0.0, 0.0), 0.01);
  EXPECT_EQ(fb.correction()[1], 0.0);
  EXPECT_NEAR(fb.correction()[0], 0.08, 1e-12);
  const LowState bent = uprightState(0.0, 0.2);
  EXPECT_EQ(test::allocationsDuring([&] {
              for (int k = 0; k < 100; ++k) fb.update({0.25, 0.1, 0.78}, walk, bent, 0.01);
            }),
            0u);
}

// envelope_min/max (bounds on the fed-back pitch/roll, the actor's trained range): a bent walk whose
// torso reaches only 80 % of what it is given is fed back up to the envelope's 0.4 rad and no
// further, where the walking bound alone lets the command reach 0.48; what the envelope cuts does
// not wind up the integrator; the standing integrator is bounded alike; a bend inside the envelope
// is corrected as before; a command already beyond it passes unchanged (not corrected further
// out, not clipped); the default bounds nothing beyond the command's range; invalid bounds are
// refused, naming the field.
TEST(PostureFeedback, EnvelopeKeepsTheCorrectionInsideTheActorsTrainedRange) {
  PostureFeedbackConfig c = walkingPitchConfig(1.0);
  c.envelope_min = {-0.3, -0.2};
  c.envelope_max = {0.4, 0.2};
  ASSERT_EQ(c.validate(), "");
  const PostureFeedbackConfig wide = walkingPitchConfig(1.0);
  ASSERT_EQ(wide.envelope_max[0], 1.5) << "the default bounds nothing beyond the command's range";
  const VelocityCommand walk{0.4, 0.0, 0.0};
  // The actor achieves 80 % of the pitch it is given; returns the largest pitch sent to it.
  auto run = [&](PostureFeedback& fb, double u_pitch, const VelocityCommand& v, int ticks) {
    double torso = 0.0, most = -1.0;
    for (int k = 0; k < ticks; ++k) {
      const PostureCommand& out = fb.update({u_pitch, 0.0, 0.66}, v, uprightState(0.0, torso), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch - torso);
      most = std::max(most, out.pitch);
    }
    return most;
  };
  PostureFeedback without(wide, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  PostureFeedback with(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  EXPECT_NEAR(run(without, 0.4, walk, 4000), 0.48, 1e-9) << "the walking bound alone: 0.4 + 0.08";
  EXPECT_NEAR(run(with, 0.4, walk, 4000), 0.4, 1e-12) << "never beyond the envelope";
  EXPECT_NEAR(with.correction()[0], 0.0, 1e-12) << "the cut came off the integrator";
  // Told to stop with the bend kept: the standing integrator is bounded alike.
  EXPECT_GT(run(without, 0.4, {}, 3000), 0.45) << "standing, the robot needs 0.5 and gets it";
  EXPECT_NEAR(run(with, 0.4, {}, 3000), 0.4, 1e-12);
  // A bend inside the envelope: corrected as usual, within the envelope.
  with.reset();
  EXPECT_LE(run(with, 0.3, walk, 4000), 0.4);
  EXPECT_NEAR(with.command().pitch, 0.375, 0.005) << "80 % of 0.375 is the commanded 0.3";
  EXPECT_NEAR(with.correction()[0], 0.075, 0.005);
  // A command beyond the envelope (the shaper allows up to 0.6): passed on, not pushed further out.
  with.reset();
  EXPECT_NEAR(run(with, 0.5, walk, 4000), 0.5, 1e-12);
  EXPECT_NEAR(with.command().pitch, 0.5, 1e-12);
  // Roll alike: a lean at 0.19 whose torso stays upright is corrected up to 0.2 only.
  PostureFeedbackConfig r = c;
  r.walking_ki = {0.0, 0.5};
  r.walking_min_command_rad = 0.0;
  PostureFeedback roll(r, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  for (int k = 0; k < 3000; ++k) roll.update({0.0, 0.19, 0.78}, walk, uprightState(0.0, 0.0), 0.01);
  EXPECT_NEAR(roll.command().roll, 0.2, 1e-12);
  const LowState bent = uprightState(0.0, 0.1);
  EXPECT_EQ(test::allocationsDuring([&] {
              for (int k = 0; k < 100; ++k) with.update({0.4, 0.1, 0.66}, walk, bent, 0.01);
            }),
            0u);
  PostureFeedbackConfig bad = c;
  bad.envelope_min[0] = 0.05;
  EXPECT_NE(bad.validate().find("envelope_min/envelope_max[0] (pitch)"), std::string::npos);
  bad = c;
  bad.envelope_max[1] = std::nan("");
  EXPECT_NE(bad.validate().find("envelope_min/envelope_max[1] (roll)"), std::string::npos);
}

// walking_deadband_rad: an upright walk whose torso leans back 0.07 rad is corrected until the lean
// is just beyond the band (0.03: inside it the correction decays), and one that leans 0.02 is left
// alone; at the stop the correction decays.
TEST(PostureFeedback, WalkingDeadBandCorrectsOnlyALeanBeyondIt) {
  PostureFeedbackConfig c = walkingPitchConfig(0.0);
  c.walking_deadband_rad = 0.03;
  ASSERT_EQ(c.validate(), "");
  const VelocityCommand walk{0.5, 0.3, 0.5};
  for (const double lean : {-0.07, -0.02}) {
    PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
    double torso = lean, t = 0.0, avg = 0.0;
    int n_avg = 0;
    for (int k = 0; k < 6000; ++k) {
      const double sway = 0.03 * std::sin(2.0 * M_PI * 1.4 * t);
      const PostureCommand& out = fb.update({0.0, 0.0, 0.78}, walk, uprightState(0.0, torso + sway), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch + lean - torso);
      t += 0.01;
      if (k >= 5000) {
        avg += torso;
        ++n_avg;
      }
    }
    avg /= n_avg;
    if (lean < -0.05) {
      // Beyond the band it integrates, inside it decays: the lean settles just beyond the band.
      EXPECT_LT(avg, -0.03) << "corrected into the band: the correction would decay there";
      EXPECT_GT(avg, -0.04) << "the lean of 0.07 rad brought to within 0.01 of the band";
      EXPECT_GT(fb.correction()[0], 0.03);
      EXPECT_LT(fb.correction()[0], 0.05);
    } else {
      EXPECT_EQ(fb.correction()[0], 0.0) << "a lean inside the band is left alone";
    }
    // Told to stand: the correction decays, monotonically.
    double prev = fb.correction()[0];
    for (int k = 0; k < 300; ++k) {
      fb.update({0.0, 0.0, 0.78}, {}, uprightState(0.0, torso), 0.01);
      EXPECT_LE(std::fabs(fb.correction()[0]), std::fabs(prev) + 1e-15);
      prev = fb.correction()[0];
    }
  }
  // Without the band (0, the default), an upright walk is not integrated at all.
  c.walking_deadband_rad = 0.0;
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  for (int k = 0; k < 3000; ++k) fb.update({0.0, 0.0, 0.78}, walk, uprightState(0.0, -0.2), 0.01);
  EXPECT_EQ(fb.correction()[0], 0.0);
  // Out of range: refused, naming the field.
  c.walking_deadband_rad = 0.4;
  EXPECT_NE(c.validate().find("walking_deadband_rad"), std::string::npos);
}

/// Heap allocations of 300 ticks of a crouched (0.68 m) walk leaning back 0.1 rad.
std::size_t crouchedWalkAllocations(const PostureFeedbackConfig& c, const std::array<double, 2>& heights,
                                    const VelocityCommand& walk) {
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
  const LowState lean = uprightState(0.0, -0.1);
  test::AllocationGuard guard;
  for (int k = 0; k < 300; ++k) fb.update({0.0, 0.0, 0.68}, walk, lean, 0.01);
  return guard.count();
}

// walking_crouch_m: a robot whose torso leans back 0.06 rad when crouched still and 0.10 when it
// walks crouched (the actor's lean in issue 12's `crouch_walk`). Standing crouched, the standing
// integrator corrects the 0.06. Walking crouched, that correction is held (within the walking
// bound), not dropped at the first step, and the walking integrator adds the rest: the
// gait-averaged torso comes upright. Without the
// key the crouched walk is an upright-command walk, left alone, and it leans back. An upright walk
// (or one crouched less than the key) is left alone either way.
TEST(PostureFeedback, CrouchedWalkFeedsBackItsLeanAndHoldsTheStillCrouchsCorrection) {
  PostureFeedbackConfig c = walkingPitchConfig(1.0);
  c.walking_crouch_m = 0.03;
  ASSERT_EQ(c.validate(), "");
  const std::array<double, 2> heights{0.45, 0.85};
  const VelocityCommand walk{0.4, 0.0, 0.0};
  struct Run {
    double min_correction_walking = 1.0;  ///< smallest correction after the first step [rad]
    double mean_torso = 0.0;              ///< gait-averaged torso pitch over the walk's last 5 s [rad]
    double correction = 0.0;              ///< at the end of the walk [rad]
  };
  auto run = [&](const PostureFeedbackConfig& cfg, double height) {
    PostureFeedback fb(cfg, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
    const double crouch = 0.78 - height;
    double torso = 0.0, t = 0.0;
    Run r;
    auto step = [&](const VelocityCommand& v, bool walking) {
      const double lean = crouch > 0.02 ? (walking ? -0.10 : -0.06) : (walking ? -0.02 : 0.0);
      const double sway = walking ? 0.04 * std::sin(2.0 * M_PI * 1.4 * t) : 0.0;
      const PostureCommand& out = fb.update({0.0, 0.0, height}, v, uprightState(0.0, torso + sway), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch + lean - torso);
      t += 0.01;
    };
    for (int k = 0; k < 2000; ++k) step({}, false);  // 20 s crouched still
    for (int k = 0; k < 2000; ++k) {                  // 20 s crouched walk
      step(walk, true);
      r.min_correction_walking = std::min(r.min_correction_walking, fb.correction()[0]);
      if (k >= 1500) r.mean_torso += torso / 500.0;
    }
    r.correction = fb.correction()[0];
    return r;
  };
  // Crouched 0.10 m (the grid's crouch_walk at 0.68 m).
  const Run on = run(c, 0.68);
  EXPECT_GT(on.min_correction_walking, 0.06) << "the still crouch's correction (0.075) was dropped at the first step";
  EXPECT_NEAR(on.mean_torso, 0.0, 0.01) << "the crouched walk still leans";
  EXPECT_NEAR(on.correction, 0.125, 0.01) << "0.075 held + 0.05 walking";
  PostureFeedbackConfig off = c;
  off.walking_crouch_m = 0.0;
  const Run without = run(off, 0.68);
  EXPECT_LT(without.mean_torso, -0.09) << "without the key a crouched walk is left alone";
  EXPECT_LT(std::fabs(without.correction), 1e-3);
  // A still crouch that needed more than the walking bound (0.08): walking, what lies beyond the
  // bound decays (decay_time_s, 0.5 s) and the rest is held, without a jump.
  {
    PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
    double torso = 0.0;
    for (int k = 0; k < 2000; ++k) {
      const PostureCommand& out = fb.update({0.0, 0.0, 0.68}, {}, uprightState(0.0, torso), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch - 0.115 - torso);
    }
    const double still = fb.correction()[0];
    EXPECT_NEAR(still, 0.14375, 0.002);
    double prev = still, largest_step = 0.0;
    for (int k = 0; k < 150; ++k) {
      fb.update({0.0, 0.0, 0.68}, walk, uprightState(0.0, 0.0), 0.01);  // walking, upright on the average
      largest_step = std::max(largest_step, std::fabs(fb.correction()[0] - prev));
      prev = fb.correction()[0];
    }
    EXPECT_LT(largest_step, 0.002) << "the correction jumped";
    EXPECT_LT(fb.correction()[0], 0.08 + 0.07 * std::exp(-1.5 / 0.5)) << "the excess over the walking bound decays";
    EXPECT_GT(fb.correction()[0], 0.07) << "the part within the walking bound is held";
  }
  // A commanded bend walked crouched is a commanded walk as before: the still pose's correction is
  // not held into it (it decays while the walking integrator starts from zero).
  {
    PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
    double torso = 0.0;
    for (int k = 0; k < 2000; ++k) {
      const PostureCommand& out = fb.update({0.25, 0.0, 0.68}, {}, uprightState(0.0, torso), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch - torso);
    }
    EXPECT_NEAR(fb.correction()[0], 0.0625, 0.002);
    for (int k = 0; k < 100; ++k) {
      const PostureCommand& out = fb.update({0.25, 0.0, 0.68}, walk, uprightState(0.0, torso), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch - torso);
    }
    EXPECT_LT(fb.correction()[0], 0.05) << "a bent walk held the still pose's correction";
  }
  // Crouched less than the key (0.02 m), or upright: the walk's pitch is left alone.
  for (const double h : {0.76, 0.78}) {
    const Run upright = run(c, h);
    EXPECT_LT(std::fabs(upright.correction), 1e-3) << "height " << h;
  }
  // Allocation-free, crouched walking.
  EXPECT_EQ(crouchedWalkAllocations(c, heights, walk), 0u);
  // Out of range, and without a standing height: refused, naming the field.
  PostureFeedbackConfig bad = c;
  bad.walking_crouch_m = 0.3;
  EXPECT_NE(bad.validate().find("walking_crouch_m"), std::string::npos);
  EXPECT_THROW(PostureFeedback(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}), ConfigError);
}

// walking_crouch_release: an actor that leans *forward* 0.05 rad crouched still and back 0.06 rad
// walking crouched (H3 at 0.62 / 0.68 m). Held, the still crouch's correction (about -0.06) adds to
// the walk's backward lean and the walking integrator (bound 0.08) spends itself cancelling it; with
// the key, the held correction decays once the gait-averaged torso is behind the command, and the
// walking integrator brings the torso upright. An actor that leans back in both (the held
// correction agrees with the walking error) is held as before, and nothing jumps.
TEST(PostureFeedback, CrouchedWalkReleasesAStandingCorrectionOpposedToTheWalk) {
  PostureFeedbackConfig c = walkingPitchConfig(1.0);
  c.walking_crouch_m = 0.03;
  c.walking_max_correction_rad = 0.08;
  const std::array<double, 2> heights{0.45, 0.85};
  const VelocityCommand walk{0.4, 0.0, 0.0};
  struct Run {
    double mean_torso = 0.0;       ///< gait-averaged torso pitch over the walk's last 5 s [rad]
    double correction_start = 0.0; ///< when the walk starts [rad]
    double largest_step = 0.0;     ///< largest change of the correction in one tick while walking [rad]
    double correction = 0.0;       ///< at the end of the walk [rad]
  };
  auto run = [&](bool release, double still_lean, double walk_lean) {
    PostureFeedbackConfig cfg = c;
    cfg.walking_crouch_release = release;
    EXPECT_EQ(cfg.validate(), "");
    PostureFeedback fb(cfg, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
    double torso = 0.0, t = 0.0;
    Run r;
    for (int k = 0; k < 2000; ++k) {  // 20 s crouched still
      const PostureCommand& out = fb.update({0.0, 0.0, 0.68}, {}, uprightState(0.0, torso), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch + still_lean - torso);
    }
    r.correction_start = fb.correction()[0];
    double prev = r.correction_start;
    for (int k = 0; k < 2000; ++k) {  // 20 s crouched walk
      const double sway = 0.04 * std::sin(2.0 * M_PI * 1.4 * t);
      const PostureCommand& out = fb.update({0.0, 0.0, 0.68}, walk, uprightState(0.0, torso + sway), 0.01);
      torso += 0.01 / 0.3 * (0.8 * out.pitch + walk_lean - torso);
      t += 0.01;
      r.largest_step = std::max(r.largest_step, std::fabs(fb.correction()[0] - prev));
      prev = fb.correction()[0];
      if (k >= 1500) r.mean_torso += torso / 500.0;
    }
    r.correction = fb.correction()[0];
    return r;
  };
  const Run held = run(false, 0.05, -0.06);
  const Run released = run(true, 0.05, -0.06);
  EXPECT_NEAR(held.correction_start, -0.0625, 0.002);
  EXPECT_NEAR(released.correction_start, -0.0625, 0.002);
  EXPECT_LT(held.mean_torso, -0.04) << "held, the standing correction should keep the torso back (the walking bound spent)";
  EXPECT_NEAR(released.mean_torso, 0.0, 0.01) << "released, the walking integrator should bring the torso upright";
  EXPECT_NEAR(released.correction, 0.075, 0.005) << "the walk's 0.06 lean over the plant's gain 0.8, within the walking bound";
  EXPECT_LT(released.largest_step, 0.002) << "the correction jumped";
  // Leaning back in both: the held correction agrees with the walking error and is held as before.
  const Run same_held = run(false, -0.06, -0.10);
  const Run same_released = run(true, -0.06, -0.10);
  EXPECT_NEAR(same_released.correction, same_held.correction, 1e-9);
  EXPECT_NEAR(same_released.mean_torso, same_held.mean_torso, 1e-9);
  // Allocation-free.
  c.walking_crouch_release = true;
  EXPECT_EQ(crouchedWalkAllocations(c, heights, walk), 0u);
}

// still_measured_velocity: told to stand but still running (the estimate above the threshold), the
// standing correction is held, neither integrated nor decayed; once the robot is seen still, or
// without an estimate (or an invalid one), it integrates as before.
TEST(PostureFeedback, StandingCorrectionIsHeldWhileTheRobotStillMoves) {
  PostureFeedbackConfig c;
  c.enabled = true;
  c.ki = {1.0, 1.0};
  c.still_measured_velocity = 0.3;
  ASSERT_EQ(c.validate(), "");
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  const LowState short_of_bend = uprightState(0.0, 0.3);  // torso at 0.3 rad, told 0.4
  BaseVelocityEstimate running;
  running.valid = true;
  running.stance_feet = 1;
  running.v_x = 1.5;
  BaseVelocityEstimate stopped = running;
  stopped.v_x = 0.1;
  // Builds a correction while still.
  for (int k = 0; k < 50; ++k) fb.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, &stopped);
  const double built = fb.correction()[0];
  EXPECT_GT(built, 0.02);
  // Commanded still, but running: held exactly.
  for (int k = 0; k < 300; ++k) fb.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, &running);
  EXPECT_EQ(fb.correction()[0], built) << "integrated while the robot ran on";
  // An invalid estimate, or none: as before (integrates).
  running.valid = false;
  fb.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, &running);
  EXPECT_GT(fb.correction()[0], built);
  const double after_invalid = fb.correction()[0];
  fb.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, nullptr);
  EXPECT_GT(fb.correction()[0], after_invalid);
  // Seen still again: integrates.
  const double before = fb.correction()[0];
  for (int k = 0; k < 50; ++k) fb.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, &stopped);
  EXPECT_GT(fb.correction()[0], before);
  // Off (0, the default): integrates while running too.
  c.still_measured_velocity = 0.0;
  PostureFeedback off(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  running.valid = true;
  for (int k = 0; k < 50; ++k) off.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, &running);
  EXPECT_GT(off.correction()[0], 0.02);
  // Allocation-free; out of range refused, naming the field.
  std::size_t n = 0;
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 100; ++k) fb.update({0.4, 0.0, 0.78}, {}, short_of_bend, 0.01, &running);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
  c.still_measured_velocity = 2.5;
  EXPECT_NE(c.validate().find("still_measured_velocity"), std::string::npos);
}

// A standing pitch/roll integrator at ki 1 /s on the unfiltered attitude: what the settling and
// release tests below start from.
PostureFeedbackConfig integratingConfig() {
  PostureFeedbackConfig c;
  c.enabled = true;
  c.ki = {1.0, 1.0};
  c.filter_time_s = 0.0;
  return c;
}

// settle_s: standing, the torso lags the shaper's unbend ramp (0.4 -> 0 rad at 0.5 rad/s); integrating
// that lag winds the correction negative, and the robot then stands leaning back. With settle_s the
// correction is held through the ramp and integrates only once the command has been steady that long.
TEST(PostureFeedback, StandingCorrectionWaitsForThePostureCommandToSettle) {
  PostureFeedbackConfig c = integratingConfig();
  c.envelope_max = {0.6, 0.3};
  ASSERT_EQ(c.validate(), "");
  auto unbend = [&](double settle_s, std::vector<double>* corr) {
    PostureFeedbackConfig cc = c;
    cc.settle_s = settle_s;
    PostureFeedback fb(cc, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
    // Bent and still at 0.4 rad, the torso at 0.36: a positive correction builds.
    for (int k = 0; k < 300; ++k) fb.update({0.4, 0.0, 0.78}, {}, uprightState(0.0, 0.36), 0.01);
    corr->push_back(fb.correction()[0]);
    // The ramp to 0 over 0.8 s with the torso 0.15 rad behind it, then the torso at 0.
    for (int k = 1; k <= 80; ++k) {
      const double cmd = 0.4 - 0.005 * k;
      fb.update({cmd, 0.0, 0.78}, {}, uprightState(0.0, std::min(0.4, cmd + 0.15)), 0.01);
    }
    corr->push_back(fb.correction()[0]);
    // The torso 0.03 rad forward of the command after it.
    for (int k = 0; k < 20; ++k) fb.update({0.0, 0.0, 0.78}, {}, uprightState(0.0, 0.03), 0.01);
    corr->push_back(fb.correction()[0]);
    for (int k = 0; k < 100; ++k) fb.update({0.0, 0.0, 0.78}, {}, uprightState(0.0, 0.03), 0.01);
    corr->push_back(fb.correction()[0]);
  };
  std::vector<double> off, on;
  unbend(0.0, &off);
  unbend(0.5, &on);
  // Before the ramp both built a positive correction (on: 0.5 s less of it, the start's settling).
  EXPECT_GT(on[0], 0.05);
  EXPECT_NEAR(off[0] - on[0], 0.04 * 0.5, 1e-9);
  // Off: the ramp's lag is integrated (up to 0.15 rad for 0.8 s): the correction falls by about 0.1.
  EXPECT_LT(off[1], off[0] - 0.08);
  // On: held through the ramp (but its first tick, inside the 0.01 rad that counts as settled), and
  // 0.2 s after it, still held (not yet settled).
  EXPECT_NEAR(on[1], on[0], 1e-4);
  EXPECT_DOUBLE_EQ(on[2], on[1]);
  // Settled: integrates again (the torso forward of the command: the correction falls).
  EXPECT_LT(on[3], on[2]);
  c.settle_s = 5.5;
  EXPECT_NE(c.validate().find("settle_s"), std::string::npos);
}

// stop_settle_s: the torso's swing after a stop (H5c stopping a crouched turn: back 0.15 rad for half
// a second, then forward past upright) is the robot's own transient, not a posture error. Integrated,
// it winds a forward correction that the torso then follows into a run-on; with stop_settle_s the
// standing correction is held until the velocity command has been still that long.
TEST(PostureFeedback, StandingCorrectionWaitsForTheRobotToSettleAfterAStop) {
  PostureFeedbackConfig c = integratingConfig();
  ASSERT_EQ(c.validate(), "");
  struct Run {
    double at_stop = 0.0, after_swing = 0.0, largest_change_in_swing = 0.0, settled = 0.0;
    std::size_t allocations = 0;
  };
  auto run = [&](double stop_settle_s) {
    PostureFeedbackConfig cc = c;
    cc.stop_settle_s = stop_settle_s;
    PostureFeedback fb(cc, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
    const PostureCommand upright{0.0, 0.0, 0.78};
    // Standing with the torso 0.02 rad back: a small forward correction builds (3 s).
    for (int k = 0; k < 300; ++k) fb.update(upright, {}, uprightState(0.0, -0.02), 0.01);
    // A turn for 0.5 s (the standing correction decays), then the stop.
    for (int k = 0; k < 50; ++k) fb.update(upright, {0.0, 0.0, 0.4}, uprightState(0.0, 0.0), 0.01);
    Run r;
    r.at_stop = fb.correction()[0];
    const LowState back = uprightState(0.0, -0.15), forward = uprightState(0.0, 0.08), ahead = uprightState(0.0, 0.03);
    test::AllocationGuard guard;
    // The swing, inside the first second after the stop: 0.5 s back at -0.15 rad, 0.45 s forward at +0.08.
    for (int k = 0; k < 95; ++k) {
      fb.update(upright, {}, k < 50 ? back : forward, 0.01);
      r.largest_change_in_swing = std::max(r.largest_change_in_swing, std::fabs(fb.correction()[0] - r.at_stop));
    }
    r.after_swing = fb.correction()[0];
    // The torso 0.03 rad forward for 0.54 s more, settled from 1.0 s after the stop: 50 ticks integrate.
    for (int k = 0; k < 54; ++k) fb.update(upright, {}, ahead, 0.01);
    r.settled = fb.correction()[0];
    r.allocations = guard.count();
    return r;
  };
  const Run off = run(0.0);
  const Run on = run(1.0);
  EXPECT_GT(off.at_stop, 0.02);
  EXPECT_GT(on.at_stop, 0.01);  // 1 s less of it: the start waits too (below)
  // Off: the swing is integrated: 0.075 forward, 0.036 back, so the correction ends 0.039 further forward.
  EXPECT_NEAR(off.after_swing - off.at_stop, 0.15 * 0.5 - 0.08 * 0.45, 1e-6);
  // On: held through the whole swing, exactly.
  EXPECT_EQ(on.largest_change_in_swing, 0.0);
  EXPECT_DOUBLE_EQ(on.after_swing, on.at_stop);
  // Settled: integrates again (the torso forward of the command: the correction falls by 0.015).
  EXPECT_NEAR(on.settled - on.after_swing, -0.03 * 0.5, 1e-6);
  EXPECT_EQ(on.allocations, 0u);
  // The wait counts from the first still tick, so the standing integrator waits at the start too.
  PostureFeedbackConfig cc = c;
  cc.stop_settle_s = 1.0;
  PostureFeedback fresh(cc, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  for (int k = 0; k < 99; ++k) fresh.update({0.0, 0.0, 0.78}, {}, uprightState(0.0, -0.1), 0.01);
  EXPECT_EQ(fresh.correction()[0], 0.0);
  for (int k = 0; k < 10; ++k) fresh.update({0.0, 0.0, 0.78}, {}, uprightState(0.0, -0.1), 0.01);
  EXPECT_GT(fresh.correction()[0], 0.005);
  c.stop_settle_s = 5.5;
  EXPECT_NE(c.validate().find("stop_settle_s"), std::string::npos);
}

// walking_velocity_settle_s: as a crouched walk starts from a stand, the torso swings forward (H10a
// side-stepping at 0.66 m: +0.2 rad for about 0.4 s) and then leans back for as long as it walks
// (-0.06 rad here). Integrated from the first tick, the swing winds a backward correction, the wrong
// way for the walk; with the key the walking integrator holds until the shaped velocity command has
// stayed within 0.05 of where it settled that long, counted again through a ramp, and then feeds back
// the walk's lean. Off (0, the default) it integrates from the first tick, as before.
TEST(PostureFeedback, WalkingCorrectionWaitsForTheWalkToSettle) {
  PostureFeedbackConfig c = walkingPitchConfig(1.0);
  c.walking_ki = {2.0, 0.0};
  c.walking_max_correction_rad = 0.15;
  c.max_correction_rad = 0.2;
  c.walking_filter_time_s = 0.0;  // the attitude as measured, so that the integrals below are exact
  c.walking_crouch_m = 0.02;
  ASSERT_EQ(c.validate(), "");
  const std::array<double, 2> heights{0.45, 0.85};
  const PostureCommand crouched{0.0, 0.0, 0.66};
  struct Run {
    double after_ramp = 0.0, after_swing = 0.0, before_settled = 0.0, settled = 0.0, end = 0.0;
    std::size_t allocations = 0;
  };
  auto run = [&](double settle_s) {
    PostureFeedbackConfig cc = c;
    cc.walking_velocity_settle_s = settle_s;
    EXPECT_EQ(cc.validate(), "");
    PostureFeedback fb(cc, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
    const LowState upright = uprightState(0.0, 0.0), swing = uprightState(0.0, 0.2), back = uprightState(0.0, -0.06);
    // Crouched and still, upright: no correction.
    for (int k = 0; k < 200; ++k) fb.update(crouched, {}, upright, 0.01);
    Run r;
    test::AllocationGuard guard;
    // The shaper's ramp to 0.4 m/s over 0.5 s with the torso still upright, then the swing (0.4 s
    // forward), then the walk's lean back.
    for (int k = 1; k <= 50; ++k) fb.update(crouched, {0.008 * k, 0.0, 0.0}, upright, 0.01);
    r.after_ramp = fb.correction()[0];
    const VelocityCommand walk{0.4, 0.0, 0.0};
    for (int k = 0; k < 40; ++k) fb.update(crouched, walk, swing, 0.01);
    r.after_swing = fb.correction()[0];
    // The ramp's last step beyond 0.05 of where it settled is its 49th tick: 0.99 s after it.
    for (int k = 0; k < 58; ++k) fb.update(crouched, walk, back, 0.01);
    r.before_settled = fb.correction()[0];
    for (int k = 0; k < 50; ++k) fb.update(crouched, walk, back, 0.01);  // 50 ticks from 1.0 s on
    r.settled = fb.correction()[0];
    for (int k = 0; k < 200; ++k) fb.update(crouched, walk, back, 0.01);
    r.end = fb.correction()[0];
    r.allocations = guard.count();
    return r;
  };
  const Run off = run(0.0);
  const Run on = run(1.0);
  // Off: the swing winds a backward correction (2 /s x 0.2 rad x 0.4 s = 0.16, bounded at 0.15)...
  EXPECT_NEAR(off.after_swing, -0.15, 1e-9);
  // ...that the walk's lean back (0.12 rad/s at 2 /s) takes more than a second to unwind.
  EXPECT_LT(off.before_settled, -0.02) << "off: still pushing the leaning-back walk further back";
  // On: held through the ramp and the swing, exactly (nothing integrated, nothing decayed)...
  EXPECT_EQ(on.after_ramp, 0.0);
  EXPECT_EQ(on.after_swing, 0.0);
  EXPECT_EQ(on.before_settled, 0.0) << "integrated before the walk had settled for 1.0 s";
  // ...then it feeds back the walk's lean: 50 ticks x 2 /s x 0.06 rad x 0.01 s = +0.06.
  EXPECT_NEAR(on.settled, 0.06, 1e-6);
  EXPECT_NEAR(on.end, 0.15, 1e-9) << "the walk's lean fed back to the walking bound";
  EXPECT_GT(on.settled, off.settled) << "on: ahead of the wound-up integrator";
  EXPECT_EQ(on.allocations, 0u);
  EXPECT_EQ(off.allocations, 0u);
  // A change of the walk's command by more than 0.05 restarts the wait (a turn added to the walk).
  {
    PostureFeedbackConfig cc = c;
    cc.walking_velocity_settle_s = 1.0;
    PostureFeedback fb(cc, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, heights, 0.78);
    const LowState back = uprightState(0.0, -0.06);
    for (int k = 0; k < 150; ++k) fb.update(crouched, {0.4, 0.0, 0.0}, back, 0.01);
    const double walking = fb.correction()[0];
    EXPECT_GT(walking, 0.0);
    for (int k = 0; k < 90; ++k) fb.update(crouched, {0.4, 0.0, 0.3}, back, 0.01);
    EXPECT_EQ(fb.correction()[0], walking) << "integrated within 1.0 s of the turn being added";
    for (int k = 0; k < 20; ++k) fb.update(crouched, {0.4, 0.0, 0.3}, back, 0.01);
    EXPECT_GT(fb.correction()[0], walking);
    // Within 0.05 of where it settled (the feedback's own trims): the wait is not restarted.
    const double trimmed = fb.correction()[0];
    fb.update(crouched, {0.44, 0.0, 0.27}, back, 0.01);
    EXPECT_GT(fb.correction()[0], trimmed);
  }
  PostureFeedbackConfig bad = c;
  bad.walking_velocity_settle_s = 5.5;
  EXPECT_NE(bad.validate().find("walking_velocity_settle_s"), std::string::npos);
  bad.walking_velocity_settle_s = -0.1;
  EXPECT_NE(bad.validate().find("walking_velocity_settle_s"), std::string::npos);
}

// overshoot_release: standing, a correction that pushes the torso further past the command (beyond
// 0.02 rad on its other side) decays at decay_time_s on top of its integration; within the band, or
// with the torso still short of the command, it only integrates, as without the key.
TEST(PostureFeedback, StandingCorrectionPushingTheTorsoPastTheCommandDecays) {
  PostureFeedbackConfig c = integratingConfig();
  c.decay_time_s = 0.5;
  ASSERT_EQ(c.validate(), "");
  const LowState behind = uprightState(0.0, -0.05);
  auto run = [&](bool release, double torso, double* built, std::size_t* allocations) {
    PostureFeedbackConfig cc = c;
    cc.overshoot_release = release;
    PostureFeedback fb(cc, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
    const PostureCommand upright{0.0, 0.0, 0.78};
    // The torso 0.05 rad back for 2 s: a forward correction of about 0.1 rad builds (no release: the
    // torso is short of the command, on the correction's side).
    for (int k = 0; k < 200; ++k) fb.update(upright, {}, behind, 0.01);
    *built = fb.correction()[0];
    const LowState swung = uprightState(0.0, torso);
    test::AllocationGuard guard;
    for (int k = 0; k < 50; ++k) fb.update(upright, {}, swung, 0.01);
    *allocations = guard.count();
    return fb.correction()[0];
  };
  double built_off = 0.0, built_on = 0.0;
  std::size_t n = 0;
  // The torso swings 0.06 rad forward of the command for 0.5 s.
  const double off = run(false, 0.06, &built_off, &n);
  const double on = run(true, 0.06, &built_on, &n);
  EXPECT_EQ(n, 0u);
  EXPECT_NEAR(built_on, 0.1, 0.002);
  EXPECT_DOUBLE_EQ(built_on, built_off);
  // Off: it integrates back at 0.06 rad/s only.
  EXPECT_NEAR(off, built_off - 0.06 * 0.5, 1e-9);
  // On: c <- c (1 - dt/0.5) - 0.06 dt each tick.
  double expected = built_on;
  for (int k = 0; k < 50; ++k) expected = expected * (1.0 - 0.01 / 0.5) - 0.06 * 0.01;
  EXPECT_NEAR(on, expected, 1e-9);
  EXPECT_LT(on, off - 0.03);
  // Within the 0.02 rad band, or short of the command: as without the key.
  EXPECT_DOUBLE_EQ(run(true, 0.015, &built_on, &n), run(false, 0.015, &built_off, &n));
  EXPECT_DOUBLE_EQ(run(true, -0.03, &built_on, &n), run(false, -0.03, &built_off, &n));
}

TEST(PostureFeedback, UpsetUprightDecaysTheCorrectionInsteadOfIntegrating) {
  // The upset guard holds with upright: the shaper sends pitch 0, the torso leans back 0.12 rad as the
  // robot runs on. Integrating, the standing correction would push the torso forward again.
  PostureFeedbackConfig c;
  c.enabled = true;
  c.ki = {1.0, 1.0};
  c.max_correction_rad = 0.15;
  c.decay_time_s = 0.5;
  ASSERT_EQ(c.validate(), "");
  const LowState leaning_back = uprightState(0.0, -0.12);
  auto run = [&](bool upset, std::vector<double>* trace) {
    PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
    // A correction built while still (the torso 0.1 short of a 0.3 rad bend).
    for (int k = 0; k < 100; ++k) fb.update({0.3, 0.0, 0.78}, {}, uprightState(0.0, 0.2), 0.01);
    for (int k = 0; k < 300; ++k) {
      fb.update({0.0, 0.0, 0.78}, {}, leaning_back, 0.01, nullptr, upset);
      trace->push_back(fb.correction()[0]);
    }
  };
  std::vector<double> plain, upset;
  plain.reserve(300);
  upset.reserve(300);
  run(false, &plain);
  run(true, &upset);
  EXPECT_NEAR(plain.back(), 0.15, 1e-9) << "integrating: pushed forward to the bound";
  EXPECT_LT(std::fabs(upset.back()), 0.01) << "upset: decayed towards 0";
  for (std::size_t k = 1; k < upset.size(); ++k) {
    EXPECT_LE(std::fabs(upset[k]), std::fabs(upset[k - 1]) + 1e-12) << "never grows: " << k;
    EXPECT_LE(std::fabs(upset[k] - upset[k - 1]), 0.01 / 0.5 * 0.15 + 1e-12) << "continuous: " << k;
  }
}

TEST(PostureFeedback, WalkingDecayAfterAStop) {
  PostureFeedbackConfig c;
  c.enabled = true;
  c.ki = {0.0, 0.0};  // no standing integrator: what is left after the stop is the walking one
  c.walking_ki = {1.0, 1.0};
  c.walking_max_correction_rad = 0.08;
  c.walking_settle_s = 0.0;
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  for (int k = 0; k < 2000; ++k) fb.update({0.0, 0.0, 0.78}, {0.0, 0.4, 0.0}, uprightState(0.0, -0.2), 0.01);
  EXPECT_NEAR(fb.correction()[0], 0.08, 1e-12) << "walking_min_command_rad 0: upright walks are corrected too";
  double prev = fb.correction()[0];
  for (int k = 0; k < 300; ++k) {
    fb.update({0.0, 0.0, 0.78}, {}, uprightState(0.0, -0.2), 0.01);
    EXPECT_LE(fb.correction()[0], prev) << "monotone decay, no jump";
    EXPECT_GE(prev - fb.correction()[0], 0.0);
    EXPECT_LE(prev - fb.correction()[0], 0.08 * 0.01 / 0.5 + 1e-12) << "decays at decay_time_s, never jumps";
    prev = fb.correction()[0];
  }
  EXPECT_LT(fb.correction()[0], 0.08 * 0.01) << "3 s after the stop (6 decay times)";
}

// A crouch with flat feet: hip pitch -a, knee 2a, ankle pitch -a on both legs (the pelvis goes
// straight down as a grows), the IMU level.
LowState crouchState(double a) {
  LowState s = uprightState(0.0, 0.0);
  for (const char* side : {"left", "right"}) {
    s.motors[static_cast<std::size_t>(jointIndex(std::string(side) + "_hip_pitch_joint"))].q = -a;
    s.motors[static_cast<std::size_t>(jointIndex(std::string(side) + "_knee_joint"))].q = 2.0 * a;
    s.motors[static_cast<std::size_t>(jointIndex(std::string(side) + "_ankle_pitch_joint"))].q = -a;
  }
  return s;
}

struct HeightFixture {
  std::shared_ptr<const gco::LegModel> legs = gco::LegModel::fromRobotConfig(test::g1Robot());
  gco::LegJointIndex idx = legs->jointIndices(robotJointNames());
  /// The pelvis height over the sole with straight legs, less 1 cm: a standing height the legs can reach [m].
  double standingHeight() const {
    gco::LegKinematics kin(legs);
    Eigen::Isometry3d X_BS;
    EXPECT_TRUE(kin.forward(Foot::kLeft, gco::LegVector::Zero(), &X_BS));
    return -X_BS.translation().z() - 0.01;
  }
};

/// The walking height tests' config: standing height feedback bounded to 5 mm, the walking one at @p ki with
/// @p max_correction [m], walking_settle_s 1 s.
PostureFeedbackConfig walkingHeightConfig(double ki, double max_correction) {
  PostureFeedbackConfig c;
  c.enabled = true;
  c.height_ki = 1.0;
  c.max_height_correction_m = 0.005;
  c.walking_height_ki = ki;
  c.walking_max_height_correction_m = max_correction;
  c.walking_settle_s = 1.0;
  return c;
}

// The crouchState angle that puts the pelvis at height @p h [m] (bisection on fb's own measure).
double crouchAngleFor(PostureFeedback& fb, double h) {
  double lo = 0.0, hi = 1.2;
  for (int i = 0; i < 60; ++i) {
    const double mid = 0.5 * (lo + hi);
    double hm = 0.0;
    fb.pelvisHeight(crouchState(mid), &hm);
    (hm > h ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

TEST(PostureFeedback, HeightIsThePelvisAboveTheLowerSoleInTheWorld) {
  HeightFixture hf;
  PostureFeedbackConfig c;
  c.enabled = true;
  c.height_ki = 1.0;
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {0.45, 0.85}, 0.78, hf.legs, hf.idx);
  // Independent check on the same chains: the sole of the zero pose in B.
  gco::LegKinematics kin(hf.legs);
  Eigen::Isometry3d X_BS;
  ASSERT_TRUE(kin.forward(Foot::kLeft, gco::LegVector::Zero(), &X_BS));
  double h0 = 0.0, h1 = 0.0, h_tilt = 0.0;
  ASSERT_TRUE(fb.pelvisHeight(crouchState(0.0), &h0));
  EXPECT_NEAR(h0, -X_BS.translation().z(), 1e-9);
  EXPECT_GT(h0, 0.6);
  ASSERT_TRUE(fb.pelvisHeight(crouchState(0.4), &h1));
  EXPECT_LT(h1, h0 - 0.03) << "a crouch lowers the pelvis";
  // The pelvis pitched 0.3 rad on straight legs: the soles swing out and rise in W, so the height
  // is the sole's W z, not its B z.
  ASSERT_TRUE(fb.pelvisHeight(uprightState(0.3, 0.0), &h_tilt));
  EXPECT_LT(h_tilt, h0 - 0.01);
  // One of the right leg's joints not finite: no height.
  LowState bad = crouchState(0.2);
  bad.motors[static_cast<std::size_t>(jointIndex("right_knee_joint"))].q = std::nan("");
  EXPECT_FALSE(fb.pelvisHeight(bad, &h1));
  // Off (height_ki 0): no height is measured and the command's height passes unchanged.
  PostureFeedbackConfig off = c;
  off.height_ki = 0.0;
  PostureFeedback fb_off(off, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3});
  EXPECT_FALSE(fb_off.pelvisHeight(crouchState(0.2), &h1));
  EXPECT_EQ(fb_off.update({0.0, 0.0, 0.62}, {}, crouchState(0.2), 0.01).height, 0.62);
  // On without leg chains: a setup error.
  EXPECT_THROW(PostureFeedback(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {0.45, 0.85}, 0.78), ConfigError);
}

TEST(PostureFeedback, HeightClosesTheLoopWithinItsBoundsAndNeverStraightensBeyondStanding) {
  HeightFixture hf;
  PostureFeedbackConfig c;
  c.enabled = true;
  c.height_ki = 1.0;
  c.max_height_correction_m = 0.03;
  gco::LegKinematics kin(hf.legs);
  Eigen::Isometry3d X_BS;
  ASSERT_TRUE(kin.forward(Foot::kLeft, gco::LegVector::Zero(), &X_BS));
  const double h0 = -X_BS.translation().z();  // straight legs
  const double standing = h0 - 0.01;
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {0.45, 0.85}, standing, hf.legs, hf.idx);
  auto angleFor = [&](double h) { return crouchAngleFor(fb, h); };
  // A robot that crouches 85 % as deep as it is told (the actor stopped 1.6 cm short of 0.62 m).
  double a = 0.0;
  auto run = [&](double u_h, const VelocityCommand& v, int ticks) {
    for (int k = 0; k < ticks; ++k) {
      const PostureCommand& out = fb.update({0.0, 0.0, u_h}, v, crouchState(a), 0.01);
      const double a_target = angleFor(standing - 0.85 * (standing - out.height));
      a += 0.01 / 0.3 * (a_target - a);
    }
  };
  const double u1 = standing - 0.10;
  // While the crouch is new (height_settle_s, 1 s) the lag is by design: nothing integrates.
  run(u1, {}, 90);
  EXPECT_EQ(fb.heightCorrection(), 0.0);
  run(u1, {}, 1500);
  double h = 0.0;
  ASSERT_TRUE(fb.pelvisHeight(crouchState(a), &h));
  EXPECT_NEAR(h, u1, 0.002) << "the crouch reaches the commanded height";
  EXPECT_NEAR(fb.heightCorrection(), -0.10 * 0.15 / 0.85, 0.002);
  EXPECT_NEAR(fb.command().height, u1 + fb.heightCorrection(), 1e-12);
  EXPECT_NEAR(fb.measuredHeight(), h, 0.002);
  // A deeper crouch needs more than max_height_correction_m: the correction stops at the bound.
  run(standing - 0.25, {}, 1500);
  EXPECT_NEAR(fb.heightCorrection(), -0.03, 1e-12);
  // Walking: no integration, the correction decays.
  run(u1, {0.3, 0.0, 0.0}, 500);
  EXPECT_LT(std::fabs(fb.heightCorrection()), 1e-3);
  // Told to stand while standing 1 cm below the standing height: never straightened beyond it.
  a = angleFor(standing - 0.01);
  for (int k = 0; k < 1000; ++k) fb.update({0.0, 0.0, standing}, {}, crouchState(a), 0.01);
  EXPECT_EQ(fb.heightCorrection(), 0.0);
  EXPECT_EQ(fb.command().height, standing);
  // Per tick with the height on: no allocation.
  std::size_t n = 0;
  const LowState crouched = crouchState(0.3);
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 200; ++k) fb.update({0.0, 0.0, 0.65}, {}, crouched, 0.01);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
  EXPECT_LT(fb.heightCorrection(), 0.0);
}

// A walk that starts from a crouched stand below the walking floor, with the standing height integrator lowering
// the command (the robot stands 2 cm high): as the walk starts the floor's bound (never below the command there)
// takes effect in one tick. The applied correction follows at kWalkingHeightCorrectionRate (0.1 m/s), so the
// height command moves by at most 1 mm per 10 ms tick; before that rate it stepped by the whole standing
// correction, 5 mm (the SIL's height reference at 0.644 m/s: docs/controller.md "Walking height correction").
TEST(PostureFeedback, WalkingHeightDoesNotStepTheCommandAsAWalkStartsBelowTheFloor) {
  HeightFixture hf;
  const PostureFeedbackConfig c = walkingHeightConfig(3.0, 0.04);
  const double standing = hf.standingHeight();
  const double floor = standing - 0.12;
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {standing - 0.20, 0.85}, standing, hf.legs, hf.idx,
                     floor);
  const double u = floor - 0.04;  // told to crouch below the floor
  const LowState high = crouchState(crouchAngleFor(fb, u + 0.02));
  for (int k = 0; k < 400; ++k) fb.update({0.0, 0.0, u}, {}, high, 0.01);
  ASSERT_NEAR(fb.heightCorrection(), -c.max_height_correction_m, 1e-6) << "the standing correction lowers, at its bound";
  double max_step = 0.0, before = fb.command().height;
  for (int k = 0; k < 50; ++k) {
    const double h = fb.update({0.0, 0.0, u}, {0.3, 0.0, 0.0}, high, 0.01).height;
    max_step = std::max(max_step, std::fabs(h - before));
    before = h;
  }
  EXPECT_GE(fb.command().height, u - 1e-9) << "the floor's bound holds, once the correction has moved: not below the command";
  EXPECT_LE(max_step, PostureFeedback::kWalkingHeightCorrectionRate * 0.01 + 1e-12) << "no step in the height command";
  EXPECT_GT(max_step, 0.5 * PostureFeedback::kWalkingHeightCorrectionRate * 0.01) << "the correction was released";
}

TEST(PostureFeedback, WalkingHeightClosesTheLoopAboveTheWalkingFloorAndLetsGoAtTheStop) {
  HeightFixture hf;
  const PostureFeedbackConfig c = walkingHeightConfig(1.0, 0.04);
  const double standing = hf.standingHeight();
  const double floor = standing - 0.12;  // the shaper's walking floor
  PostureFeedback fb(c, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {standing - 0.16, 0.85}, standing, hf.legs, hf.idx,
                     floor);
  auto angleFor = [&](double h) { return crouchAngleFor(fb, h); };
  // A robot that walks 75 % as deep as it is told (N24b walked −0.5 m/s at 0.70 m at 0.729), with
  // a 2 cm bob at 2 Hz on top (the gait), and stands where it is told.
  double a = 0.0, t = 0.0, max_step = 0.0;
  auto run = [&](double u_h, const VelocityCommand& v, int ticks) {
    for (int k = 0; k < ticks; ++k) {
      const double before = fb.command().height;
      const PostureCommand& out = fb.update({0.0, 0.0, u_h}, v, crouchState(a), 0.01);
      if (k > 0) max_step = std::max(max_step, std::fabs(out.height - before));
      const bool walking = v.vx != 0.0 || v.vy != 0.0 || v.wz != 0.0;
      const double depth = (walking ? 0.75 : 1.0) * (standing - out.height);
      const double bob = walking ? 0.01 * std::sin(2.0 * M_PI * 2.0 * t) : 0.0;
      a += 0.01 / 0.3 * (angleFor(standing - depth + bob) - a);
      t += 0.01;
    }
  };
  const VelocityCommand walk{-0.4, 0.0, 0.0};
  const double u1 = standing - 0.08;
  run(u1, {}, 300);  // crouched, standing: reaches it
  // Walking: nothing integrates while the walk is new (walking_settle_s).
  run(u1, walk, 90);
  EXPECT_EQ(fb.walkingHeightCorrection(), 0.0);
  run(u1, walk, 2500);
  EXPECT_NEAR(fb.measuredHeight(), u1, 0.006) << "the walk reaches the commanded height (within its bob)";
  EXPECT_NEAR(fb.walkingHeightCorrection(), -0.08 * 0.25 / 0.75, 0.004);
  EXPECT_NEAR(fb.command().height, u1 + fb.heightCorrection(), 1e-12);
  // Walking 1 cm above the floor: the correction stops at the floor, and the integrator does not wind up.
  const double u2 = floor + 0.01;
  run(u2, walk, 2500);
  EXPECT_NEAR(fb.command().height, floor, 1e-9);
  EXPECT_NEAR(fb.walkingHeightCorrection(), -0.01, 1e-9);
  // The stop: the walking correction decays (decay_time_s), continuously, never below the floor.
  max_step = 0.0;
  run(u2, {}, 10);
  EXPECT_GE(fb.command().height, floor - 1e-12);
  run(u2, {}, 290);
  EXPECT_LT(std::fabs(fb.walkingHeightCorrection()), 1e-3);
  EXPECT_LT(max_step, 0.01 * 0.04 / c.decay_time_s + 1e-6) << "no step in the height command at the stop";
  // Tilted beyond max_tilt_rad while walking: the walking correction decays instead of integrating.
  run(u1, walk, 1500);
  const double before_tilt = fb.walkingHeightCorrection();
  ASSERT_LT(before_tilt, -0.01);
  LowState tilted = uprightState(0.8, 0.0);
  for (int k = 0; k < 300; ++k) fb.update({0.0, 0.0, u1}, walk, tilted, 0.01);
  EXPECT_LT(std::fabs(fb.walkingHeightCorrection()), 0.1 * std::fabs(before_tilt));
  // Per tick walking: no allocation.
  std::size_t n = 0;
  const LowState crouched = crouchState(0.3);
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 200; ++k) fb.update({0.0, 0.0, u1}, walk, crouched, 0.01);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
  // Off (walking_height_ki 0, the default): walking leaves the height command alone.
  PostureFeedbackConfig off = c;
  off.walking_height_ki = 0.0;
  PostureFeedback fb_off(off, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {standing - 0.16, 0.85}, standing, hf.legs,
                         hf.idx, floor);
  for (int k = 0; k < 500; ++k) fb_off.update({0.0, 0.0, u1}, walk, crouchState(0.2), 0.01);
  EXPECT_EQ(fb_off.command().height, u1);
  // On without leg chains: a setup error naming the key.
  PostureFeedbackConfig walk_only = c;
  walk_only.height_ki = 0.0;
  try {
    PostureFeedback bad(walk_only, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, {0.45, 0.85}, 0.78);
    ADD_FAILURE() << "expected ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("walking_height_ki"), std::string::npos) << e.what();
  }
}

TEST(PostureFeedback, WalkingHeightBelowTheFloorBringsAHighWalkerDownToTheFloorAndNoFurther) {
  HeightFixture hf;
  const PostureFeedbackConfig c = walkingHeightConfig(3.0, 0.06);
  const double standing = hf.standingHeight();
  const double floor = standing - 0.10;  // the shaper's walking floor
  const std::array<double, 2> height_range{standing - 0.17, 0.85};
  // A robot that walks 4 cm above the height it is told (finetune_n24b/F0a: told 0.66 m, 0.679-0.715)
  // with a 2 cm bob at 2 Hz (the gait), and stands where it is told.
  struct Walker {
    PostureFeedback fb;
    double a = 0.0, t = 0.0, max_step = 0.0, lowest = 1.0;
  };
  auto make = [&](double below) {
    PostureFeedbackConfig cfg = c;
    cfg.walking_below_floor_m = below;
    return Walker{PostureFeedback(cfg, test::g1Robot(), {-0.3, 0.6}, {-0.3, 0.3}, height_range, standing, hf.legs,
                                  hf.idx, floor)};
  };
  auto run = [&](Walker& w, double u_h, const VelocityCommand& v, int ticks) {
    for (int k = 0; k < ticks; ++k) {
      const double before = w.fb.command().height;
      const PostureCommand& out = w.fb.update({0.0, 0.0, u_h}, v, crouchState(w.a), 0.01);
      if (k > 0) w.max_step = std::max(w.max_step, std::fabs(out.height - before));
      w.lowest = std::min(w.lowest, out.height);
      const bool walking = v.vx != 0.0 || v.vy != 0.0 || v.wz != 0.0;
      const double h = walking ? out.height + 0.04 + 0.01 * std::sin(2.0 * M_PI * 2.0 * w.t) : out.height;
      w.a += 0.01 / 0.3 * (crouchAngleFor(w.fb, h) - w.a);
      w.t += 0.01;
    }
  };
  const VelocityCommand walk{-0.4, 0.0, 0.0};
  // Told to walk at the floor: without the margin the command stops at the floor and the pelvis 4 cm above it.
  Walker at_floor = make(0.0);
  run(at_floor, floor, {}, 300);
  run(at_floor, floor, walk, 3000);
  EXPECT_NEAR(at_floor.fb.command().height, floor, 1e-9);
  EXPECT_NEAR(at_floor.fb.measuredHeight(), floor + 0.04, 0.006);
  // A margin of 3 cm: the command goes 3 cm below the floor, the pelvis comes to 1 cm above it.
  Walker part = make(0.03);
  run(part, floor, {}, 300);
  run(part, floor, walk, 3000);
  EXPECT_NEAR(part.fb.command().height, floor - 0.03, 1e-9);
  EXPECT_NEAR(part.fb.measuredHeight(), floor + 0.01, 0.006);
  // A margin of 5 cm, more than this walker needs: the pelvis comes to the floor, and the command
  // settles where that takes (4 cm below), not at the bound: the integrator's target is the floor.
  Walker full = make(0.05);
  run(full, floor, {}, 300);
  run(full, floor, walk, 3000);
  EXPECT_NEAR(full.fb.measuredHeight(), floor, 0.006);
  EXPECT_NEAR(full.fb.command().height, floor - 0.04, 0.006);
  EXPECT_GT(full.lowest, floor - 0.05 - 1e-9) << "never beyond the margin";
  // Walking above the floor with that margin: the command goes no lower than the walker needs.
  run(full, floor + 0.03, walk, 3000);
  EXPECT_NEAR(full.fb.measuredHeight(), floor + 0.03, 0.006);
  // Back at the floor, then the stop: the correction decays at decay_time_s, the command back up to
  // the floor without a step.
  run(full, floor, walk, 3000);
  full.max_step = 0.0;
  run(full, floor, {}, 10);
  EXPECT_LT(full.fb.command().height, floor - 0.03) << "no jump back to the floor at the stop";
  run(full, floor, {}, 400);
  EXPECT_NEAR(full.fb.command().height, floor, 0.002);
  EXPECT_LT(full.max_step, 0.01 * 0.06 / c.decay_time_s + 1e-6) << "no step in the height command at the stop";
  // Per tick walking below the floor: no allocation.
  std::size_t n = 0;
  const LowState crouched = crouchState(0.3);
  {
    test::AllocationGuard guard;
    for (int k = 0; k < 200; ++k) full.fb.update({0.0, 0.0, floor}, walk, crouched, 0.01);
    n = guard.count();
  }
  EXPECT_EQ(n, 0u);
}

// Config errors (unknown keys, ranges naming the field): test/bad_input/test_bad_input.cpp ctrl_velocity_feedback_*.


BaseVelocityEstimate estimateOf(double vx, double vy, double wz) {
  BaseVelocityEstimate e;
  e.valid = true;
  e.stance_feet = 1;
  e.v_x = vx;
  e.v_y = vy;
  e.yaw_rate = wz;
  return e;
}

UpsetGuardConfig guardConfig() {
  UpsetGuardConfig g;
  g.enabled = true;
  g.max_error = {0.8, 0.4, 0.7};
  g.trigger_s = 0.7;
  g.settle_velocity = 0.15;
  g.settle_s = 1.0;
  g.rearm_band = 0.05;
  return g;
}

TEST(UpsetGuard, LatchesOnlyAfterAnAxisStaysOffItsCommandForTriggerS) {
  UpsetGuard guard(guardConfig());
  const VelocityCommand u{1.0, 0.0, 0.0};
  const double dt = 0.01;
  // Lagging a walk's start (0.7 m/s short of v_x, within its 0.8 bound) never trips it.
  for (int k = 0; k < 500; ++k) EXPECT_FALSE(guard.update(u, u, estimateOf(0.3, 0.0, 0.0), dt));
  // Sideways at 0.5 m/s (beyond v_y's 0.4) for 0.6 s, then back on track: a break resets the run.
  for (int k = 0; k < 60; ++k) EXPECT_FALSE(guard.update(u, u, estimateOf(0.9, 0.5, 0.0), dt));
  EXPECT_FALSE(guard.update(u, u, estimateOf(0.9, 0.1, 0.0), dt));
  // Invalid estimates neither count nor break a run.
  int k = 0;
  for (; k < 69; ++k) ASSERT_FALSE(guard.update(u, u, estimateOf(0.9, 0.5, 0.0), dt)) << k;
  BaseVelocityEstimate invalid = estimateOf(0.9, 5.0, 0.0);
  invalid.valid = false;
  for (int j = 0; j < 50; ++j) EXPECT_FALSE(guard.update(u, u, invalid, dt));
  EXPECT_TRUE(guard.update(u, u, estimateOf(0.9, 0.5, 0.0), dt)) << "0.70 s off its command";
  EXPECT_TRUE(guard.latched());
  EXPECT_EQ(guard.upsets(), 1u);
  // The yaw axis alone trips it too (a fresh guard).
  UpsetGuard spin(guardConfig());
  bool tripped = false;
  for (int j = 0; j < 80 && !tripped; ++j) tripped = spin.update({0.0, 0.0, 0.0}, {}, estimateOf(0.0, 0.0, -0.9), dt);
  EXPECT_TRUE(tripped);
}

TEST(UpsetGuard, HoldsUntilTheRobotSettlesAndTheOperatorLetsGo) {
  UpsetGuard guard(guardConfig());
  const double dt = 0.01;
  const VelocityCommand walk{1.0, 0.0, 0.0};
  for (int k = 0; k < 70; ++k) guard.update(walk, walk, estimateOf(-0.5, 0.0, 0.0), dt);
  ASSERT_TRUE(guard.latched());
  // Settled for 2 s, but the operator still commands 1.0 m/s: held.
  for (int k = 0; k < 200; ++k) EXPECT_TRUE(guard.update({}, walk, estimateOf(0.02, 0.0, 0.0), dt));
  // The operator lets go while the robot still moves: held until it has settled for settle_s.
  for (int k = 0; k < 50; ++k) EXPECT_TRUE(guard.update({}, {}, estimateOf(0.4, 0.0, 0.0), dt));
  int released_at = -1;
  for (int k = 0; k < 300 && released_at < 0; ++k)
    if (!guard.update({}, {}, estimateOf(0.05, -0.05, 0.1), dt)) released_at = k;
  EXPECT_NEAR(released_at, 100, 1) << "released after 1.0 s settled with the stick neutral";
  EXPECT_FALSE(guard.latched());
  EXPECT_EQ(guard.upsets(), 1u);
  // Disabled: never holds.
  UpsetGuardConfig off = guardConfig();
  off.enabled = false;
  UpsetGuard none(off);
  for (int k = 0; k < 300; ++k) EXPECT_FALSE(none.update(walk, walk, estimateOf(-1.0, 1.0, 2.0), dt));
}

TEST(UpsetGuard, TheShaperTakesTheVelocityToZeroContinuouslyAndCountsTheUpset) {
  CommandLimits limits;
  limits.max_acceleration = {1.0, 1.0, 2.0};
  CommandShaper shaper(limits);
  UpsetGuard guard(guardConfig());
  CommandSample s;
  s.command.vx = 1.0;
  const double dt = 0.01;
  double prev_vx = 0.0;
  bool held_once = false;
  test::AllocationGuard alloc;
  for (int k = 0; k < 600; ++k) {
    const double t = k * dt;
    s.velocity_time = s.posture_time = t;
    // The robot follows for 2 s, then staggers sideways at 0.8 m/s while told to walk on.
    const BaseVelocityEstimate est = t < 2.0 ? estimateOf(shaper.velocity().vx, 0.0, 0.0) : estimateOf(0.2, 0.8, 0.0);
    const bool hold = guard.update(shaper.velocity(), shaper.target(), est, dt);
    held_once = held_once || hold;
    shaper.update(s, t, dt, hold);
    ASSERT_LE(std::fabs(shaper.velocity().vx - prev_vx), limits.max_acceleration[0] * dt + 1e-12) << "at " << t;
    prev_vx = shaper.velocity().vx;
  }
  EXPECT_EQ(alloc.count(), 0u);
  EXPECT_TRUE(held_once);
  EXPECT_EQ(shaper.velocity().vx, 0.0) << "held at zero while the operator still commands 1.0 m/s";
  EXPECT_EQ(shaper.target().vx, 1.0) << "the operator's command is kept (the re-arm looks at it)";
  EXPECT_EQ(shaper.counters().upsets, 1u);
  EXPECT_GT(shaper.counters().upset_hold_ticks, 200u);
}

TEST(UpsetGuard, UprightStraightensTheTorsoWhileLatchedAndGivesThePostureBackContinuously) {
  // Told to walk bent 0.3 rad with a 0.1 rad lean, crouched to 0.66 m: the robot runs on at
  // 1.2 m/s while told to stop, the guard latches; later it settles and the operator lets go.
  CommandLimits limits;
  limits.max_acceleration = {1.0, 1.0, 2.0};
  limits.posture_rate = 0.5;
  const double dt = 0.01;
  auto run = [&](bool upright, std::vector<PostureCommand>* trace, std::vector<bool>* held) {
    CommandShaper shaper(limits);
    UpsetGuard guard(guardConfig());
    CommandSample s;
    s.command.pitch = 0.3;
    s.command.roll = 0.1;
    s.command.height = 0.66;
    for (int k = 0; k < 900; ++k) {
      const double t = k * dt;
      s.velocity_time = s.posture_time = t;
      s.command.vx = t < 2.0 ? 0.6 : 0.0;
      const BaseVelocityEstimate est = t < 2.0 ? estimateOf(shaper.velocity().vx, 0.0, 0.0)
                                      : t < 5.0 ? estimateOf(1.2, 0.0, 0.0) : estimateOf(0.0, 0.0, 0.0);
      const bool hold = guard.update(shaper.velocity(), shaper.target(), est, dt);
      shaper.update(s, t, dt, hold, hold && upright);
      trace->push_back(shaper.posture());
      held->push_back(hold);
    }
  };
  std::vector<PostureCommand> on, off;
  std::vector<bool> held_on, held_off;
  on.reserve(900);
  off.reserve(900);
  run(true, &on, &held_on);
  run(false, &off, &held_off);
  ASSERT_EQ(held_on, held_off) << "upright does not change when the guard latches or releases";
  int first = -1, last = -1;
  for (int k = 0; k < 900; ++k)
    if (held_on[static_cast<std::size_t>(k)]) last = k, first = first < 0 ? k : first;
  ASSERT_GT(first, 200) << "latched in the run-on";
  ASSERT_LT(last, 850) << "released after settling";
  double min_pitch_held = 1.0;
  for (int k = 1; k < 900; ++k) {
    const auto i = static_cast<std::size_t>(k);
    // Continuous: the posture slew bounds every step, latched or not.
    ASSERT_LE(std::fabs(on[i].pitch - on[i - 1].pitch), limits.posture_rate * dt + 1e-12) << k;
    ASSERT_LE(std::fabs(on[i].roll - on[i - 1].roll), limits.posture_rate * dt + 1e-12) << k;
    EXPECT_EQ(on[i].height, off[i].height) << "the height goes on: " << k;
    if (!held_on[i] && k < first) {
      EXPECT_EQ(on[i].pitch, off[i].pitch) << k;
    }
    if (held_on[i]) min_pitch_held = std::min(min_pitch_held, on[i].pitch);
  }
  EXPECT_EQ(min_pitch_held, 0.0) << "upright within the hold (0.6 s at 0.5 rad/s)";
  EXPECT_EQ(on[static_cast<std::size_t>(last)].roll, 0.0);
  for (int k = first; k <= last; ++k) EXPECT_NEAR(off[static_cast<std::size_t>(k)].pitch, 0.3, 1e-12) << "without: bent on";
  EXPECT_NEAR(on.back().pitch, 0.3, 1e-12) << "released: back to the operator's bend";
  EXPECT_NEAR(on.back().roll, 0.1, 1e-12);
}

TEST(UpsetGuard, ConfigRefusesValuesOutOfRangeNamingTheField) {
  UpsetGuardConfig g = guardConfig();
  EXPECT_EQ(g.validate(), "");
  g.max_error[1] = 0.0;
  EXPECT_NE(g.validate().find("max_error[1] (v_y"), std::string::npos) << g.validate();
  g = guardConfig();
  g.trigger_s = 6.0;
  EXPECT_NE(g.validate().find("trigger_s"), std::string::npos);
  g = guardConfig();
  g.rearm_band = -0.1;
  EXPECT_NE(g.validate().find("rearm_band"), std::string::npos);
  EXPECT_THROW(UpsetGuard{g}, ConfigError);
  // The guard runs on the velocity feedback's estimate: enabled without it is refused.
  VelocityFeedbackConfig f;
  f.enabled = false;
  f.upset_guard = guardConfig();
  EXPECT_NE(f.validate().find("upset_guard.enabled: needs velocity_feedback.enabled"), std::string::npos) << f.validate();
  f.enabled = true;
  EXPECT_EQ(f.validate(), "");
}

}  // namespace
}  // namespace pmg
