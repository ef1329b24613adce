// pmg_log_export: converts the PMG_STATE telemetry of an LCM event log (lcm-logger format, as
// written by pmg_controller --log) into a CSV table for plotting and analysis.
//
//   pmg_log_export --log run.lcmlog --csv run.csv [--robot config/robots/g1/g1.yaml]
// The robot config defaults to the G1's in pmg's data directory (pmg::dataDir()). A log that ends in
// a partial event (truncated: the logger or the controller was killed) or holds bytes between events
// is still exported up to its last complete event, with a warning and exit code 2.
// Columns: t, mode, phase, vx, vy, wz, pitch, roll, height, opt_* (u' after GCO), gco_status, contact_l, contact_r, base_x/y/z,
// then q_<joint>, q_ref_<joint>, tau_<joint> for every joint of the robot config.
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>

#include "pmg/common/data_paths.hpp"
#include "pmg/common/robot_config.hpp"

int main(int argc, char** argv) {
  CLI::App app{"pmg_log_export: PMG_STATE of an LCM event log -> CSV"};
  std::string log_path, csv_path, robot_path = pmg::resolveData("config/robots/g1/g1.yaml").string();
  app.add_option("--log", log_path, "LCM event log")->required()->check(CLI::ExistingFile);
  app.add_option("--csv", csv_path, "output CSV")->required();
  app.add_option("--robot", robot_path, "robot config (joint names)")->check(CLI::ExistingFile)->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  try {
    const pmg::RobotConfig robot = pmg::loadRobotConfig(robot_path);
    lcm::LogFile log(log_path, "r");
    if (!log.good()) throw std::runtime_error(log_path + ": cannot open LCM log");
    std::ofstream csv(csv_path);
    if (!csv) throw std::runtime_error(csv_path + ": cannot write");
    csv << "t,mode,phase,vx,vy,wz,pitch,roll,height,opt_vx,opt_vy,opt_wz,opt_pitch,opt_roll,opt_height,"
           "fb_vx,fb_vy,fb_wz,est_vx,est_vy,est_wz,fb_pitch,fb_roll,fb_height,gco_status,"
           "contact_l,contact_r,base_x,base_y,base_z,fault";
    for (const auto& prefix : {"q_", "q_ref_", "tau_"})
      for (const auto& j : robot.joints) csv << ',' << prefix << j.name;
    csv << '\n';
    long rows = 0, skipped = 0, events = 0;
    // lcm-logger event framing: sync word, event number, timestamp, channel length, data length
    // (4 + 8 + 8 + 4 + 4 bytes), channel, data. LCM's reader skips bytes up to the next sync word and
    // stops silently at a partial event; compare what it consumed with what the events account for.
    constexpr long kEventHeaderBytes = 28;
    long consumed_by_events = 0, end_of_last_event = 0;
    pmg_lcm::controller_state_t m;
    while (const lcm::LogEvent* ev = log.readNextEvent()) {
      ++events;
      consumed_by_events += kEventHeaderBytes + static_cast<long>(ev->channel.size()) + ev->datalen;
      end_of_last_event = std::ftell(log.getFilePtr());
      if (ev->channel != "PMG_STATE") continue;
      if (m.decode(ev->data, 0, ev->datalen) < 0 || m.num_joints != static_cast<int>(robot.numJoints())) {
        ++skipped;
        continue;
      }
      char buf[64];
      csv << 1e-6 * static_cast<double>(m.utime) << ',' << int(m.mode) << ',' << m.phase;
      for (double c : m.command) csv << ',' << c;
      for (double c : m.command_opt) csv << ',' << c;
      for (double c : m.command_feedback) csv << ',' << c;
      for (double c : m.velocity_estimate) csv << ',' << c;
      for (double c : m.posture_feedback) csv << ',' << c;
      csv << ',' << m.gco_status;
      csv << ',' << int(m.in_contact[0]) << ',' << int(m.in_contact[1]);
      for (double p : m.base_position) csv << ',' << p;
      csv << ',' << m.fault;
      for (const auto* vec : {&m.q, &m.q_ref, &m.tau})
        for (double v : *vec) {
          std::snprintf(buf, sizeof(buf), ",%.6g", v);
          csv << buf;
        }
      csv << '\n';
      ++rows;
    }
    std::printf("%s: %ld PMG_STATE rows -> %s (%ld undecodable or wrong joint count skipped)\n", log_path.c_str(),
                rows, csv_path.c_str(), skipped);
    const auto file_size = static_cast<long>(std::filesystem::file_size(log_path));
    if (end_of_last_event != file_size || consumed_by_events != end_of_last_event) {
      std::fprintf(stderr,
                   "pmg_log_export: warning: %s is truncated or corrupt: %ld complete events end at byte %ld of %ld, "
                   "%ld bytes between events skipped; exported the complete events only\n",
                   log_path.c_str(), events, end_of_last_event, file_size, end_of_last_event - consumed_by_events);
      return 2;
    }
    return rows > 0 ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_log_export: %s\n", e.what());
    return 1;
  }
}
