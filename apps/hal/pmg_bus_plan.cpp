// pmg_bus_plan: check a bus plan against the 2 ms cycle budget and print per-bus load and the
// send schedule inside the slot. Exit code 0 if the HAL would accept it, 1 if it would refuse it.
//
//   pmg_bus_plan config/hal/g1_can.yaml [--schedule] [--csv out.csv]
#include <cstdio>
#include <fstream>

#include <CLI/CLI.hpp>

#include "pmg/hal/bus/bus_plan.hpp"

int main(int argc, char** argv) {
  using namespace pmg::hal::bus;
  CLI::App app{"pmg_bus_plan: check a CAN bus plan against the HAL cycle budget"};
  std::string path, csv;
  bool schedule = false;
  app.add_option("plan", path, "bus plan YAML")->required()->check(CLI::ExistingFile);
  app.add_flag("--schedule", schedule, "print the per-bus send schedule inside the slot");
  app.add_option("--csv", csv, "write one row per motor: bus, id, joint, send/reply-due offsets, frame times [us], load (for apps/hal/plot_bus_plan.py)");
  CLI11_PARSE(app, argc, argv);
  try {
    BusPlanOptions o;
    const std::vector<BusConfig> buses = BusPlan::parseYaml(path, o);
    const BusPlanCheck check = checkBusPlan(buses, o);
    if (!check.ok) {
      std::printf("%s: REFUSED\n%s", path.c_str(), check.message.c_str());
      for (std::size_t b = 0; b < buses.size() && b < check.loads.size(); ++b)
        std::printf("  %-6s %2zu motors  load %5.1f %%\n", buses[b].name.c_str(), check.loads[b].motors,
                    100.0 * check.loads[b].load);
      return 1;
    }
    const BusPlan plan(buses, o, path);
    std::printf("%s: accepted (period %.3f ms, max load %.0f %%, turnaround %.0f us)\n%s", path.c_str(),
                1e3 * o.period_s, 100.0 * o.max_load, 1e6 * o.turnaround_s, plan.report().c_str());
    std::ofstream out;
    if (!csv.empty()) {
      out.open(csv);
      out << "bus,motor,joint,send_us,reply_due_us,command_us,reply_us,load\n";
    }
    for (std::size_t b = 0; b < plan.buses().size(); ++b) {
      for (const SlotEntry& e : plan.schedule()[b]) {
        const MotorSpec& m = plan.buses()[b].motors[static_cast<std::size_t>(e.motor)];
        if (schedule)
          std::printf("  %-6s %-28s send %7.1f us  reply due %7.1f us\n", plan.buses()[b].name.c_str(),
                      m.name.c_str(), 1e6 * e.send_offset_s, 1e6 * e.reply_due_s);
        if (out) out << plan.buses()[b].name << "," << int(m.motor_id) << "," << m.name << "," << 1e6 * e.send_offset_s
                     << "," << 1e6 * e.reply_due_s << "," << 1e6 * plan.loads()[b].command_s << ","
                     << 1e6 * plan.loads()[b].reply_s << "," << plan.loads()[b].load << "\n";
      }
    }
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "pmg_bus_plan: %s\n", e.what());
    return 2;
  }
}
