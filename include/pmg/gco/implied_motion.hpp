#pragma once
/// @file implied_motion.hpp
/// Stance-implied motion tables of the dynamic clips, for the generator's command-consistent
/// blending (include/pmg/generator/generator.hpp, docs/generator.md). Setup / offline only.
///
/// For a clip D (N phase samples, period T, contacts c_f) and an amplitude a, the clip is played
/// alone about the standing pose, q(φ_k) = clamp(q_stand + a (q_D(φ_k) − q_stand), limits),
/// q̇(φ_k) = a q̇_D(φ_k) (0 where clamped); at each sample with a foot in stance,
/// pmg::gco::stanceImpliedVelocity gives the base velocity (v_x, v_y, ω) in the heading frame H
/// that holds the stance soles still (level pelvis, as the generator's templates). The table entry
/// is the mean over those samples [m/s, m/s, rad/s]. The entry at a = 0 is exactly 0.
/// The table is cut after the last amplitude at which the clip's own axis still grows (in its
/// direction), so the generator can invert it.

#include <memory>
#include <vector>

#include "pmg/generator/clip.hpp"
#include "pmg/generator/generator.hpp"
#include "pmg/generator/joint_space.hpp"
#include "pmg/gco/leg_kinematics.hpp"

namespace pmg {
struct RobotConfig;
}

namespace pmg::gco {

/// Default amplitude grid: 0, 0.1, …, 2.0.
std::vector<double> defaultImpliedAmplitudes();

/// Table of `clip` at `amplitudes` (strictly increasing, first 0). `joints`: the generator joint
/// space of the same robot (q_stand, limits, joint order of clip.q). Throws std::invalid_argument
/// on a bad grid or a clip whose own axis does not grow at the first non-zero amplitude.
ImpliedMotionTable computeImpliedMotion(const DynamicClip& clip, const GeneratorJointSpace& joints,
                                        std::shared_ptr<const LegModel> legs, const std::vector<double>& amplitudes);

/// Options of computeConsistencyMap. Grids: the command envelope of docs/generator.md.
struct ConsistencyMapOptions {
  std::vector<double> vx{-0.5, -0.25, 0.0, 0.25, 0.5, 0.75, 1.0};  ///< [m/s]
  std::vector<double> vy{-0.4, -0.2, 0.0, 0.2, 0.4};               ///< [m/s]
  std::vector<double> wz{-0.8, -0.4, 0.0, 0.4, 0.8};               ///< [rad/s]
  /// Pelvis heights [m]; values <= 0 stand for the squat clip's neutral (the standing height).
  std::vector<double> height{0.62, 0.66, 0.70, 0.0};
  std::vector<double> pitch{0.0, 0.2, 0.4};  ///< torso pitch commands [rad]
  int iterations = 8;          ///< fixed-point iterations u_gen ← u_gen + (u − m(u_gen))
  double max_correction = 1.5; ///< |Δu| bound per axis [m/s, rad/s]
  /// Damped Gauss-Newton after the fixed point, only where its best point leaves some axis outside
  /// the target band max(target_relative |u_i|, target_absolute_i) (issue 12's ±10 %, 0.03 m/s,
  /// 0.05 rad/s): steps on the residual scaled by the band, (JᵀJ + λI)⁻¹ Jᵀ r, J by forward
  /// differences of jacobian_step, halved up to 3 times until the largest scaled residual falls;
  /// it stops when no step improves it. Points inside the band keep the fixed point's Δu.
  int newton_iterations = 20;
  double target_relative = 0.1;
  Eigen::Vector3d target_absolute{0.03, 0.03, 0.05};  ///< [m/s, m/s, rad/s]
  double jacobian_step = 0.02;      ///< [m/s or rad/s]
  double newton_damping = 1e-3;     ///< λ
  int samples_per_cycle = 100; ///< phase samples of the cycle mean m(u_gen)
};

/// Cycle-mean stance-implied base motion (v_x, v_y, ω) in H of the references the generator makes
/// for the constant command (u, posture): one gait cycle from φ = 0 in `samples_per_cycle` equal
/// steps, stanceImpliedVelocity at every sample with a foot in stance, their mean. `gen` is reset.
Eigen::Vector3d cycleImpliedVelocity(MotionGenerator& gen, LegKinematics& kin, const LegJointIndex& idx,
                                     const VelocityCommand& u, const PostureCommand& posture, int samples_per_cycle = 100);

/// Residual correction map of the command-consistent blending (ConsistencyMap, clip.hpp): for every
/// grid point, the Δu for which the generator (kConsistent, per-clip tables of `library`, no map)
/// fed u + Δu makes references whose cycle-mean stance-implied motion is u. `library` must carry
/// the implied_motion tables. `worst_residual` (optional): largest |m(u + Δu) − u| left [m/s or rad/s].
ConsistencyMap computeConsistencyMap(const ClipLibrary& library, const RobotConfig& robot,
                                     const ConsistencyMapOptions& options = {}, double* worst_residual = nullptr);

/// Computes and stores the table of every dynamic clip of `library` (robot: the leg chains,
/// q_stand and limits). Throws as above, naming the clip.
void addImpliedMotion(ClipLibrary* library, const RobotConfig& robot,
                      const std::vector<double>& amplitudes = defaultImpliedAmplitudes());

}  // namespace pmg::gco
