#pragma once
/// @file cli_checks.hpp
/// CLI11 validators the tools share. CLI::Range lets NaN through (every comparison with NaN is
/// false), so numeric options that must be finite use pmg::cli::finiteIn(lo, hi) instead.

#include <cmath>
#include <string>

#include <CLI/CLI.hpp>

namespace pmg::cli {

/// A finite number in [lo, hi]; "nan", "inf" and anything unparsable are refused with the range.
inline CLI::Validator finiteIn(double lo, double hi) {
  const std::string range = "a finite number in [" + CLI::detail::to_string(lo) + ", " + CLI::detail::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(text, v) || !std::isfinite(v) || v < lo || v > hi)
          return "'" + text + "': expected " + range;
        return {};
      },
      "FINITE in [" + CLI::detail::to_string(lo) + " - " + CLI::detail::to_string(hi) + "]");
}

}  // namespace pmg::cli
