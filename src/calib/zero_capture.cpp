// Zero-point calibration protocol: YAML, and the capture through a pmg::HalBackend.
#include <array>
#include <cmath>
#include <cstdlib>
#include <stdexcept>

#include <fmt/format.h>

#include "pmg/calib/zero_calibration.hpp"
#include "pmg/hal/hal_stack.hpp"
#include "pmg/common/mujoco_model.hpp"
#include "pmg/common/robot_config.hpp"
#include "pmg/common/yaml_archive.hpp"
#include "pmg/hal/backend.hpp"

namespace pmg::calib {
namespace {

using pmg::Foot;

void check(bool ok, const std::string& src, const std::string& field, double v, const std::string& range) {
  if (!ok) throw ConfigError(fmt::format("{}: zero_calibration.{} = {}: expected {}", src, field, v, range));
}

Eigen::Vector3d upFromQuat(const std::array<double, 4>& wxyz) {
  const Eigen::Quaterniond q(wxyz[0], wxyz[1], wxyz[2], wxyz[3]);
  return q.normalized().toRotationMatrix().transpose() * Eigen::Vector3d::UnitZ();  // R_WI^T e_z
}

double angleBetween(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

Eigen::Isometry3d flatten(const Eigen::Isometry3d& X) {
  const Eigen::Vector3d x = X.linear().col(0);
  Eigen::Isometry3d F = Eigen::Isometry3d::Identity();
  F.linear() = Eigen::AngleAxisd(std::atan2(x.y(), x.x()), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  F.translation() = Eigen::Vector3d(X.translation().x(), X.translation().y(), 0.0);
  return F;
}

}  // namespace

void ZeroProtocol::validate() const {
  const std::string& s = source;
  check(std::isfinite(settle_s) && settle_s >= 0.2 && settle_s <= 30, s, "settle_s", settle_s, "in [0.2, 30] s");
  check(std::isfinite(move_s) && move_s >= 0.2 && move_s <= 30, s, "move_s", move_s, "in [0.2, 30] s");
  check(std::isfinite(hold_s) && hold_s >= 0.1 && hold_s <= 30, s, "hold_s", hold_s, "in [0.1, 30] s");
  check(std::isfinite(average_s) && average_s > 0 && average_s <= hold_s, s, "average_s", average_s,
        "in (0, hold_s] s");
  check(std::isfinite(max_gyro_rms) && max_gyro_rms > 0, s, "max_gyro_rms", max_gyro_rms, "> 0 rad/s");
  check(std::isfinite(max_tilt_spread) && max_tilt_spread > 0, s, "max_tilt_spread", max_tilt_spread, "> 0 rad");
  check(std::isfinite(max_tilt_error) && max_tilt_error > 0, s, "max_tilt_error", max_tilt_error, "> 0 rad");
  check(std::isfinite(max_home_drift) && max_home_drift > 0, s, "max_home_drift", max_home_drift, "> 0 rad");
  check(std::isfinite(max_shift_m) && max_shift_m > 0 && max_shift_m <= 0.3, s, "max_shift_m", max_shift_m,
        "in (0, 0.3] m");
  check(std::isfinite(max_angle_rad) && max_angle_rad > 0 && max_angle_rad <= 0.6, s, "max_angle_rad",
        max_angle_rad, "in (0, 0.6] rad");
  check(!poses.empty(), s, "poses", 0, "a non-empty list");
  for (const auto* g : {&leg_kp, &leg_kd}) {
    const char* f = g == &leg_kp ? "leg_kp" : "leg_kd";
    check(g->empty() || g->size() == 6, s, f, static_cast<double>(g->size()), "6 entries (chain order) or none");
    for (double v : *g) check(std::isfinite(v) && v >= 0 && v <= 2000, s, f, v, "each in [0, 2000]");
  }
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const ZeroPoseSpec& p = poses[k];
    const std::string f = fmt::format("poses[{}] ({})", k, p.name);
    check(p.dp.allFinite() && p.dp.norm() <= max_shift_m, s, f + ".dp", p.dp.norm(), "finite, |dp| <= max_shift_m");
    check(p.rpy.allFinite() && p.rpy.cwiseAbs().maxCoeff() <= max_angle_rad, s, f + ".rpy",
          p.rpy.cwiseAbs().maxCoeff(), "finite, each |angle| <= max_angle_rad");
  }
}

namespace {

// The protocol file format (config/calib/zero_poses_g1.yaml), read with pmg::yaml.
struct PoseEntry {
  std::string name;
  std::array<double, 3> dp{0.0, 0.0, 0.0};
  std::array<double, 3> rpy{0.0, 0.0, 0.0};
  template <class A>
  void Serialize(A* a) {
    a->Visit("name", &name, "pose name (default: pose<k>)");
    a->Visit("dp", &dp, "pelvis shift [x, y, z] in the stance frame [m]");
    a->Visit("rpy", &rpy, "pelvis roll, pitch, yaw about the stance axes [rad]");
  }
};

struct ProtocolSection {
  ZeroProtocol* p = nullptr;
  std::vector<PoseEntry> poses;
  template <class A>
  void Serialize(A* a) {
    a->Visit("settle_s", &p->settle_s, "[s]");
    a->Visit("move_s", &p->move_s, "[s]");
    a->Visit("hold_s", &p->hold_s, "[s]");
    a->Visit("average_s", &p->average_s, "[s]");
    a->Visit("max_gyro_rms", &p->max_gyro_rms, "[rad/s]");
    a->Visit("max_tilt_spread", &p->max_tilt_spread, "[rad]");
    a->Visit("max_tilt_error", &p->max_tilt_error, "[rad]");
    a->Visit("max_home_drift", &p->max_home_drift, "[rad]");
    a->Visit("max_shift_m", &p->max_shift_m, "[m]");
    a->Visit("max_angle_rad", &p->max_angle_rad, "[rad]");
    a->Visit("leg_kp", &p->leg_kp, "6 leg gains, chain order [N m/rad]");
    a->Visit("leg_kd", &p->leg_kd, "6 leg gains, chain order [N m s/rad]");
    a->Visit("start_from_current", &p->start_from_current, "hold the readings found at start");
    a->Visit("flatten_feet", &p->flatten_feet, "plan with the home's feet flattened");
    a->Visit("poses", &poses, "the poses", yaml::kRequired);
  }
};

struct ProtocolFile {
  ProtocolSection zero_calibration;
  template <class A>
  void Serialize(A* a) {
    a->Visit("zero_calibration", &zero_calibration, "the capture protocol", yaml::kRequired);
  }
};

}  // namespace

ZeroProtocol loadZeroProtocol(const std::string& path) {
  ZeroProtocol p;
  p.source = path;
  ProtocolFile f;
  f.zero_calibration.p = &p;
  yaml::readYaml(yaml::loadYamlDocument(path), &f);
  const auto& poses = f.zero_calibration.poses;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    ZeroPoseSpec s;
    s.name = poses[k].name.empty() ? fmt::format("pose{}", k) : poses[k].name;
    s.dp = Eigen::Vector3d(poses[k].dp[0], poses[k].dp[1], poses[k].dp[2]);
    s.rpy = Eigen::Vector3d(poses[k].rpy[0], poses[k].rpy[1], poses[k].rpy[2]);
    p.poses.push_back(s);
  }
  p.validate();
  return p;
}

std::array<int, kZeroJoints> zeroJointIndices(const gco::LegModel& model, const RobotConfig& robot) {
  const gco::LegJointIndex idx = model.jointIndices(robot.jointNames());
  std::array<int, kZeroJoints> out{};
  for (int f = 0; f < 2; ++f)
    for (int j = 0; j < gco::kLegDofs; ++j)
      out[static_cast<std::size_t>(gco::kLegDofs * f + j)] = idx[static_cast<std::size_t>(f)][static_cast<std::size_t>(j)];
  return out;
}

std::vector<ZeroSample> synthesizeZeroSamples(std::shared_ptr<const gco::LegModel> model, const RobotConfig& robot,
                                              const ZeroProtocol& protocol, const ZeroVector& z_true) {
  const std::array<int, kZeroJoints> idx = zeroJointIndices(*model, robot);
  gco::LegKinematics kin(model);
  const Eigen::VectorXd q0 = robot.defaultPose();
  gco::LegVector ql, qr;
  for (int j = 0; j < 6; ++j) {
    ql(j) = q0(idx[static_cast<std::size_t>(j)]);
    qr(j) = q0(idx[static_cast<std::size_t>(6 + j)]);
  }
  Eigen::Isometry3d X_BL, X_BR;
  if (!kin.forward(Foot::kLeft, ql, &X_BL) || !kin.forward(Foot::kRight, qr, &X_BR))
    throw std::runtime_error("synthesizeZeroSamples: forward kinematics of the default pose failed");
  // M: level, at the middle of the soles; the pelvis level above it; the feet flattened.
  Eigen::Isometry3d X_MB0 = Eigen::Isometry3d::Identity();
  X_MB0.translation() = -0.5 * (X_BL.translation() + X_BR.translation());
  const Eigen::Isometry3d X_ML = flatten(X_MB0 * X_BL), X_MR = flatten(X_MB0 * X_BR);
  std::vector<ZeroSample> out;
  for (const ZeroPoseSpec& pose : protocol.poses) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = (Eigen::AngleAxisd(pose.rpy.z(), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(pose.rpy.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(pose.rpy.x(), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix();
    X.translation() = X_MB0.translation() + pose.dp;
    gco::LegVector sl, sr;
    const double el = kin.inverse(Foot::kLeft, X.inverse() * X_ML, ql, &sl);
    const double er = kin.inverse(Foot::kRight, X.inverse() * X_MR, qr, &sr);
    if (!(el < 1e-6) || !(er < 1e-6))
      throw std::runtime_error(fmt::format("synthesizeZeroSamples: pose '{}': IK error {:.2g} / {:.2g}", pose.name, el, er));
    ZeroSample s;
    s.name = pose.name;
    s.readings.head<6>() = sl;
    s.readings.tail<6>() = sr;
    s.readings -= z_true;
    s.up_I = X.linear().transpose() * Eigen::Vector3d::UnitZ();
    out.push_back(s);
  }
  return out;
}

ZeroCapture captureZeroPoses(HalBackend& backend, const RobotConfig& robot, std::shared_ptr<const gco::LegModel> model,
                             const ZeroProtocol& protocol, const std::function<void(const std::string&)>& log,
                             const ZeroVector& z_guess, const Eigen::VectorXd& start_targets) {
  protocol.validate();
  const auto say = [&](const std::string& s) {
    if (log) log(s);
  };
  const int n = static_cast<int>(robot.numJoints());
  if (n > kMaxMotors) throw std::runtime_error("captureZeroPoses: robot has more joints than kMaxMotors");
  const std::array<int, kZeroJoints> idx = zeroJointIndices(*model, robot);
  gco::LegKinematics kin(model);
  const double dt = backend.cyclePeriod();
  Eigen::VectorXd kp = robot.kp(), kd = robot.kd();
  for (int j = 0; j < kZeroJoints; ++j) {
    const int i = idx[static_cast<std::size_t>(j)];
    if (!protocol.leg_kp.empty()) kp(i) = protocol.leg_kp[static_cast<std::size_t>(j % 6)];
    if (!protocol.leg_kd.empty()) kd(i) = protocol.leg_kd[static_cast<std::size_t>(j % 6)];
  }
  Eigen::VectorXd target = robot.defaultPose();
  LowCommand cmd;
  LowState st;
  cmd.num_motors = n;
  ZeroCapture out;
  double t0 = -1.0;
  const auto exchange = [&](bool gains) {
    for (int i = 0; i < n; ++i) {
      pmg::MotorCommand& m = cmd.motors[static_cast<std::size_t>(i)];
      m.q = target(i);
      m.qd = 0.0;
      m.kp = gains ? kp(i) : 0.0;
      m.kd = gains ? kd(i) : 0.0;
      m.tau_ff = 0.0;
    }
    ++cmd.sequence;
    if (backend.exchange(cmd, st) == BackendStatus::kFault)
      throw std::runtime_error(fmt::format("captureZeroPoses: backend '{}' fault at t = {:.3f} s", backend.name(), st.time));
    if (st.mode == Mode::kDamping)  // the HAL supervisor (makeHalStack) stopped the motors
      throw std::runtime_error(fmt::format("captureZeroPoses: the HAL supervisor latched damping at t = {:.3f} s: {}",
                                           st.time, toString(st.fault)));
    if (t0 < 0) t0 = st.time;
    out.duration_s = st.time - t0;
  };
  const auto readings = [&] {
    ZeroVector r;
    for (int j = 0; j < kZeroJoints; ++j) r(j) = st.motors[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])].q;
    return r;
  };
  const auto cycles = [&](double s) { return std::max(1, static_cast<int>(std::lround(s / dt))); };

  // Hold `seconds` at the current target; average over the last average_s.
  const auto hold = [&](double seconds, ZeroSample* sample) {
    const int total = cycles(seconds), avg = std::min(total, cycles(protocol.average_s));
    ZeroVector sum = ZeroVector::Zero();
    Eigen::Vector3d up_sum = Eigen::Vector3d::Zero();
    double w2 = 0.0;
    std::vector<Eigen::Vector3d> ups;
    ups.reserve(static_cast<std::size_t>(avg));
    for (int c = 0; c < total; ++c) {
      exchange(true);
      if (c >= total - avg) {
        sum += readings();
        const Eigen::Vector3d u = upFromQuat(st.imu.quat_wxyz);
        up_sum += u;
        ups.push_back(u);
        w2 += st.imu.gyro[0] * st.imu.gyro[0] + st.imu.gyro[1] * st.imu.gyro[1] + st.imu.gyro[2] * st.imu.gyro[2];
      }
    }
    sample->readings = sum / avg;
    sample->up_I = up_sum.normalized();
    sample->gyro_rms = std::sqrt(w2 / avg);
    sample->tilt_spread = 0.0;
    for (const auto& u : ups) sample->tilt_spread = std::max(sample->tilt_spread, angleBetween(u, sample->up_I));
  };

  // Ramp from the current readings (or the held start_targets) to the default pose, or keep holding them
  // (start_from_current); then settle.
  if (start_targets.size() != 0 && start_targets.size() != n)
    throw std::invalid_argument(fmt::format("captureZeroPoses: start_targets has {} entries, expected 0 or {}",
                                            start_targets.size(), n));
  const bool held = start_targets.size() == n;
  if (held) target = start_targets;
  exchange(held);
  {
    Eigen::VectorXd start(n);
    for (int i = 0; i < n; ++i) start(i) = held ? start_targets(i) : st.motors[static_cast<std::size_t>(i)].q;
    const Eigen::VectorXd goal = protocol.start_from_current ? start : robot.defaultPose();
    const int steps = cycles(protocol.move_s);
    for (int c = 1; c <= steps; ++c) {
      const double s = 0.5 - 0.5 * std::cos(M_PI * c / steps);
      target = start + s * (goal - start);
      exchange(true);
    }
  }
  ZeroSample home;
  hold(protocol.settle_s, &home);

  // Stance frame M from the home pose on the nominal model (z = 0), levelled by the IMU.
  Eigen::Isometry3d X_BL, X_BR;
  const ZeroVector q_home = home.readings + z_guess;  // model angles of the home pose
  if (!kin.forward(Foot::kLeft, q_home.head<6>(), &X_BL) || !kin.forward(Foot::kRight, q_home.tail<6>(), &X_BR))
    throw std::runtime_error("captureZeroPoses: forward kinematics of the home pose failed");
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();  // W: level, yaw of B
  X_WB.linear() = Eigen::Quaterniond::FromTwoVectors(home.up_I, Eigen::Vector3d::UnitZ()).toRotationMatrix();  // IMU = pelvis axes
  const Eigen::Isometry3d X_WL = X_WB * X_BL, X_WR = X_WB * X_BR;
  const Eigen::Vector3d xl = X_WL.linear().col(0), xr = X_WR.linear().col(0);
  const double yaw_m = std::atan2(xl.y() + xr.y(), xl.x() + xr.x());
  Eigen::Isometry3d X_WM = Eigen::Isometry3d::Identity();
  X_WM.linear() = Eigen::AngleAxisd(yaw_m, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  X_WM.translation() = 0.5 * (X_WL.translation() + X_WR.translation());
  const bool keep_feet = !protocol.flatten_feet;
  const Eigen::Isometry3d X_ML = keep_feet ? X_WM.inverse() * X_WL : flatten(X_WM.inverse() * X_WL);
  const Eigen::Isometry3d X_MR = keep_feet ? X_WM.inverse() * X_WR : flatten(X_WM.inverse() * X_WR);
  const Eigen::Isometry3d X_MB0 = X_WM.inverse() * X_WB;  // measured home pelvis pose in M
  const double yaw0 = std::atan2(X_MB0.linear()(1, 0), X_MB0.linear()(0, 0));  // home: pelvis level, this yaw
  say(fmt::format("home: feet {:.3f} m apart, pelvis {:.3f} m above the soles, tilt {:.4f} rad",
                  (X_MR.translation() - X_ML.translation()).norm(), X_MB0.translation().z(),
                  angleBetween(home.up_I, Eigen::Vector3d::UnitZ())));

  gco::LegVector ql = q_home.head<6>(), qr = q_home.tail<6>();  // model angles
  // Puts the leg targets at the IK solution for pelvis pose X_MB (feet at X_ML, X_MR).
  const auto setPelvis = [&](const Eigen::Isometry3d& X_MB, const std::string& pose_name) {
    gco::LegVector sl, sr;
    const double el = kin.inverse(Foot::kLeft, X_MB.inverse() * X_ML, ql, &sl);
    const double er = kin.inverse(Foot::kRight, X_MB.inverse() * X_MR, qr, &sr);
    if (!(el < 1e-4) || !(er < 1e-4))
      throw std::runtime_error(fmt::format("captureZeroPoses: pose '{}' ({}): leg IK error {:.2g} / {:.2g} (left/right): "
                                           "unreachable or outside the joint limits", pose_name, protocol.source, el, er));
    ql = sl;
    qr = sr;
    for (int j = 0; j < 6; ++j) {
      target(idx[static_cast<std::size_t>(j)]) = ql(j) - z_guess(j);  // reading space
      target(idx[static_cast<std::size_t>(6 + j)]) = qr(j) - z_guess(6 + j);
    }
  };
  const auto moveTo = [&](const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, const std::string& pose_name) {
    const Eigen::Quaterniond qa(from.linear()), qb(to.linear());
    const int steps = cycles(protocol.move_s);
    for (int c = 1; c <= steps; ++c) {
      const double s = 0.5 - 0.5 * std::cos(M_PI * c / steps);
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.linear() = qa.slerp(s, qb).toRotationMatrix();
      X.translation() = (1 - s) * from.translation() + s * to.translation();
      setPelvis(X, pose_name);
      exchange(true);
    }
  };

  // Whole-body centre of mass of the nominal model (MuJoCo kinematics of the robot's MJCF), in M, for
  // the leg targets of pelvis pose X_MB; the other joints at their default.
  const MjModelPtr mj = loadMujocoModel(robot.mjcf_path);
  const MjDataPtr md(mj_makeData(mj.get()));
  std::array<int, kZeroJoints> qadr{};
  for (int j = 0; j < kZeroJoints; ++j) {
    const std::string& jn = robot.joints[static_cast<std::size_t>(idx[static_cast<std::size_t>(j)])].name;
    const int id = mj_name2id(mj.get(), mjOBJ_JOINT, jn.c_str());
    if (id < 0) throw std::runtime_error("captureZeroPoses: joint " + jn + " not in " + robot.mjcf_path);
    qadr[static_cast<std::size_t>(j)] = mj->jnt_qposadr[id];
  }
  for (std::size_t i = 0; i < robot.numJoints(); ++i) {
    const int id = mj_name2id(mj.get(), mjOBJ_JOINT, robot.joints[i].name.c_str());
    if (id >= 0) md->qpos[mj->jnt_qposadr[id]] = robot.joints[i].default_position;
  }
  const auto comOf = [&](const Eigen::Isometry3d& X_MB) {
    const Eigen::Quaterniond qb(X_MB.linear());
    for (int a = 0; a < 3; ++a) md->qpos[a] = X_MB.translation()(a);
    md->qpos[3] = qb.w();
    md->qpos[4] = qb.x();
    md->qpos[5] = qb.y();
    md->qpos[6] = qb.z();
    for (int j = 0; j < 6; ++j) {
      md->qpos[qadr[static_cast<std::size_t>(j)]] = ql(j);
      md->qpos[qadr[static_cast<std::size_t>(6 + j)]] = qr(j);
    }
    mj_kinematics(mj.get(), md.get());
    mj_comPos(mj.get(), md.get());
    return Eigen::Vector3d(md->subtree_com[0], md->subtree_com[1], md->subtree_com[2]);
  };
  // Pelvis pose of a protocol pose: orientation and height from the spec, horizontal position such that
  // the centre of mass is dp.xy from the middle of the soles (static balance on the nominal model).
  const Eigen::Vector3d sole_mid = 0.5 * (X_ML.translation() + X_MR.translation());
  const auto planPose = [&](const ZeroPoseSpec& pose) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = (Eigen::AngleAxisd(pose.rpy.z(), Eigen::Vector3d::UnitZ()) *
                  Eigen::AngleAxisd(pose.rpy.y(), Eigen::Vector3d::UnitY()) *
                  Eigen::AngleAxisd(pose.rpy.x(), Eigen::Vector3d::UnitX()))
                     .toRotationMatrix() *
                 Eigen::AngleAxisd(yaw0, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X.translation() = X_MB0.translation() + pose.dp;
    const gco::LegVector sl = ql, sr = qr;
    const Eigen::VectorXd saved = target;
    for (int iter = 0; iter < 20; ++iter) {
      setPelvis(X, pose.name);
      const Eigen::Vector2d err = (sole_mid + pose.dp).head<2>() - comOf(X).head<2>();
      X.translation().head<2>() += err;
      if (err.norm() < 1e-4) break;
    }
    ql = sl;  // planning must not change the warm start or the targets of the motion
    qr = sr;
    target = saved;
    return X;
  };

  // Home: pelvis level at the measured height, centre of mass over the middle of the soles; reached by a
  // joint-space move from the default-pose targets (both ends satisfy the closed chain on the nominal model).
  say(fmt::format("home: centre of mass {:.4f} {:.4f} m from the middle of the soles (nominal model, default pose)",
                  (comOf(X_MB0) - sole_mid).x(), (comOf(X_MB0) - sole_mid).y()));
  const Eigen::Isometry3d X_home = planPose(ZeroPoseSpec{"home", Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()});
  {
    const Eigen::VectorXd from = target;
    setPelvis(X_home, "home");
    const Eigen::VectorXd to = target;
    const int steps = cycles(protocol.move_s);
    for (int c = 1; c <= steps; ++c) {
      target = from + (0.5 - 0.5 * std::cos(M_PI * c / steps)) * (to - from);
      exchange(true);
    }
  }
  ZeroSample home2;
  hold(protocol.settle_s, &home2);
  const std::array<double, 4> home_quat = st.imu.quat_wxyz;
  const Eigen::Vector3d home_base(st.base_position[0], st.base_position[1], st.base_position[2]);
  Eigen::Isometry3d current = X_home;
  for (const ZeroPoseSpec& pose : protocol.poses) {
    const Eigen::Isometry3d X = planPose(pose);
    moveTo(current, X, pose.name);
    current = X;
    ZeroSample s;
    s.name = pose.name;
    hold(protocol.hold_s, &s);
    // Tipped? Compare the measured pelvis tilt with the planned one.
    const Eigen::Vector3d up_plan = X.linear().transpose() * Eigen::Vector3d::UnitZ();
    const double tilt_err = angleBetween(up_plan, s.up_I);
    if (tilt_err > protocol.max_tilt_error)
      throw std::runtime_error(fmt::format("captureZeroPoses: pose '{}': IMU tilt is {:.3f} rad from the planned pelvis "
                                           "tilt (max_tilt_error = {}): the robot tipped; aborted",
                                           pose.name, tilt_err, protocol.max_tilt_error));
    if (s.gyro_rms > protocol.max_gyro_rms) {
      s.valid = false;
      s.reason = fmt::format("moving: gyro RMS {:.4f} rad/s > max_gyro_rms {}", s.gyro_rms, protocol.max_gyro_rms);
    } else if (s.tilt_spread > protocol.max_tilt_spread) {
      s.valid = false;
      s.reason = fmt::format("moving: tilt spread {:.4f} rad > max_tilt_spread {}", s.tilt_spread,
                             protocol.max_tilt_spread);
    }
    say(fmt::format("pose {:<14} tilt {:.4f} rad (planned {:.4f}), gyro RMS {:.5f} rad/s{}", pose.name,
                    angleBetween(s.up_I, Eigen::Vector3d::UnitZ()),
                    angleBetween(up_plan, Eigen::Vector3d::UnitZ()), s.gyro_rms,
                    s.valid ? "" : "  REFUSED: " + s.reason));
    out.samples.push_back(s);
  }
  // Back home: the IMU orientation (with yaw) must be where it started, else the feet moved.
  moveTo(current, X_home, "home");
  ZeroSample end;
  hold(protocol.settle_s, &end);
  const Eigen::Quaterniond qa(home_quat[0], home_quat[1], home_quat[2], home_quat[3]);
  const Eigen::Quaterniond qb(st.imu.quat_wxyz[0], st.imu.quat_wxyz[1], st.imu.quat_wxyz[2], st.imu.quat_wxyz[3]);
  out.home_drift = qa.normalized().angularDistance(qb.normalized());
  out.feet_moved = out.home_drift > protocol.max_home_drift;
  if (st.base_truth_valid)
    out.max_base_drift_m =
        (Eigen::Vector3d(st.base_position[0], st.base_position[1], st.base_position[2]) - home_base).norm();
  out.final_targets = target;
  say(fmt::format("home again: orientation drift {:.5f} rad{}", out.home_drift,
                  out.feet_moved ? "  FEET MOVED (max_home_drift exceeded)" : ""));
  return out;
}

void declareProtocolGains(const ZeroProtocol& protocol, const RobotConfig& robot, const gco::LegModel& model,
                          HalStackConfig& stack) {
  const Eigen::VectorXd kp = robot.kp(), kd = robot.kd();
  stack.stand_kp.assign(kp.data(), kp.data() + kp.size());
  stack.stand_kd.assign(kd.data(), kd.data() + kd.size());
  const std::array<int, kZeroJoints> idx = zeroJointIndices(model, robot);
  for (int j = 0; j < kZeroJoints; ++j) {
    const auto i = static_cast<std::size_t>(idx[static_cast<std::size_t>(j)]);
    if (!protocol.leg_kp.empty()) stack.stand_kp[i] = protocol.leg_kp[static_cast<std::size_t>(j % 6)];
    if (!protocol.leg_kd.empty()) stack.stand_kd[i] = protocol.leg_kd[static_cast<std::size_t>(j % 6)];
  }
  stack.soft_stand_duration_s = 0.2;
}

}  // namespace pmg::calib
