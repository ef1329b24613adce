#pragma once
/// @file clip_transforms.hpp
/// The transforms of PMG dynamic clips (pmg::clips): left/right mirror, time reversal and phase
/// rotation. The clip builder (pmg_make_clips: `walk_lateral_right`, `turn_right`) and the generator
/// (GeneratorModel: a clip missing for one sign of an axis) derive clips with these same functions.
/// Setup-time code: allocates and throws std::invalid_argument.
///
/// Phase convention of every clip (docs/clip_format.md): φ = 0 is the left foot's touchdown, i.e.
/// the start μ_left − σ_left of the left foot's contact interval. The generator plays all clips on
/// one shared phase φ and blends them sample by sample (eqs. 5, 7), so a derived clip is rotated back
/// onto this convention; otherwise a blend of, e.g., walking forward and walking right would average
/// the left leg's stance of one template with its swing in the other.

#include <string>

#include <Eigen/Core>

#include "pmg/common/robot_config.hpp"
#include "pmg/generator/clip.hpp"
#include "pmg/generator/joint_space.hpp"

namespace pmg {

/// Left/right mirror of joint vectors, one per row: (M q)_j = mirror_sign_j · q_{mirror_index_j}
/// (GeneratorJointSpace's mirror convention). @p q: (rows × n) [rad or rad/s].
/// @throws std::invalid_argument if q has not n columns or the mirror map is not of size n.
Eigen::MatrixXd mirrorJoints(const Eigen::MatrixXd& q, const GeneratorJointSpace& joints);

/// Rotates the N samples of a dynamic clip by @p shift samples (new sample k = old sample k + shift,
/// any integer, taken modulo N) and moves the contact centres μ by −shift / N (wrapped to [0, 1)),
/// so the clip describes the same motion starting at another phase.
void rotateClipPhase(DynamicClip& clip, Eigen::Index shift);

/// Rotates the clip so that φ = 0 is the left foot's touchdown: shift = round((μ_left − σ_left) N)
/// mod N. A foot always (σ = 0.5 at μ = 0.5) or never (σ = 0) in contact gives no rotation.
/// @returns the shift applied, in samples [0, N).
Eigen::Index alignPhaseOnLeftTouchdown(DynamicClip& clip);

/// The left/right mirror image of a dynamic clip (the robot reflected in its sagittal x-z plane):
/// - q and q̇: mirrorJoints();
/// - base velocity v' = (v_x, −v_y, v_z); angular velocity (a pseudo-vector) ω' = (−ω_x, ω_y, −ω_z);
/// - contacts of the two feet swapped;
/// - direction: a lateral (v_y) or yaw (ω) clip changes sign, a forward clip keeps it;
/// - then alignPhaseOnLeftTouchdown() (the mirror of a clip that starts at the left touchdown starts
///   at the right one);
/// - name = @p new_name; provenance "mocap" becomes "mocap_mirrored" (a synthesized or already
///   derived clip keeps its provenance); notes = "left/right mirror of clip '<name>' (robot mirror
///   map), phase rotated by <shift> samples; <notes>".
/// @throws std::invalid_argument if the clip's joint count differs from the joint space's.
DynamicClip mirrorClip(const DynamicClip& clip, const GeneratorJointSpace& joints, const std::string& new_name);
/// mirrorClip() with the robot config's mirror map (generatorJointSpace(robot)).
DynamicClip mirrorClip(const DynamicClip& clip, const RobotConfig& robot, const std::string& new_name);

/// The clip played backwards in time (walking backward from walking forward):
/// - sample k takes sample (N − k) mod N, i.e. q'(φ) = q(1 − φ);
/// - q̇, v_base and ω_base change sign (d/dt of a reversed motion); base height is kept;
/// - contact centres μ' = 1 − μ (σ kept);
/// - direction changes sign (on every axis);
/// - then alignPhaseOnLeftTouchdown() (a touchdown played backwards is a lift-off);
/// - name = @p new_name; provenance "mocap" becomes "mocap_time_reversed" (others are kept); notes =
///   "time reversal of clip '<name>', phase rotated by <shift> samples; <notes>".
DynamicClip timeReverseClip(const DynamicClip& clip, const std::string& new_name);

}  // namespace pmg
