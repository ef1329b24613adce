#include "pmg/motion/clip_builder.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <fmt/format.h>

#include "pmg/clips/clip_transforms.hpp"
#include "pmg/clips/clip_validation.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace pmg::motion {
namespace {

const char* footName(Foot f) { return f == Foot::kLeft ? "left" : "right"; }

/// Flips runs shorter than min_frames (non-circular sequence), repeated until stable.
void debounce(std::vector<bool>& flags, int min_frames) {
  const int F = static_cast<int>(flags.size());
  for (int pass = 0; pass < 4; ++pass) {
    bool changed = false;
    int start = 0;
    while (start < F) {
      int end = start;
      while (end < F && flags[static_cast<std::size_t>(end)] == flags[static_cast<std::size_t>(start)]) ++end;
      // Runs touching the ends of the motion are kept (they may continue outside the recording).
      if (start > 0 && end < F && end - start < min_frames) {
        for (int k = start; k < end; ++k) flags[static_cast<std::size_t>(k)] = !flags[static_cast<std::size_t>(k)];
        changed = true;
      }
      start = end;
    }
    if (!changed) break;
  }
}

/// Hampel filter on columns [first, first + count) of x: a value farther than
/// max(3 · 1.4826 · MAD, 0.05) from the median of its 5-sample window is replaced by that median.
void despike(Eigen::MatrixXd& x, Eigen::Index first, Eigen::Index count) {
  const Eigen::Index R = x.rows();
  if (R < 5) return;
  const Eigen::MatrixXd in = x;
  for (Eigen::Index c = first; c < first + count; ++c)
    for (Eigen::Index r = 0; r < R; ++r) {
      const Eigen::Index a = std::max<Eigen::Index>(0, std::min(r - 2, R - 5));
      double w[5], dev[5];
      for (int i = 0; i < 5; ++i) w[i] = in(a + i, c);
      std::sort(w, w + 5);
      const double med = w[2];
      for (int i = 0; i < 5; ++i) dev[i] = std::abs(w[i] - med);
      std::sort(dev, dev + 5);
      if (std::abs(in(r, c) - med) > std::max(3.0 * 1.4826 * dev[2], 0.05)) x(r, c) = med;
    }
}

Eigen::Vector3d rotationLog(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

}  // namespace

void ContactOptions::validate() const {
  if (!(height_threshold > 0.0)) throw std::invalid_argument(fmt::format("ContactOptions.height_threshold = {}: expected > 0 [m]", height_threshold));
  if (!(speed_threshold > 0.0)) throw std::invalid_argument(fmt::format("ContactOptions.speed_threshold = {}: expected > 0 [m/s]", speed_threshold));
  if (min_frames < 1) throw std::invalid_argument(fmt::format("ContactOptions.min_frames = {}: expected >= 1", min_frames));
}

void DynamicClipOptions::validate() const {
  if (name.empty()) throw std::invalid_argument("DynamicClipOptions.name: expected a non-empty clip name");
  if (num_samples < 8) throw std::invalid_argument(fmt::format("DynamicClipOptions.num_samples = {}: expected >= 8", num_samples));
  if (!(smoothing_sigma >= 0.0) || !std::isfinite(smoothing_sigma))
    throw std::invalid_argument(fmt::format("DynamicClipOptions.smoothing_sigma = {}: expected finite >= 0 [s]", smoothing_sigma));
  if (closing == CycleClosing::kInSwing) {
    for (std::size_t f = 0; f < kNumFeet; ++f)
      if (leg_joints[f].empty())
        throw std::invalid_argument(fmt::format("DynamicClipOptions.leg_joints[{}]: empty; closing kInSwing needs the {} leg's joints",
                                                f, footName(static_cast<Foot>(f))));
    for (int j : leg_joints[0])
      if (std::find(leg_joints[1].begin(), leg_joints[1].end(), j) != leg_joints[1].end())
        throw std::invalid_argument(fmt::format("DynamicClipOptions.leg_joints: joint {} is in both legs", j));
  }
}

ContactSequence detectContacts(const RobotMotion& motion, const ContactOptions& options) {
  options.validate();
  const int F = motion.numFrames();
  if (F < 2 || motion.p_WS[0].rows() != F || motion.p_WS[1].rows() != F)
    throw std::invalid_argument("detectContacts: motion has no foot tracks (call placeOnGround first) or < 2 frames");
  ContactSequence out(static_cast<std::size_t>(F));
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const Eigen::MatrixXd& p = motion.p_WS[f];
    std::vector<bool> flags(static_cast<std::size_t>(F));
    for (int k = 0; k < F; ++k) {
      const int a = std::max(0, k - 1), b = std::min(F - 1, k + 1);
      const double speed = (p.row(b).head<2>() - p.row(a).head<2>()).norm() * motion.fps / static_cast<double>(b - a);
      flags[static_cast<std::size_t>(k)] = p(k, 2) < options.height_threshold && speed < options.speed_threshold;
    }
    debounce(flags, options.min_frames);
    for (int k = 0; k < F; ++k) out[static_cast<std::size_t>(k)][f] = flags[static_cast<std::size_t>(k)];
  }
  return out;
}

std::vector<int> findContactEvents(const ContactSequence& contacts, Foot foot, ContactEvent event, int search_begin,
                                   int search_end) {
  std::vector<int> events;
  const auto f = static_cast<std::size_t>(foot);
  const int F = static_cast<int>(contacts.size());
  for (int k = std::max(1, search_begin); k < std::min(F, search_end); ++k) {
    const bool now = contacts[static_cast<std::size_t>(k)][f], before = contacts[static_cast<std::size_t>(k - 1)][f];
    if ((event == ContactEvent::kTouchdown && now && !before) || (event == ContactEvent::kLiftoff && !now && before))
      events.push_back(k);
  }
  return events;
}

CycleWindow findGaitCycle(const ContactSequence& contacts, Foot foot, ContactEvent event, int search_begin,
                          int search_end) {
  const std::vector<int> ev = findContactEvents(contacts, foot, event, search_begin, search_end);
  if (ev.size() < 2)
    throw std::runtime_error(fmt::format("findGaitCycle: found {} {} events of the {} foot in frames [{}, {}): expected >= 2",
                                         ev.size(), event == ContactEvent::kTouchdown ? "touchdown" : "liftoff",
                                         footName(foot), search_begin, search_end));
  return {ev[0], ev[1]};
}

FootContact contactModel(const std::vector<bool>& in_contact) {
  const int M = static_cast<int>(in_contact.size());
  const int count = static_cast<int>(std::count(in_contact.begin(), in_contact.end(), true));
  if (M == 0 || count == 0) return {0.0, 0.0};
  if (count == M) return {0.5, 0.5};
  int best_start = 0, best_len = 0;
  for (int s = 0; s < M; ++s) {
    if (!in_contact[static_cast<std::size_t>(s)] || in_contact[static_cast<std::size_t>((s + M - 1) % M)]) continue;
    int len = 0;
    while (len < M && in_contact[static_cast<std::size_t>((s + len) % M)]) ++len;
    if (len > best_len) {
      best_len = len;
      best_start = s;
    }
  }
  double mu = (best_start + 0.5 * (best_len - 1)) / M;
  mu -= std::floor(mu);
  if (mu >= 1.0) mu = 0.0;
  return {mu, std::min(0.5, 0.5 * best_len / M)};
}

Eigen::MatrixXd circularGaussianSmooth(const Eigen::MatrixXd& x, double sigma_samples, double truncate_sigmas) {
  if (sigma_samples <= 0.0) return x;
  const Eigen::Index M = x.rows();
  const int half = static_cast<int>(std::ceil(truncate_sigmas * sigma_samples));
  std::vector<double> w(static_cast<std::size_t>(2 * half + 1));
  double sum = 0.0;
  for (int j = -half; j <= half; ++j) {
    w[static_cast<std::size_t>(j + half)] = std::exp(-0.5 * j * j / (sigma_samples * sigma_samples));
    sum += w[static_cast<std::size_t>(j + half)];
  }
  Eigen::MatrixXd y = Eigen::MatrixXd::Zero(M, x.cols());
  for (Eigen::Index k = 0; k < M; ++k)
    for (int j = -half; j <= half; ++j) {
      const Eigen::Index i = ((k + j) % M + M) % M;
      y.row(k) += (w[static_cast<std::size_t>(j + half)] / sum) * x.row(i);
    }
  return y;
}

Eigen::MatrixXd resamplePeriodic(const Eigen::MatrixXd& x, int num_samples) {
  const Eigen::Index M = x.rows();
  Eigen::MatrixXd y(num_samples, x.cols());
  for (int k = 0; k < num_samples; ++k) {
    const double u = static_cast<double>(k) * static_cast<double>(M) / num_samples;
    const Eigen::Index i = static_cast<Eigen::Index>(std::floor(u));
    const double t = u - static_cast<double>(i);
    auto row = [&](Eigen::Index j) { return x.row(((j % M) + M) % M); };
    const Eigen::RowVectorXd p0 = row(i - 1), p1 = row(i), p2 = row(i + 1), p3 = row(i + 2);
    y.row(k) = 0.5 * (2.0 * p1 + (p2 - p0) * t + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t * t +
                      (3.0 * p1 - p0 - 3.0 * p2 + p3) * t * t * t);
  }
  return y;
}

Eigen::MatrixXd periodicDerivative(const Eigen::MatrixXd& x, double period) {
  const Eigen::Index N = x.rows();
  Eigen::MatrixXd d(N, x.cols());
  const double h = period / static_cast<double>(N);
  for (Eigen::Index k = 0; k < N; ++k) d.row(k) = (x.row((k + 1) % N) - x.row((k + N - 1) % N)) / (2.0 * h);
  return d;
}

DynamicClip buildDynamicClip(const RobotMotion& motion, const ContactSequence& contacts, const CycleWindow& window,
                             const RobotConfig& robot, const DynamicClipOptions& options) {
  options.validate();
  const int F = motion.numFrames();
  const int M = window.end - window.begin;
  if (window.begin < 0 || window.end >= F || M < 4)
    throw std::invalid_argument(fmt::format("buildDynamicClip({}): cycle window [{}, {}] invalid for a motion of {} frames "
                                            "(need 0 <= begin, end < frames, end - begin >= 4)",
                                            options.name, window.begin, window.end, F));
  if (static_cast<int>(contacts.size()) != F) throw std::invalid_argument("buildDynamicClip: contact sequence length != frames");
  const Eigen::Index n = motion.q.cols();
  if (n != static_cast<Eigen::Index>(robot.numJoints())) throw std::invalid_argument("buildDynamicClip: joint count != robot config");
  const double dt = 1.0 / motion.fps;

  // Columns: q (n) | v_H (3) | omega_H (3) | base height (1), rows: frames begin..end.
  const Eigen::Index d = n + 7;
  Eigen::MatrixXd X(M + 1, d);
  for (int r = 0; r <= M; ++r) {
    const int k = window.begin + r;
    const int a = std::max(0, k - 1), b = std::min(F - 1, k + 1);
    const double span = (b - a) * dt;
    const Eigen::Matrix3d Ra = motion.R_WB[static_cast<std::size_t>(a)].toRotationMatrix();
    const Eigen::Matrix3d Rb = motion.R_WB[static_cast<std::size_t>(b)].toRotationMatrix();
    const Eigen::Vector3d v_W = (motion.p_WB.row(b) - motion.p_WB.row(a)).transpose() / span;
    const Eigen::Vector3d w_W = rotationLog(Rb * Ra.transpose()) / span;
    const double psi = headingOf(motion.R_WB[static_cast<std::size_t>(k)]);
    const Eigen::Matrix3d R_HW = Eigen::AngleAxisd(-psi, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    X.row(r).head(n) = motion.q.row(k);
    X.row(r).segment<3>(n) = (R_HW * v_W).transpose();
    X.row(r).segment<3>(n + 3) = (R_HW * w_W).transpose();
    X(r, n + 6) = motion.p_WB(k, 2);
  }
  // Base velocities: single-frame spikes (root jumps in the source, e.g. the 7° yaw step at frame
  // 19 of humanoid3d_walk.txt) replaced by the local median (Hampel filter).
  despike(X, n, 6);
  // Mean command over the cycle (before closing).
  const Eigen::Index cmd_col = options.axis == CommandAxis::kForward ? n : options.axis == CommandAxis::kLateral ? n + 1 : n + 5;
  const double mean_cmd = X.col(cmd_col).head(M).mean();
  if (std::abs(mean_cmd) < 1e-3)
    throw std::runtime_error(fmt::format("buildDynamicClip({}): mean {} command over the cycle is {:.2e}: expected |x̄| >= 1e-3",
                                         options.name, toString(options.axis), mean_cmd));

  // Close the cycle: remove the drift with a zero-mean ramp g(r) − mean(g), g(0) = 0, g(M) = 1, so
  // row M equals row 0 and the cycle mean (x̄, mean posture) is unchanged; then drop row M.
  // Column ramps: linear, or (kInSwing) for a leg's joints the raised-cosine swing ramp of its foot.
  // (The linear ramp keeps its closed-form mean, (M − 1) / 2M, so the kLinearRamp clips are
  // bit-identical to those built before kInSwing existed.)
  Eigen::MatrixXd ramp(M, d);
  for (int r = 0; r < M; ++r) ramp.row(r).setConstant(static_cast<double>(r) / M - 0.5 * (M - 1) / M);
  if (options.closing == CycleClosing::kInSwing) {
    // Zero-mean ramp whose rate is sin²(π (r − s + ½) / L) over each run [s, s + L) of the window
    // (not wrapped) where `up(r)` holds; empty when `up` never holds.
    const auto swingRamp = [&](const auto& up) {
      Eigen::VectorXd rate = Eigen::VectorXd::Zero(M);
      int r = 0;
      while (r < M) {
        if (!up(r)) {
          ++r;
          continue;
        }
        int e = r;
        while (e < M && up(e)) ++e;
        for (int k = r; k < e; ++k) rate(k) = std::pow(std::sin(M_PI * (k - r + 0.5) / (e - r)), 2);
        r = e;
      }
      if (rate.sum() <= 0.0) return Eigen::VectorXd();
      Eigen::VectorXd g(M);
      double acc = 0.0;
      for (int k = 0; k < M; ++k) {
        g(k) = acc;
        acc += rate(k) / rate.sum();
      }
      return Eigen::VectorXd(g.array() - g.mean());
    };
    const auto inSwing = [&](std::size_t f, int r) { return !contacts[static_cast<std::size_t>(window.begin + r)][f]; };
    for (std::size_t f = 0; f < kNumFeet; ++f) {
      const Eigen::VectorXd g = swingRamp([&](int r) { return inSwing(f, r); });
      if (g.size() == 0) continue;  // no swing: linear ramp
      for (int j : options.leg_joints[f]) {
        if (j < 0 || j >= n)
          throw std::invalid_argument(fmt::format("buildDynamicClip({}): leg_joints[{}] holds joint {}: expected [0, {})", options.name, f, j, n));
        ramp.col(j) = g;
      }
    }
    // Base velocities and height: corrected in single support only. In double support the base
    // yaw rate and velocity are what keeps both planted soles still relative to each other, and
    // no base correction (GCO) can undo a change there; in single support GCO re-fits them to the
    // stance foot anyway.
    const Eigen::VectorXd g_base = swingRamp([&](int r) { return inSwing(0, r) || inSwing(1, r); });
    if (g_base.size() > 0)
      for (Eigen::Index c = n; c < d; ++c) ramp.col(c) = g_base;
  }
  Eigen::MatrixXd P(M, d);
  const Eigen::RowVectorXd drift = X.row(M) - X.row(0);
  for (int r = 0; r < M; ++r) P.row(r) = X.row(r) - ramp.row(r).cwiseProduct(drift);
  // Clamp to the joint limits before smoothing (the ramp can push a joint that rests on its limit
  // past it); the convex Gaussian then rounds the approach to the limit instead of a clamp kink.
  {
    const Eigen::VectorXd lo = robot.lowerLimits(), hi = robot.upperLimits();
    for (int r = 0; r < M; ++r)
      for (Eigen::Index j = 0; j < n; ++j) P(r, j) = std::min(hi(j), std::max(lo(j), P(r, j)));
  }
  P = circularGaussianSmooth(P, options.smoothing_sigma * motion.fps);
  // A closed cycle returns to the same pelvis height, roll and pitch: v_z, ω_x and ω_y have zero
  // mean (their raw means come from capture drift and from the despiked root jumps).
  for (const Eigen::Index c : {n + 2, n + 3, n + 4}) P.col(c).array() -= P.col(c).mean();

  std::vector<std::array<bool, kNumFeet>> cyc(contacts.begin() + window.begin, contacts.begin() + window.end);
  int shift = 0;
  if (options.align_on_left_touchdown) {
    for (int r = 0; r < M; ++r) {
      const bool now = cyc[static_cast<std::size_t>(r)][0], before = cyc[static_cast<std::size_t>((r + M - 1) % M)][0];
      if (now && !before) {
        shift = r;
        break;
      }
    }
  }
  Eigen::MatrixXd S(M, d);
  std::vector<std::array<bool, kNumFeet>> cyc_shifted(static_cast<std::size_t>(M));
  for (int r = 0; r < M; ++r) {
    S.row(r) = P.row((r + shift) % M);
    cyc_shifted[static_cast<std::size_t>(r)] = cyc[static_cast<std::size_t>((r + shift) % M)];
  }
  const Eigen::MatrixXd Y = resamplePeriodic(S, options.num_samples);

  DynamicClip clip;
  clip.name = options.name;
  clip.axis = options.axis;
  clip.direction = mean_cmd > 0.0 ? 1 : -1;
  clip.nominal_scale = std::abs(mean_cmd);
  clip.period = M * dt;
  clip.q = Y.leftCols(n);
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  for (Eigen::Index k = 0; k < clip.q.rows(); ++k)
    for (Eigen::Index j = 0; j < n; ++j) clip.q(k, j) = std::min(upper(j), std::max(lower(j), clip.q(k, j)));
  clip.qd = periodicDerivative(clip.q, clip.period);
  clip.v_base = Y.middleCols(n, 3);
  clip.omega_base = Y.middleCols(n + 3, 3);
  clip.base_height = Y.col(n + 6);
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    std::vector<bool> flags(static_cast<std::size_t>(M));
    for (int r = 0; r < M; ++r) flags[static_cast<std::size_t>(r)] = cyc_shifted[static_cast<std::size_t>(r)][f];
    clip.contact[f] = contactModel(flags);
  }
  clip.meta.robot = robot.name;
  clip.meta.joint_names = robot.jointNames();
  clip.meta.frame_begin = window.begin;
  clip.meta.frame_end = window.end;
  clip.meta.source_fps = motion.fps;
  clip.meta.source_file = motion.source_file;
  return clip;
}

}  // namespace pmg::motion

namespace pmg::motion {

void StaticClipOptions::validate() const {
  if (name.empty()) throw std::invalid_argument("StaticClipOptions.name: expected a non-empty clip name");
  if (num_samples < 2) throw std::invalid_argument(fmt::format("StaticClipOptions.num_samples = {}: expected >= 2", num_samples));
}

Eigen::VectorXd postureValues(const RobotMotion& motion, const KinematicModel& model, PostureAxis axis) {
  const int F = motion.numFrames();
  Eigen::VectorXd v(F);
  if (axis == PostureAxis::kHeight) {
    for (int k = 0; k < F; ++k) v(k) = motion.p_WB(k, 2);
    return v;
  }
  const LimbChain torso = model.chain(model.config().base_link, "torso_link");
  ChainFkWorkspace ws(torso);
  for (int k = 0; k < F; ++k) {
    Eigen::Isometry3d X_BT;
    const Eigen::VectorXd q = motion.q.row(k).transpose();
    if (!ws.tipPose(q, X_BT)) throw std::runtime_error("postureValues: KDL forward kinematics failed");
    const Eigen::Matrix3d R_WB = motion.R_WB[static_cast<std::size_t>(k)].toRotationMatrix();
    const double psi = headingOf(motion.R_WB[static_cast<std::size_t>(k)]);
    const Eigen::Vector3d z_H = Eigen::AngleAxisd(-psi, Eigen::Vector3d::UnitZ()).toRotationMatrix() * R_WB * X_BT.linear().col(2);
    v(k) = axis == PostureAxis::kPitch ? std::atan2(z_H.x(), z_H.z()) : std::atan2(-z_H.y(), z_H.z());
  }
  return v;
}

StaticClip buildStaticClip(const RobotMotion& motion, const Eigen::VectorXd& values, int begin, int end,
                           const RobotConfig& robot, const StaticClipOptions& options) {
  options.validate();
  if (begin < 0 || end >= motion.numFrames() || end <= begin || values.size() != motion.numFrames())
    throw std::invalid_argument(fmt::format("buildStaticClip({}): frames [{}, {}] invalid for {} frames", options.name, begin, end,
                                            motion.numFrames()));
  const double v0 = values(begin), v1 = values(end);
  const double sign = v1 >= v0 ? 1.0 : -1.0;
  if (std::abs(v1 - v0) < 1e-3)
    throw std::invalid_argument(fmt::format("buildStaticClip({}): value changes by {:.2e} only over frames [{}, {}]", options.name,
                                            v1 - v0, begin, end));
  // Monotone (running extreme) value along the segment.
  std::vector<double> mono;
  double best = v0;
  for (int k = begin; k <= end; ++k) {
    best = sign > 0 ? std::max(best, values(k)) : std::min(best, values(k));
    mono.push_back(best);
  }
  const int K = options.num_samples;
  const auto n = motion.q.cols();
  StaticClip c;
  c.name = options.name;
  c.axis = options.axis;
  c.values.resize(K);
  c.q.resize(K, n);
  for (int i = 0; i < K; ++i) {
    const double target = v0 + (v1 - v0) * i / (K - 1);
    std::size_t k = 0;
    while (k + 1 < mono.size() && sign * (mono[k + 1] - target) < 0.0) ++k;
    Eigen::RowVectorXd q = motion.q.row(begin + static_cast<int>(k));
    if (k + 1 < mono.size() && mono[k + 1] != mono[k]) {
      const double a = std::min(1.0, std::max(0.0, (target - mono[k]) / (mono[k + 1] - mono[k])));
      q = (1 - a) * motion.q.row(begin + static_cast<int>(k)) + a * motion.q.row(begin + static_cast<int>(k) + 1);
    }
    const int row = sign > 0 ? i : K - 1 - i;
    c.values(row) = target;
    c.q.row(row) = q;
  }
  c.neutral = v0;
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  for (Eigen::Index i = 0; i < c.q.rows(); ++i)
    for (Eigen::Index j = 0; j < n; ++j) c.q(i, j) = std::min(upper(j), std::max(lower(j), c.q(i, j)));
  c.meta.robot = robot.name;
  c.meta.joint_names = robot.jointNames();
  c.meta.frame_begin = begin;
  c.meta.frame_end = end + 1;
  c.meta.source_fps = motion.fps;
  c.meta.source_file = motion.source_file;
  return c;
}

}  // namespace pmg::motion

namespace pmg::motion {

void RobotContactOptions::validate() const {
  if (!(enter_height > 0.0) || !std::isfinite(enter_height))
    throw std::invalid_argument(fmt::format("RobotContactOptions.enter_height = {}: expected finite > 0 [m]", enter_height));
  if (!(exit_height >= enter_height) || !std::isfinite(exit_height))
    throw std::invalid_argument(
        fmt::format("RobotContactOptions.exit_height = {}: expected finite >= enter_height = {} [m]", exit_height, enter_height));
  if (!(enter_relative_speed > 0.0) || !std::isfinite(enter_relative_speed))
    throw std::invalid_argument(
        fmt::format("RobotContactOptions.enter_relative_speed = {}: expected finite > 0 [m/s]", enter_relative_speed));
  if (!(exit_relative_speed >= enter_relative_speed) || !std::isfinite(exit_relative_speed))
    throw std::invalid_argument(fmt::format(
        "RobotContactOptions.exit_relative_speed = {}: expected finite >= enter_relative_speed = {} [m/s]", exit_relative_speed,
        enter_relative_speed));
}

ClipSoleTracks clipSoleTracks(const DynamicClip& clip, const KinematicModel& model) {
  const Eigen::Index N = clip.q.rows();
  if (clip.q.cols() != static_cast<Eigen::Index>(model.config().numJoints()))
    throw std::invalid_argument(fmt::format("clipSoleTracks({}): clip has {} joints, robot config {}", clip.name, clip.q.cols(),
                                            model.config().numJoints()));
  if (N < 3 || clip.v_base.rows() != N || clip.omega_base.rows() != N || clip.base_height.size() != N || !(clip.period > 0))
    throw std::invalid_argument(fmt::format("clipSoleTracks({}): expected >= 3 samples with matching base tracks and period > 0",
                                            clip.name));
  Eigen::Vector3d p_FS = Eigen::Vector3d::Zero();
  for (const auto& s : g1SolePoints_F()) p_FS += 0.25 * s;
  const LimbChain legs[2] = {model.leftLeg(), model.rightLeg()};
  ChainFkWorkspace ws_left(legs[0]), ws_right(legs[1]);
  ChainFkWorkspace* ws[2] = {&ws_left, &ws_right};
  // Sole centre relative to the pelvis, level pelvis: p_BS = p_HS (H axes), per sample and foot.
  std::array<Eigen::MatrixXd, 2> r{Eigen::MatrixXd(N, 3), Eigen::MatrixXd(N, 3)};
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::VectorXd q = clip.q.row(k).transpose();
    for (int f = 0; f < 2; ++f) {
      Eigen::Isometry3d X_BF;
      if (!ws[f]->tipPose(q, X_BF))
        throw std::runtime_error(fmt::format("clipSoleTracks({}): KDL forward kinematics failed at sample {}", clip.name, k));
      r[static_cast<std::size_t>(f)].row(k) = (X_BF * p_FS).transpose();
    }
  }
  ClipSoleTracks t;
  t.height.resize(N, 2);
  t.speed.resize(N, 2);
  t.relative_speed.resize(N);
  const double h = clip.period / static_cast<double>(N);
  for (Eigen::Index k = 0; k < N; ++k) {
    const double zl = r[0](k, 2), zr = r[1](k, 2), z_ground = std::min(zl, zr);
    const double wz = clip.omega_base(k, 2);
    Eigen::Vector2d v_feet[2];
    for (int f = 0; f < 2; ++f) {
      const Eigen::MatrixXd& rf = r[static_cast<std::size_t>(f)];
      t.height(k, f) = rf(k, 2) - z_ground;
      // v_S = v_B + ω_z e_z × r + d r / dt (H axes), horizontal part.
      const Eigen::Vector2d dr = (rf.row((k + 1) % N).head<2>() - rf.row((k + N - 1) % N).head<2>()).transpose() / (2.0 * h);
      const Eigen::Vector2d v(clip.v_base(k, 0) - wz * rf(k, 1) + dr.x(), clip.v_base(k, 1) + wz * rf(k, 0) + dr.y());
      t.speed(k, f) = v.norm();
      v_feet[f] = v;
    }
    t.relative_speed(k) = (v_feet[0] - v_feet[1]).norm();
  }
  return t;
}

std::array<std::vector<bool>, kNumFeet> robotContactLabels(const ClipSoleTracks& tracks, const RobotContactOptions& options) {
  options.validate();
  const Eigen::Index N = tracks.height.rows();
  if (N == 0 || tracks.height.cols() != 2 || tracks.speed.rows() != N || tracks.relative_speed.size() != N)
    throw std::invalid_argument(fmt::format("robotContactLabels: {} height rows, {} speed rows, {} relative speeds: expected "
                                            "equal sizes > 0 and two feet",
                                            N, tracks.speed.rows(), tracks.relative_speed.size()));
  std::array<std::vector<bool>, kNumFeet> out{std::vector<bool>(static_cast<std::size_t>(N)),
                                              std::vector<bool>(static_cast<std::size_t>(N))};
  std::array<bool, kNumFeet> c{false, false};
  std::array<long, kNumFeet> since{0, 0};  // sample index (over both laps) where the stance started
  for (int lap = 0; lap < 2; ++lap)
    for (Eigen::Index k = 0; k < N; ++k) {
      const long t = lap * static_cast<long>(N) + static_cast<long>(k);
      const double s_rel = tracks.relative_speed(k);
      for (int f = 0; f < 2; ++f)  // rule 1
        if (c[static_cast<std::size_t>(f)] && !(tracks.height(k, f) < options.exit_height)) c[static_cast<std::size_t>(f)] = false;
      if (c[0] && c[1] && !(s_rel < options.exit_relative_speed)) {  // rule 2: the older stance ends
        const std::size_t older = since[0] <= since[1] ? 0 : 1;
        c[older] = false;
      }
      for (int f = 0; f < 2; ++f) {  // rule 3
        const auto F = static_cast<std::size_t>(f);
        if (c[F] || !(tracks.height(k, f) < options.enter_height)) continue;
        if (!c[1 - F] || s_rel < options.enter_relative_speed) {
          c[F] = true;
          since[F] = t;
        }
      }
      if (lap == 1)
        for (std::size_t f = 0; f < kNumFeet; ++f) out[f][static_cast<std::size_t>(k)] = c[f];
    }
  return out;
}

void relabelContactsFromRobotFeet(DynamicClip& clip, const KinematicModel& model, const RobotContactOptions& options) {
  options.validate();
  const ClipSoleTracks tracks = clipSoleTracks(clip, model);
  const auto labels = robotContactLabels(tracks, options);
  for (std::size_t f = 0; f < kNumFeet; ++f) {
    const std::vector<bool>& flags = labels[f];
    if (std::none_of(flags.begin(), flags.end(), [](bool b) { return b; }))
      throw std::runtime_error(fmt::format("relabelContactsFromRobotFeet({}): the {} sole is never in contact (never within {} m "
                                           "of the lower sole)",
                                           clip.name, footName(static_cast<Foot>(f)), options.enter_height));
    clip.contact[f] = contactModel(flags);
  }
  alignPhaseOnLeftTouchdown(clip);  // φ = 0 at the left foot's touchdown, as in every clip
}

void symmetrizeStaticClip(StaticClip& clip, const RobotConfig& robot) {
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  if (clip.q.cols() != n)
    throw std::invalid_argument(fmt::format("symmetrizeStaticClip({}): clip has {} joints, robot config {}", clip.name, clip.q.cols(), n));
  clip.q = 0.5 * (clip.q + mirrorJoints(clip.q, generatorJointSpace(robot)));
}

void symmetrizeGaitClip(DynamicClip& clip, const RobotConfig& robot) {
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  const Eigen::Index N = clip.q.rows();
  if (clip.q.cols() != n || clip.qd.cols() != n || clip.qd.rows() != N)
    throw std::invalid_argument(fmt::format("symmetrizeGaitClip({}): q {}x{}, qd {}x{}; the robot config has {} joints", clip.name,
                                            N, clip.q.cols(), clip.qd.rows(), clip.qd.cols(), n));
  if (N == 0 || N % 2 != 0)
    throw std::invalid_argument(fmt::format("symmetrizeGaitClip({}): {} samples; expected an even number (half a cycle = N/2 samples)",
                                            clip.name, N));
  if (clip.axis != CommandAxis::kForward)
    throw std::invalid_argument(fmt::format("symmetrizeGaitClip({}): axis {}; expected forward (a side-step or a turn is not its own "
                                            "mirror image)", clip.name, toString(clip.axis)));
  if (clip.v_base.rows() != N || clip.omega_base.rows() != N || clip.base_height.size() != N)
    throw std::invalid_argument(fmt::format("symmetrizeGaitClip({}): v_base, omega_base or base_height has not {} rows", clip.name, N));
  DynamicClip half = clip;
  rotateClipPhase(half, N / 2);  // sample k of `half` is sample k + N/2 of the clip
  const GeneratorJointSpace joints = generatorJointSpace(robot);
  clip.q = 0.5 * (clip.q + mirrorJoints(half.q, joints));
  clip.qd = 0.5 * (clip.qd + mirrorJoints(half.qd, joints));
  const Eigen::Vector3d s_v(1.0, -1.0, 1.0), s_w(-1.0, 1.0, -1.0);
  clip.v_base = 0.5 * (clip.v_base + half.v_base * s_v.asDiagonal());
  clip.omega_base = 0.5 * (clip.omega_base + half.omega_base * s_w.asDiagonal());
  clip.base_height = 0.5 * (clip.base_height + half.base_height);
  FootContact& left = clip.contact[static_cast<std::size_t>(Foot::kLeft)];
  const FootContact right = clip.contact[static_cast<std::size_t>(Foot::kRight)];
  const double a = 2.0 * M_PI * left.mu, b = 2.0 * M_PI * (right.mu - 0.5);
  double mu = std::atan2(std::sin(a) + std::sin(b), std::cos(a) + std::cos(b)) / (2.0 * M_PI);
  mu -= std::floor(mu);
  left.mu = mu >= 1.0 ? 0.0 : mu;
  left.sigma = 0.5 * (left.sigma + right.sigma);
  FootContact& r = clip.contact[static_cast<std::size_t>(Foot::kRight)];
  r.sigma = left.sigma;
  r.mu = left.mu + 0.5;
  r.mu -= std::floor(r.mu);
  clip.implied = ImpliedMotionTable{};
}

}  // namespace pmg::motion

namespace pmg::motion {

void keepLegDirections(StaticClip& clip, const KinematicModel& model) {
  const RobotConfig& robot = model.config();
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  if (clip.q.cols() != n)
    throw std::invalid_argument(fmt::format("keepLegDirections({}): clip has {} joints, robot config {}", clip.name, clip.q.cols(), n));
  const std::vector<std::string> names = robot.jointNames();
  auto index = [&](const std::string& joint) {
    const auto it = std::find(names.begin(), names.end(), joint);
    if (it == names.end()) throw std::invalid_argument(fmt::format("keepLegDirections({}): robot has no joint '{}'", clip.name, joint));
    return static_cast<Eigen::Index>(it - names.begin());
  };
  const Eigen::Index hip[2] = {index("left_hip_pitch_joint"), index("right_hip_pitch_joint")};
  const Eigen::Index ankle[2] = {index("left_ankle_pitch_joint"), index("right_ankle_pitch_joint")};
  const LimbChain legs[2] = {model.leftLeg(), model.rightLeg()};
  ChainFkWorkspace ws_left(legs[0]), ws_right(legs[1]);
  ChainFkWorkspace* ws[2] = {&ws_left, &ws_right};
  // Angle of hip → ankle about the pelvis y axis (a rotation +θ about y moves the ankle to −x).
  auto legAngle = [&](int f, const Eigen::VectorXd& q) {
    Eigen::Isometry3d X_BH, X_BF;
    if (!ws[f]->segmentPose(q, 0, X_BH) || !ws[f]->tipPose(q, X_BF))
      throw std::runtime_error(fmt::format("keepLegDirections({}): KDL forward kinematics failed", clip.name));
    const Eigen::Vector3d v = X_BF.translation() - X_BH.translation();
    return std::atan2(-v.x(), -v.z());
  };
  Eigen::Index neutral_row = 0;
  (clip.values.array() - clip.neutral).abs().minCoeff(&neutral_row);
  const Eigen::VectorXd q0 = clip.q.row(neutral_row).transpose();
  const double beta0[2] = {legAngle(0, q0), legAngle(1, q0)};
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  for (Eigen::Index i = 0; i < clip.q.rows(); ++i) {
    Eigen::VectorXd q = clip.q.row(i).transpose();
    for (int f = 0; f < 2; ++f) {
      // Fixed-point iteration: turning the ankle pitch moves the foot link origin (the ankle roll
      // axis sits 18 mm below the ankle pitch axis) a little; converges in a few steps.
      for (int it = 0; it < 50; ++it) {
        const double delta = legAngle(f, q) - beta0[f];
        if (std::abs(delta) < 1e-12) break;
        q(hip[f]) = std::min(upper(hip[f]), std::max(lower(hip[f]), q(hip[f]) - delta));
        q(ankle[f]) = std::min(upper(ankle[f]), std::max(lower(ankle[f]), q(ankle[f]) + delta));
      }
    }
    clip.q.row(i) = q.transpose();
  }
}

}  // namespace pmg::motion

namespace pmg::motion {

void WalkingHeightOptions::validate() const {
  if (!(fraction >= 0.0 && fraction <= 1.0))
    throw std::invalid_argument(fmt::format("WalkingHeightOptions.fraction = {}: expected [0, 1]", fraction));
  if (!(min_knee >= 0.0 && min_knee <= 1.0))
    throw std::invalid_argument(fmt::format("WalkingHeightOptions.min_knee = {} rad: expected [0, 1]", min_knee));
  if (!(smoothing_samples >= 0.0 && smoothing_samples <= 10.0))
    throw std::invalid_argument(
        fmt::format("WalkingHeightOptions.smoothing_samples = {}: expected [0, 10] phase samples", smoothing_samples));
}

namespace {

/// One leg of raiseWalkingHeight: the sole centre's pose in the pelvis frame B, solved over the
/// leg's six joints (Newton, finite-difference Jacobian on the KDL chain).
class LegLengthener {
 public:
  LegLengthener(LimbChain leg, Eigen::Index knee, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const std::string& clip)
      : leg_(std::move(leg)), ws_(leg_), knee_(knee), lower_(lower), upper_(upper), clip_(clip) {
    if (leg_.joint_index.size() != 6)
      throw std::invalid_argument(fmt::format("raiseWalkingHeight({}): leg chain to {} has {} joints, expected 6", clip_, leg_.tip_link,
                                              leg_.joint_index.size()));
    for (const auto& s : g1SolePoints_F()) p_FS_ += 0.25 * s;
  }

  /// Sole centre in B [m] and the foot frame's rotation.
  void sole(const Eigen::VectorXd& q, Eigen::Vector3d& p_BS, Eigen::Matrix3d& R_BF) {
    Eigen::Isometry3d X_BF;
    if (!ws_.tipPose(q, X_BF)) throw std::runtime_error(fmt::format("raiseWalkingHeight({}): KDL forward kinematics failed", clip_));
    p_BS = X_BF * p_FS_;
    R_BF = X_BF.linear();
  }

  /// Moves the sole centre of @p q by @p d down along B's z, keeping its x, y and the foot's
  /// orientation in B. Returns false (q unchanged) if Newton does not converge, a joint leaves its
  /// limits or the knee ends below @p min_knee (or below its own flexion, if that is already smaller).
  bool lower(Eigen::VectorXd& q, double d, double min_knee) {
    Eigen::Vector3d p0;
    Eigen::Matrix3d R0;
    sole(q, p0, R0);
    const Eigen::Vector3d target(p0.x(), p0.y(), p0.z() - d);
    Eigen::VectorXd x = q;
    using Vector6d = Eigen::Matrix<double, 6, 1>;
    auto residual = [&](const Eigen::VectorXd& qq) {
      Eigen::Vector3d p;
      Eigen::Matrix3d R;
      sole(qq, p, R);
      const Eigen::Matrix3d dR = R * R0.transpose();  // rotation from the original foot, in B
      Vector6d r;
      r << p - target, 0.5 * (dR(2, 1) - dR(1, 2)), 0.5 * (dR(0, 2) - dR(2, 0)), 0.5 * (dR(1, 0) - dR(0, 1));
      return r;
    };
    constexpr double kStep = 1e-7;
    for (int it = 0; it < 30; ++it) {
      const Vector6d r = residual(x);
      if (r.norm() < 1e-10) break;
      Eigen::Matrix<double, 6, 6> J;
      for (int c = 0; c < 6; ++c) {
        Eigen::VectorXd xp = x;
        xp(leg_.joint_index[static_cast<std::size_t>(c)]) += kStep;
        J.col(c) = (residual(xp) - r) / kStep;
      }
      const Vector6d dx = J.fullPivLu().solve(-r);
      if (!dx.allFinite()) return false;
      for (int c = 0; c < 6; ++c) x(leg_.joint_index[static_cast<std::size_t>(c)]) += dx(c);
    }
    // A knee already straighter than min_knee may stay as it is, not straighten further.
    if (residual(x).norm() > 1e-8 || x(knee_) < std::min(min_knee, q(knee_)) - 1e-9) return false;
    for (const int j : leg_.joint_index)
      if (x(j) < lower_(j) || x(j) > upper_(j)) return false;
    q = x;
    return true;
  }

 private:
  LimbChain leg_;  // ChainFkWorkspace keeps a pointer to it
  ChainFkWorkspace ws_;
  Eigen::Index knee_;
  Eigen::VectorXd lower_, upper_;
  std::string clip_;
  Eigen::Vector3d p_FS_ = Eigen::Vector3d::Zero();
};

}  // namespace

WalkingHeightReport raiseWalkingHeight(DynamicClip& clip, const KinematicModel& model, const Eigen::VectorXd& q_stand,
                                       const WalkingHeightOptions& options) {
  options.validate();
  const RobotConfig& robot = model.config();
  const auto n = static_cast<Eigen::Index>(robot.numJoints());
  if (clip.q.cols() != n || q_stand.size() != n)
    throw std::invalid_argument(fmt::format("raiseWalkingHeight({}): clip has {} joints, standing pose {}, robot config {}", clip.name,
                                            clip.q.cols(), q_stand.size(), n));
  auto index = [&](const std::string& joint) {
    const int i = robot.jointIndex(joint);
    if (i < 0) throw std::invalid_argument(fmt::format("raiseWalkingHeight({}): robot has no joint '{}'", clip.name, joint));
    return static_cast<Eigen::Index>(i);
  };
  const Eigen::VectorXd lower = robot.lowerLimits(), upper = robot.upperLimits();
  LegLengthener left(model.leftLeg(), index("left_knee_joint"), lower, upper, clip.name);
  LegLengthener right(model.rightLeg(), index("right_knee_joint"), lower, upper, clip.name);
  auto pelvisHeight = [&](const Eigen::VectorXd& q) {
    Eigen::Vector3d pl, pr;
    Eigen::Matrix3d R;
    left.sole(q, pl, R);
    right.sole(q, pr, R);
    return -std::min(pl.z(), pr.z());
  };
  const Eigen::Index N = clip.q.rows();
  WalkingHeightReport rep;
  rep.standing_height = pelvisHeight(q_stand);
  for (Eigen::Index k = 0; k < N; ++k) rep.mean_height_before += pelvisHeight(clip.q.row(k).transpose()) / static_cast<double>(N);
  rep.target_raise = options.fraction * std::max(0.0, rep.standing_height - rep.mean_height_before);
  rep.mean_height_after = rep.mean_height_before;
  rep.min_raise = rep.target_raise;
  if (rep.target_raise <= 0.0 || N == 0) return rep;

  // Largest feasible raise per sample (both legs), by bisection below the target. @p q: the pose
  // raised by d when feasible.
  Eigen::VectorXd solved;
  auto feasible = [&](const Eigen::VectorXd& q0, double d, Eigen::VectorXd& q) {
    q = q0;
    return left.lower(q, d, options.min_knee) && right.lower(q, d, options.min_knee);
  };
  Eigen::VectorXd d_max(N);
  for (Eigen::Index k = 0; k < N; ++k) {
    const Eigen::VectorXd q0 = clip.q.row(k).transpose();
    if (feasible(q0, rep.target_raise, solved)) {
      d_max(k) = rep.target_raise;
      continue;
    }
    double lo = 0.0, hi = rep.target_raise;
    for (int it = 0; it < 14; ++it) {
      const double mid = 0.5 * (lo + hi);
      (feasible(q0, mid, solved) ? lo : hi) = mid;
    }
    d_max(k) = lo;
  }
  // Min-filter over ±w, then a Gaussian truncated at ±w: each smoothed value is an average of
  // values that are each <= d_max at this sample, so the smoothed raise stays feasible.
  Eigen::VectorXd d = d_max;
  const double sigma = options.smoothing_samples;
  if (sigma > 0.0) {
    constexpr double kTruncate = 3.0;  // the Gaussian's reach, in σ
    const auto w = static_cast<Eigen::Index>(std::ceil(kTruncate * sigma));
    Eigen::VectorXd eroded(N);
    for (Eigen::Index k = 0; k < N; ++k) {
      double m = d_max(k);
      for (Eigen::Index j = -w; j <= w; ++j) m = std::min(m, d_max(((k + j) % N + N) % N));
      eroded(k) = m;
    }
    d = circularGaussianSmooth(eroded, sigma, kTruncate).col(0);
  }
  for (Eigen::Index k = 0; k < N; ++k) {
    // d(k) <= d_max(k) up to rounding: step down a hair if the exact value is refused.
    double dk = d(k);
    bool ok = feasible(clip.q.row(k).transpose(), dk, solved);
    for (int it = 0; it < 20 && !ok; ++it) {
      dk *= 0.999;
      ok = feasible(clip.q.row(k).transpose(), dk, solved);
    }
    if (!ok) throw std::runtime_error(fmt::format("raiseWalkingHeight({}): no feasible raise at sample {}", clip.name, k));
    d(k) = dk;
    clip.q.row(k) = solved.transpose();
  }
  clip.qd = periodicDerivative(clip.q, clip.period);
  clip.base_height += d;
  const Eigen::MatrixXd dz = periodicDerivative(Eigen::MatrixXd(d), clip.period);
  clip.v_base.col(2) += dz.col(0);
  rep.min_raise = d.minCoeff();
  rep.mean_height_after = 0.0;
  for (Eigen::Index k = 0; k < N; ++k) rep.mean_height_after += pelvisHeight(clip.q.row(k).transpose()) / static_cast<double>(N);
  return rep;
}

}  // namespace pmg::motion
