// Single-joint response calibration on the whole robot (include/pmg/calib/joint_calibration.hpp).
#include "pmg/calib/joint_calibration.hpp"

#include <algorithm>
#include <chrono>
#include <memory>
#include <thread>
#include <cmath>
#include <limits>
#include <stdexcept>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <fmt/ranges.h>

#include <yaml-cpp/yaml.h>

#include "pmg/hal/modes.hpp"

namespace pmg::calib {

void JointExcitation::validate() const {
  auto check = [](bool ok, const char* field, double v, const char* range) {
    if (!ok) throw std::invalid_argument(fmt::format("JointExcitation.{} = {}: expected {}", field, v, range));
  };
  check(std::isfinite(amplitude_rad) && amplitude_rad > 0 && amplitude_rad <= 0.5, "amplitude_rad", amplitude_rad, "(0, 0.5] rad");
  check(std::isfinite(ramp_s) && ramp_s >= 0.01 && ramp_s <= 1.0, "ramp_s", ramp_s, "[0.01, 1] s");
  check(std::isfinite(hold_s) && hold_s >= 0.1 && hold_s <= 5.0, "hold_s", hold_s, "[0.1, 5] s");
  check(std::isfinite(chirp_s) && chirp_s >= 0.5 && chirp_s <= 20.0, "chirp_s", chirp_s, "[0.5, 20] s");
}

namespace {

// Cosine ramps between levels (fractions of the amplitude), each followed by a hold.
std::vector<double> staircase(const std::vector<double>& levels, double a, double ramp, double hold, double dt) {
  std::vector<double> out;
  double from = 0.0;
  const int nr = std::max(1, static_cast<int>(std::lround(ramp / dt)));
  const int nh = std::max(1, static_cast<int>(std::lround(hold / dt)));
  for (double l : levels) {
    const double to = l * a;
    for (int k = 1; k <= nr; ++k) out.push_back(from + (to - from) * (0.5 - 0.5 * std::cos(M_PI * k / nr)));
    for (int k = 0; k < nh; ++k) out.push_back(to);
    from = to;
  }
  return out;
}

// Sine sweep f0 -> f1 [Hz] of amplitude a under a sin^2 taper (0.25 s each end).
std::vector<double> chirp(double a, double f0, double f1, double seconds, double dt) {
  const int n = static_cast<int>(std::lround(seconds / dt));
  std::vector<double> out(static_cast<std::size_t>(n));
  const double taper = std::min(0.25, 0.25 * seconds);
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    const double phase = 2.0 * M_PI * (f0 * t + 0.5 * (f1 - f0) / seconds * t * t);
    double w = 1.0;
    if (t < taper) w = std::pow(std::sin(0.5 * M_PI * t / taper), 2);
    if (seconds - t < taper) w = std::pow(std::sin(0.5 * M_PI * (seconds - t) / taper), 2);
    out[static_cast<std::size_t>(k)] = a * w * std::sin(phase);
  }
  return out;
}

}  // namespace

std::vector<std::pair<std::string, std::vector<double>>> excitationSignals(const JointExcitation& ex, double dt) {
  ex.validate();
  if (!(dt > 0 && dt <= 0.01)) throw std::invalid_argument(fmt::format("excitationSignals: dt = {}: expected (0, 0.01] s", dt));
  const double a = ex.amplitude_rad;
  std::vector<double> steps = staircase({1.0, 0.0, -1.0, 0.0, 0.5, -0.5, 0.25, -0.25, 1.0, -1.0, 0.0}, a, ex.ramp_s, ex.hold_s, dt);
  std::vector<double> sweep = chirp(0.6 * a, 0.5, 4.0, ex.chirp_s, dt);
  // Held-out: other step sizes and a slower, larger sine burst (not in the training logs).
  std::vector<double> mixed = staircase({0.7, -0.3, 0.9, -0.8, 0.0}, a, 2.0 * ex.ramp_s, ex.hold_s, dt);
  const std::vector<double> burst = chirp(0.5 * a, 1.5, 1.5, 1.5, dt);
  mixed.insert(mixed.end(), burst.begin(), burst.end());
  const std::vector<double> tail = staircase({0.0}, a, ex.ramp_s, ex.hold_s, dt);
  mixed.insert(mixed.end(), tail.begin(), tail.end());
  return {{"steps", steps}, {"chirp", sweep}, {"mixed", mixed}};
}

JointCapture captureJoint(HalBackend& backend, const RobotConfig& robot, int index, const JointExcitation& ex,
                          const Eigen::VectorXd& hold_targets, const std::function<void(const std::string&)>& log,
                          bool with_heldout) {
  const int n = static_cast<int>(robot.numJoints());
  if (index < 0 || index >= n) throw std::invalid_argument(fmt::format("captureJoint: joint index {} not in [0, {})", index, n));
  if (hold_targets.size() != n)
    throw std::invalid_argument(fmt::format("captureJoint: hold_targets has {} entries, expected {}", hold_targets.size(), n));
  const JointConfig& jc = robot.joints[static_cast<std::size_t>(index)];
  const double dt = backend.cyclePeriod();
  const auto signals = excitationSignals(ex, dt);
  const Eigen::VectorXd kp = robot.kp(), kd = robot.kd();
  LowCommand cmd;
  cmd.num_motors = n;
  LowState st;
  JointCapture out;
  out.joint = jc.name;
  out.index = index;
  out.held_q = Eigen::VectorXd::Zero(n);
  long samples = 0;
  double t0 = -1.0;
  auto send = [&](double offset) {
    for (int i = 0; i < n; ++i) {
      pmg::MotorCommand& m = cmd.motors[static_cast<std::size_t>(i)];
      m.q = hold_targets(i) + (i == index ? offset : 0.0);
      m.qd = 0.0;
      m.kp = kp(i);
      m.kd = kd(i);
      m.tau_ff = 0.0;
    }
    ++cmd.sequence;
    if (backend.exchange(cmd, st) == BackendStatus::kFault)
      throw std::runtime_error(fmt::format("captureJoint({}): backend '{}' fault at t = {:.3f} s", jc.name, backend.name(), st.time));
    if (st.mode == Mode::kDamping)
      throw std::runtime_error(fmt::format("captureJoint({}): the HAL supervisor latched damping at t = {:.3f} s: {}", jc.name,
                                           st.time, toString(st.fault)));
    if (t0 < 0) t0 = st.time;
    for (int i = 0; i < n; ++i) out.held_q(i) += st.motors[static_cast<std::size_t>(i)].q;
    ++samples;
  };
  // Settle at the hold targets (the stack was engaged at the default pose).
  for (int k = 0; k < static_cast<int>(std::lround(0.5 / dt)); ++k) send(0.0);
  for (const auto& [name, sig] : signals) {
    if (name == "mixed" && !with_heldout) break;
    BenchLog lg;
    lg.name = jc.name + ":" + name;
    std::vector<double> t, q, dq, tau;
    for (double s : sig) {
      send(s);
      // The previous row's command is the one the driver holds from its reading on: this one.
      if (!t.empty()) {
        lg.q_cmd.push_back(cmd.motors[static_cast<std::size_t>(index)].q);
        lg.kp.push_back(cmd.motors[static_cast<std::size_t>(index)].kp);
        lg.kd.push_back(cmd.motors[static_cast<std::size_t>(index)].kd);
      }
      const auto& m = st.motors[static_cast<std::size_t>(index)];
      t.push_back(st.time);
      q.push_back(m.q);
      dq.push_back(m.qd);
      tau.push_back(m.tau);
    }
    t.pop_back();
    q.pop_back();
    dq.pop_back();
    tau.pop_back();
    lg.t = std::move(t);
    lg.q = std::move(q);
    lg.dq = std::move(dq);
    lg.tau = std::move(tau);
    lg.validate();
    (name == "mixed" ? out.heldout : out.train).push_back(std::move(lg));
    if (log) log(fmt::format("  {}: {} log, {:.2f} s", jc.name, name, sig.size() * dt));
  }
  out.held_q /= static_cast<double>(samples);
  out.duration_s = st.time - t0;
  return out;
}

CommandLatencyBackend::CommandLatencyBackend(HalBackend& inner, int cycles) : inner_(inner), cycles_(cycles) {
  if (cycles < 0 || cycles > 50) throw std::invalid_argument(fmt::format("CommandLatencyBackend: cycles = {}: expected 0..50", cycles));
}

BackendStatus CommandLatencyBackend::exchange(const LowCommand& command, LowState& state) noexcept {
  if (cycles_ == 0) return inner_.exchange(command, state);
  while (static_cast<int>(queue_.size()) < cycles_) queue_.push_back(command);
  queue_.push_back(command);
  const LowCommand due = queue_.front();
  queue_.erase(queue_.begin());
  return inner_.exchange(due, state);
}

int responseLagCycles(const JointCapture& robot, const JointCapture& sim, int max_cycles) {
  double best = std::numeric_limits<double>::infinity();
  int best_lag = 0;
  for (int lag = 0; lag <= max_cycles; ++lag) {
    double sum = 0.0;
    long n = 0;
    for (std::size_t l = 0; l < robot.train.size() && l < sim.train.size(); ++l) {
      const auto& a = robot.train[l].q;
      const auto& b = sim.train[l].q;
      const std::size_t len = std::min(a.size(), b.size());
      if (len <= static_cast<std::size_t>(lag)) continue;
      double ma = 0.0, mb = 0.0;
      const std::size_t m = len - static_cast<std::size_t>(lag);
      for (std::size_t k = 0; k < m; ++k) {
        ma += a[k + static_cast<std::size_t>(lag)];
        mb += b[k];
      }
      ma /= static_cast<double>(m);
      mb /= static_cast<double>(m);
      for (std::size_t k = 0; k < m; ++k) {
        const double e = (a[k + static_cast<std::size_t>(lag)] - ma) - (b[k] - mb);
        sum += e * e;
      }
      n += static_cast<long>(m);
    }
    const double rms = n > 0 ? std::sqrt(sum / static_cast<double>(n)) : std::numeric_limits<double>::infinity();
    if (rms < best) {
      best = rms;
      best_lag = lag;
    }
  }
  return best_lag;
}

double simulationResidual(const JointCapture& robot, const JointCapture& sim) {
  double sum = 0.0;
  long n = 0;
  for (const auto& [sse, len] : logSquaredErrors(robot, sim)) {
    sum += sse;
    n += len;
  }
  return n > 0 ? std::sqrt(sum / static_cast<double>(n)) : 0.0;
}

JointSimulator::JointSimulator(const RobotConfig& model, const MujocoBackendOptions& options, int bus_latency_cycles)
    : robot_(model),
      sim_(robot_, [&] {
        MujocoBackendOptions o = options;
        o.gantry.enabled = true;
        o.disable_contacts = true;
        o.encoder_offsets.clear();
        return o;
      }()),
      lagged_(sim_, bus_latency_cycles) {
  for (const auto& j : robot_.joints)
    configured_.push_back(j.actuator_yaml.empty() ? std::nullopt
                                                  : std::optional<ActuatorBlock>(parse_actuator_block(
                                                        YAML::Load(j.actuator_yaml), j.actuator_source)));
}

JointCapture JointSimulator::capture(int index, const std::optional<ActuatorBlock>& block, const JointExcitation& ex,
                                     const Eigen::VectorXd& hold_targets, bool with_heldout) {
  sim_.setActuatorBlock(index, block);
  sim_.reset();
  lagged_.clear();
  ++evaluations_;
  JointCapture c = captureJoint(lagged_, robot_, index, ex, hold_targets, {}, with_heldout);
  sim_.setActuatorBlock(index, configured_[static_cast<std::size_t>(index)]);
  return c;
}

std::vector<std::pair<double, long>> logSquaredErrors(const JointCapture& robot, const JointCapture& sim) {
  std::vector<std::pair<double, long>> out;
  auto add = [&](const std::vector<BenchLog>& a, const std::vector<BenchLog>& b) {
    if (a.size() < b.size()) throw std::invalid_argument("logSquaredErrors: the simulator has logs the robot has not");
    for (std::size_t l = 0; l < b.size(); ++l) {
      const std::size_t len = std::min(a[l].q.size(), b[l].q.size());
      double mean = 0.0;
      for (std::size_t k = 0; k < len; ++k) mean += a[l].q[k] - b[l].q[k];
      mean /= static_cast<double>(std::max<std::size_t>(len, 1));
      double sse = 0.0;
      for (std::size_t k = 0; k < len; ++k) {
        const double e = a[l].q[k] - b[l].q[k] - mean;
        sse += e * e;
      }
      out.emplace_back(std::isfinite(sse) ? sse : 1e30, static_cast<long>(len));
    }
  };
  add(robot.train, sim.train);
  add(robot.heldout, sim.heldout);
  return out;
}

const std::vector<RobotFitEntry>& robotFitCatalogue() {
  static const std::vector<RobotFitEntry> entries = {
      {"pd_gain", "kp_scale", 0.5, 1.6, false},
      {"armature", "armature_kgm2", 0.002, 0.15, true},
      {"coulomb_friction", "fc_Nm", 0.05, 8.0, true},
      {"viscous_friction", "fv_Nms_per_rad", 0.05, 8.0, true},
      {"transport_delay", "delay_s", 0.0005, 0.03, true},
  };
  return entries;
}

ActuatorBlock blockFromParams(const std::map<std::string, double>& params) {
  ActuatorBlock b;
  for (const auto& [key, v] : params) {
    if (key == "kp_scale") b.kp_scale = v;
    else if (key == "armature_kgm2") b.armature_kgm2 = v;
    else if (key == "fc_Nm") b.params.fc_Nm = v;
    else if (key == "fv_Nms_per_rad") b.params.fv_Nms_per_rad = v;
    else if (key == "delay_s") b.params.delay_s = v;
    else throw std::invalid_argument("blockFromParams: unknown parameter '" + key + "'");
  }
  return b;
}

void RobotFitOptions::validate() const {
  auto check = [](bool ok, const char* field, double v, const char* range) {
    if (!ok) throw std::invalid_argument(fmt::format("RobotFitOptions.{} = {}: expected {}", field, v, range));
  };
  check(threads >= 1 && threads <= 64, "threads", threads, "1..64");
  check(grid >= 3 && grid <= 50, "grid", grid, "3..50");
  check(refine >= 2 && refine <= 50, "refine", refine, "2..50");
  check(max_causes >= 0 && max_causes <= 5, "max_causes", max_causes, "0..5");
  check(min_cv_gain > 0 && min_cv_gain < 1, "min_cv_gain", min_cv_gain, "(0, 1)");
  check(noise_z > 0 && std::isfinite(noise_z), "noise_z", noise_z, "> 0");
  check(min_over_floor >= 1 && std::isfinite(min_over_floor), "min_over_floor", min_over_floor, ">= 1");
}

namespace {

// Squared errors per log of one parameter set (cached by the caller's search).
using Sse = std::vector<std::pair<double, long>>;

double rms(const Sse& e, const std::vector<int>& logs) {
  double s = 0.0;
  long n = 0;
  for (int l : logs) {
    s += e[static_cast<std::size_t>(l)].first;
    n += e[static_cast<std::size_t>(l)].second;
  }
  return n > 0 ? std::sqrt(s / static_cast<double>(n)) : 0.0;
}

// One parameter's search: a grid over [lo, hi] shared by every fold (each evaluation scores every
// log), then a golden-section refinement per fold around that fold's best grid point.
struct ParamSearch {
  const RobotFitEntry& entry;
  std::function<Sse(double)> eval;  // squared errors per log at parameter value x
  int grid, refine;
  std::vector<std::pair<double, Sse>> grid_pts;

  double toU(double x) const { return entry.log_scale ? std::log(x) : x; }
  double fromU(double u) const { return entry.log_scale ? std::exp(u) : u; }

  void runGrid() {
    const double a = toU(entry.lo), b = toU(entry.hi);
    for (int k = 0; k < grid; ++k) {
      const double x = fromU(a + (b - a) * k / (grid - 1));
      grid_pts.emplace_back(x, eval(x));
    }
  }
  // The best value for the logs `fold` (minimising their RMS residual). @p resolution (optional)
  // receives half the final golden-section bracket in parameter units: how finely the search
  // located the minimum.
  std::pair<double, Sse> fit(const std::vector<int>& fold, double* resolution = nullptr) {
    std::size_t best = 0;
    for (std::size_t k = 1; k < grid_pts.size(); ++k)
      if (rms(grid_pts[k].second, fold) < rms(grid_pts[best].second, fold)) best = k;
    double a = toU(grid_pts[best > 0 ? best - 1 : 0].first);
    double b = toU(grid_pts[std::min(best + 1, grid_pts.size() - 1)].first);
    std::pair<double, Sse> top = grid_pts[best];
    const double g = 0.5 * (std::sqrt(5.0) - 1.0);
    double c = b - g * (b - a), d = a + g * (b - a);
    Sse fc = eval(fromU(c)), fd = eval(fromU(d));
    for (int it = 2; it < refine; ++it) {
      if (rms(fc, fold) < rms(fd, fold)) {
        b = d;
        d = c;
        fd = fc;
        c = b - g * (b - a);
        fc = eval(fromU(c));
      } else {
        a = c;
        c = d;
        fc = fd;
        d = a + g * (b - a);
        fd = eval(fromU(d));
      }
    }
    if (rms(fc, fold) < rms(top.second, fold)) top = {fromU(c), fc};
    if (rms(fd, fold) < rms(top.second, fold)) top = {fromU(d), fd};
    if (resolution) *resolution = 0.5 * (fromU(b) - fromU(a));
    return top;
  }
};

}  // namespace

RobotFitResult fitJointInRobot(const RobotConfig& model_in, const MujocoBackendOptions& options, int bus_latency_cycles,
                               int index, const JointCapture& robot_capture, const JointExcitation& ex,
                               const Eigen::VectorXd& hold_targets, double noise_floor_rad, const RobotFitOptions& opt) {
  opt.validate();
  if (robot_capture.train.size() != 2 || robot_capture.heldout.size() != 1)
    throw std::invalid_argument("fitJointInRobot(" + robot_capture.joint + "): expected 2 training logs and 1 held-out log");
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<int> fold_a{0}, fold_b{1}, train{0, 1}, heldout{2};
  RobotConfig model = model_in;
  model.joints.at(static_cast<std::size_t>(index)).actuator_yaml.clear();
  std::vector<std::unique_ptr<JointSimulator>> sims;
  for (int t = 0; t < opt.threads; ++t)
    sims.push_back(std::make_unique<JointSimulator>(model, options, bus_latency_cycles));
  auto evaluate = [&](JointSimulator& sim, const std::map<std::string, double>& params, bool with_heldout = false) {
    const std::optional<ActuatorBlock> block =
        params.empty() ? std::nullopt : std::optional<ActuatorBlock>(blockFromParams(params));
    return logSquaredErrors(robot_capture, sim.capture(index, block, ex, hold_targets, with_heldout));
  };
  // CV residual of a one-parameter addition to `fixed`: fit on each training log, score on the other.
  struct Trial {
    RobotFitModel model;
    Sse all_train_fit;  // squared errors at the parameter fitted on both training logs
  };
  auto trial = [&](JointSimulator& sim, const RobotFitEntry& e, const std::map<std::string, double>& fixed,
                   const std::map<std::string, double>& fixed_uncertainty) {
    ParamSearch ps{e, [&](double x) {
                     std::map<std::string, double> p = fixed;
                     p[e.key] = x;
                     return evaluate(sim, p);
                   },
                   opt.grid, opt.refine, {}};
    ps.runGrid();
    double resolution = 0.0;
    const auto fa = ps.fit(fold_a), fb = ps.fit(fold_b), ft = ps.fit(train, &resolution);
    const double sse = fa.second[1].first + fb.second[0].first;
    const long n = fa.second[1].second + fb.second[0].second;
    Trial tr;
    tr.model.name = e.name;
    tr.model.params = fixed;
    tr.model.params[e.key] = ft.first;
    tr.model.uncertainty = fixed_uncertainty;
    tr.model.uncertainty[e.key] = std::max({std::abs(fa.first - ft.first), std::abs(fb.first - ft.first), resolution});
    tr.model.cv_rad = std::sqrt(sse / static_cast<double>(std::max(n, 1L)));
    tr.all_train_fit = ft.second;
    return tr;
  };
  // Trials of every entry not yet chosen, spread over the threads.
  auto trials = [&](const RobotFitModel& base_model, const std::vector<const RobotFitEntry*>& entries) {
    std::vector<Trial> out(entries.size());
    std::vector<std::string> errors(entries.size());
    std::vector<std::thread> workers;
    for (std::size_t t = 0; t < sims.size(); ++t) {
      workers.emplace_back([&, t] {
        for (std::size_t k = t; k < entries.size(); k += sims.size()) {
          try {
            out[k] = trial(*sims[t], *entries[k], base_model.params, base_model.uncertainty);
          } catch (const std::exception& e) {
            errors[k] = e.what();
          }
        }
      });
    }
    for (auto& w : workers) w.join();
    for (const auto& e : errors)
      if (!e.empty()) throw std::runtime_error("fitJointInRobot(" + robot_capture.joint + "): " + e);
    return out;
  };

  RobotFitResult res;
  const Sse base = evaluate(*sims[0], {}, true);
  res.baseline.name = "baseline";
  res.baseline.cv_rad = rms(base, train);  // no parameter: its CV residual is its training residual
  res.baseline.heldout_rad = rms(base, heldout);
  res.baseline.verdict = "the nominal model";
  RobotFitModel current = res.baseline;
  std::vector<const RobotFitEntry*> remaining;
  for (const auto& e : robotFitCatalogue()) remaining.push_back(&e);
  for (int step = 0; step < opt.max_causes && !remaining.empty(); ++step) {
    // No room left: the model already explains the training logs to within min_over_floor x the
    // noise floor (rule 3 of every trial would fail), so no trial is run.
    if (!(current.cv_rad > opt.min_over_floor * noise_floor_rad)) {
      if (step == 0) res.baseline.verdict = "the nominal model already explains the training logs to within the noise: nothing tried";
      break;
    }
    std::vector<Trial> tr = trials(current, remaining);
    std::size_t best = 0;
    for (std::size_t k = 1; k < tr.size(); ++k)
      if (tr[k].model.cv_rad < tr[best].model.cv_rad) best = k;
    for (auto& t : tr) {
      t.model.gain = 1.0 - t.model.cv_rad / current.cv_rad;
      std::vector<std::string> fails;
      if (!(t.model.gain > opt.min_cv_gain)) fails.push_back(fmt::format("CV gain {:.3f} <= {:.2f}", t.model.gain, opt.min_cv_gain));
      if (!(current.cv_rad - t.model.cv_rad > opt.noise_z * noise_floor_rad))
        fails.push_back(fmt::format("CV drop {:.2g} rad <= {} x floor {:.2g} rad", current.cv_rad - t.model.cv_rad, opt.noise_z,
                                    noise_floor_rad));
      if (!(current.cv_rad > opt.min_over_floor * noise_floor_rad))
        fails.push_back(fmt::format("reference CV {:.2g} rad <= {} x floor", current.cv_rad, opt.min_over_floor));
      t.model.verdict = fails.empty() ? "significant" : fmt::format("{}", fmt::join(fails, "; "));
    }
    if (step == 0)
      for (const auto& t : tr) res.candidates.push_back(t.model);
    const Trial& b = tr[best];
    if (b.model.verdict != "significant") break;
    RobotFitModel chosen = b.model;
    chosen.verdict = step == 0 ? "chosen first: lowest CV residual, significant"
                               : "chosen: lowest CV residual with the earlier causes, significant";
    current = chosen;
    res.causes.push_back(chosen);
    remaining.erase(remaining.begin() + static_cast<std::ptrdiff_t>(best));
  }
  // Held-out residual, once, for each prefix of the chosen chain.
  for (auto& c : res.causes) c.heldout_rad = rms(evaluate(*sims[0], c.params, true), heldout);
  res.extended = res.causes.empty() ? res.baseline : res.causes.back();
  res.block = blockFromParams(res.extended.params);
  for (const auto& s : sims) res.evaluations += s->evaluations();
  res.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return res;
}

}  // namespace pmg::calib
