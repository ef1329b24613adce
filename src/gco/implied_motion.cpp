#include "pmg/gco/implied_motion.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "pmg/common/robot_config.hpp"
#include "pmg/gco/foot_slip.hpp"
#include "pmg/gco/generator_bridge.hpp"
#include "pmg/generator/robot_joint_space.hpp"

namespace pmg::gco {

std::vector<double> defaultImpliedAmplitudes() {
  std::vector<double> a;
  for (int k = 0; k <= 20; ++k) a.push_back(0.1 * k);
  return a;
}

ImpliedMotionTable computeImpliedMotion(const DynamicClip& clip, const GeneratorJointSpace& joints,
                                        std::shared_ptr<const LegModel> legs, const std::vector<double>& amplitudes) {
  const std::string where = "computeImpliedMotion(" + clip.name + ")";
  if (amplitudes.size() < 2 || amplitudes[0] != 0.0)
    throw std::invalid_argument(where + ": amplitudes: expected >= 2 values starting at 0");
  for (std::size_t i = 1; i < amplitudes.size(); ++i)
    if (!(amplitudes[i] > amplitudes[i - 1])) throw std::invalid_argument(where + ": amplitudes: expected strictly increasing");
  const auto n = static_cast<Eigen::Index>(joints.joint_names.size());
  if (clip.q.cols() != n) throw std::invalid_argument(where + ": clip joints differ from the joint space");
  const LegJointIndex idx = legs->jointIndices(joints.joint_names);
  LegKinematics kin(legs);
  const Eigen::Index N = clip.q.rows();
  const auto axis = static_cast<Eigen::Index>(clip.axis);

  std::vector<Eigen::Vector3d> rows;
  Eigen::VectorXd q(n), qd(n);
  for (double a : amplitudes) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    int count = 0;
    for (Eigen::Index k = 0; k < N; ++k) {
      for (Eigen::Index j = 0; j < n; ++j) {
        const double x = joints.q_stand[j] + a * (clip.q(k, j) - joints.q_stand[j]);
        q[j] = std::clamp(x, joints.lower[j], joints.upper[j]);
        qd[j] = q[j] == x ? a * clip.qd(k, j) : 0.0;
      }
      GcoInput in;
      fillLegState(idx, q, qd, &in);
      const double phi = static_cast<double>(k) / static_cast<double>(N);
      for (std::size_t f = 0; f < kNumFeet; ++f) in.contact[f] = detail::inStance(clip.contact[f], phi);
      const ImpliedBaseVelocity iv = stanceImpliedVelocity(kin, in);
      if (!iv.valid) continue;
      sum += Eigen::Vector3d(iv.v_x, iv.v_y, iv.yaw_rate);
      ++count;
    }
    Eigen::Vector3d v = count > 0 ? Eigen::Vector3d(sum / count) : Eigen::Vector3d::Zero();
    if (a == 0.0) v.setZero();  // the standing pose: exactly no motion
    if (!rows.empty() && !(clip.direction * v[axis] > clip.direction * rows.back()[axis])) break;  // no longer invertible
    rows.push_back(v);
  }
  if (rows.size() < 2)
    throw std::invalid_argument(where + ": the clip's own axis does not grow with the amplitude (no stance-implied motion "
                                "in its direction)");
  ImpliedMotionTable t;
  t.amplitude.resize(static_cast<Eigen::Index>(rows.size()));
  t.velocity.resize(static_cast<Eigen::Index>(rows.size()), 3);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    t.amplitude[static_cast<Eigen::Index>(i)] = amplitudes[i];
    t.velocity.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
  }
  return t;
}

void addImpliedMotion(ClipLibrary* library, const RobotConfig& robot, const std::vector<double>& amplitudes) {
  const GeneratorJointSpace js = generatorJointSpace(robot);
  const auto legs = LegModel::fromRobotConfig(robot);
  for (DynamicClip& c : library->dynamic_clips) c.implied = computeImpliedMotion(c, js, legs, amplitudes);
}

Eigen::Vector3d cycleImpliedVelocity(MotionGenerator& gen, LegKinematics& kin, const LegJointIndex& idx,
                                     const VelocityCommand& u, const PostureCommand& posture, int samples_per_cycle) {
  gen.reset(0.0);
  gen.step(u, posture, 0.0);  // dt = 0: evaluates at φ = 0 without advancing; gives T_u
  const double dt = gen.output().period / samples_per_cycle;
  gen.reset(0.0);
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  int count = 0;
  GcoInput in;
  for (int k = 0; k < samples_per_cycle; ++k) {
    gen.step(u, posture, dt);
    fillFromGenerator(gen.output(), idx, u, posture, &in);
    const ImpliedBaseVelocity iv = stanceImpliedVelocity(kin, in);
    if (!iv.valid) continue;
    sum += Eigen::Vector3d(iv.v_x, iv.v_y, iv.yaw_rate);
    ++count;
  }
  return count > 0 ? Eigen::Vector3d(sum / count) : Eigen::Vector3d::Zero();
}

ConsistencyMap computeConsistencyMap(const ClipLibrary& library, const RobotConfig& robot, const ConsistencyMapOptions& o,
                                     double* worst_residual) {
  ClipLibrary lib = library;
  lib.consistency = ConsistencyMap{};
  for (const auto& c : lib.dynamic_clips)
    if (c.implied.empty()) throw std::invalid_argument("computeConsistencyMap: clip '" + c.name + "' has no implied_motion table");
  GeneratorParams params;
  params.blending = Blending::kConsistent;
  const GeneratorJointSpace js = generatorJointSpace(robot);
  auto model = std::make_shared<const GeneratorModel>(lib, js, params);
  MotionGenerator gen(model);
  const auto legs = LegModel::fromRobotConfig(robot);
  LegKinematics kin(legs);
  const LegJointIndex idx = legs->jointIndices(js.joint_names);
  const StaticClip* squat = model->staticClip(PostureAxis::kHeight);
  const double neutral = squat ? squat->neutral : js.standing_base_height;

  ConsistencyMap m;
  const std::vector<double>* g[3] = {&o.vx, &o.vy, &o.wz};
  for (std::size_t d = 0; d < 3; ++d)
    m.grid[d] = Eigen::Map<const Eigen::VectorXd>(g[d]->data(), static_cast<Eigen::Index>(g[d]->size()));
  std::vector<double> heights;
  for (double h : o.height) heights.push_back(h <= 0.0 ? neutral : h);
  std::sort(heights.begin(), heights.end());
  m.grid[3] = Eigen::Map<const Eigen::VectorXd>(heights.data(), static_cast<Eigen::Index>(heights.size()));
  for (const auto& grid : m.grid)
    for (Eigen::Index i = 1; i < grid.size(); ++i)
      if (!(grid[i] > grid[i - 1])) throw std::invalid_argument("computeConsistencyMap: grids must be strictly increasing");
  m.grid[4] = Eigen::Map<const Eigen::VectorXd>(o.pitch.data(), static_cast<Eigen::Index>(o.pitch.size()));
  for (const auto& grid : m.grid)
    if (grid.size() < 1) throw std::invalid_argument("computeConsistencyMap: every grid needs a value");
  m.delta.setZero(static_cast<Eigen::Index>(o.vx.size() * o.vy.size() * o.wz.size() * heights.size() * o.pitch.size()), 3);
  double worst = 0.0;
  Eigen::Index row = 0;
  for (double vx : o.vx)
    for (double vy : o.vy)
      for (double wz : o.wz)
        for (double h : heights)
          for (double pitch : o.pitch) {
          const Eigen::Vector3d u(vx, vy, wz);
          const PostureCommand posture{pitch, 0.0, h};
          const auto implied = [&](const Eigen::Vector3d& ug) {
            return cycleImpliedVelocity(gen, kin, idx, VelocityCommand{ug.x(), ug.y(), ug.z()}, posture, o.samples_per_cycle);
          };
          const auto clampToBox = [&](Eigen::Vector3d ug) {
            for (int a = 0; a < 3; ++a) ug[a] = std::clamp(ug[a], u[a] - o.max_correction, u[a] + o.max_correction);
            return ug;
          };
          Eigen::Vector3d u_gen = u, best = u, e_best = Eigen::Vector3d::Zero();
          double best_err = 1e9;
          for (int it = 0; it <= o.iterations; ++it) {
            const Eigen::Vector3d e = u - implied(u_gen);
            if (e.cwiseAbs().maxCoeff() < best_err) {
              best_err = e.cwiseAbs().maxCoeff();
              best = u_gen;
              e_best = e;
            }
            if (it == o.iterations) break;
            u_gen = clampToBox(u_gen + e);
          }
          // Where the fixed point (which takes the map's Jacobian as the identity) leaves the point
          // outside the target band (crouched combinations whose channels couple): damped
          // Gauss-Newton from its best point on the residual scaled by the band, with a
          // finite-difference Jacobian and step halving. Points inside the band keep their Δu.
          Eigen::Vector3d inv_band;
          for (int a = 0; a < 3; ++a) inv_band[a] = 1.0 / std::max(o.target_relative * std::fabs(u[a]), o.target_absolute[a]);
          double best_scaled = e_best.cwiseProduct(inv_band).cwiseAbs().maxCoeff();
          for (int it = 0; it < o.newton_iterations && best_scaled > 1.0; ++it) {
            const Eigen::Vector3d v0 = u - e_best;
            Eigen::Matrix3d J;
            for (int a = 0; a < 3; ++a) {
              Eigen::Vector3d ug = best;
              ug[a] += o.jacobian_step;
              J.col(a) = inv_band.asDiagonal() * ((implied(ug) - v0) / o.jacobian_step);
            }
            const Eigen::Matrix3d JtJ = J.transpose() * J + o.newton_damping * Eigen::Matrix3d::Identity();
            const Eigen::Vector3d step = JtJ.ldlt().solve(J.transpose() * e_best.cwiseProduct(inv_band));
            bool improved = false;
            for (double scale = 1.0; scale >= 0.125 && !improved; scale *= 0.5) {
              const Eigen::Vector3d ug = clampToBox(best + scale * step);
              const Eigen::Vector3d e = u - implied(ug);
              const double scaled = e.cwiseProduct(inv_band).cwiseAbs().maxCoeff();
              if (scaled < best_scaled) {
                best_scaled = scaled;
                best_err = e.cwiseAbs().maxCoeff();
                best = ug;
                e_best = e;
                improved = true;
              }
            }
            if (!improved) break;
          }
          worst = std::max(worst, best_err);
          m.delta.row(row++) = (best - u).transpose();
        }
  if (worst_residual) *worst_residual = worst;
  return m;
}

}  // namespace pmg::gco
