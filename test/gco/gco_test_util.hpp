#pragma once
// Shared fixtures of the GCO tests: the G1 leg model and a runner that feeds a synthetic template
// through GCO for a number of cycles and meters the foot slip with and without GCO.
#include <memory>
#include <string>

#include "g1_fixture.hpp"
#include "pmg/gco/foot_slip.hpp"
#include "pmg/gco/gco.hpp"
#include "pmg/gco/synthetic_gait.hpp"

namespace pmg::gco::test {

inline const std::string kG1Urdf = pmg::test::g1UrdfPath();

inline std::shared_ptr<const LegModel> g1Legs() {
  static const std::shared_ptr<const LegModel> model = LegModel::fromUrdfFile(kG1Urdf);
  return model;
}

struct RunResult {
  FootSlipStats with_gco;
  FootSlipStats without_gco;
  double max_jump_v = 0.0;   ///< max |Δu'_{v_x,v_y}| between ticks [m/s]
  double max_jump_w = 0.0;   ///< max |Δu'_ω| [rad/s]
  double max_jump_h = 0.0;   ///< max |Δu'_h| [m]
  GcoResult last;            ///< result of the final tick
  GcoCounters counters;
};

/// Runs `cycles` cycles of `gait` through a fresh Gco and through the no-GCO baseline.
inline RunResult runGait(const SyntheticGait& gait, const GcoOptions& options, int cycles) {
  RunResult rr;
  Gco gco(g1Legs(), options);
  FootSlipMeter with(g1Legs(), options.dt, options.ground_height);
  FootSlipMeter without(g1Legs(), options.dt, options.ground_height);
  bool first = true;
  BaseCommand prev;
  for (int c = 0; c < cycles; ++c) {
    for (const GcoInput& in : gait.ticks) {
      GcoResult res;
      gco.solve(in, &res);
      with.add(in, res.u_opt);
      BaseCommand tmpl;
      tmpl.v_x = in.v_HB_H.x();
      tmpl.v_y = in.v_HB_H.y();
      tmpl.yaw_rate = in.w_HB_H.z();
      tmpl.height = in.base_height;
      without.add(in, tmpl);
      if (!first) {
        rr.max_jump_v = std::max({rr.max_jump_v, std::abs(res.u_opt.v_x - prev.v_x), std::abs(res.u_opt.v_y - prev.v_y)});
        rr.max_jump_w = std::max(rr.max_jump_w, std::abs(res.u_opt.yaw_rate - prev.yaw_rate));
        rr.max_jump_h = std::max(rr.max_jump_h, std::abs(res.u_opt.height - prev.height));
      }
      first = false;
      prev = res.u_opt;
      rr.last = res;
    }
  }
  rr.with_gco = with.stats();
  rr.without_gco = without.stats();
  rr.counters = gco.counters();
  return rr;
}

}  // namespace pmg::gco::test
