// pmg_test_state_log: writes a small event log in the format of `pmg_controller --log` (PMG_STATE
// events of pmg_lcm::controller_state_t, lcm-logger framing) for the tool tests of test/apps,
// which must not depend on a controller run.
//   pmg_test_state_log OUT.lcmlog EVENTS JOINTS
#include <cstdio>
#include <cstdlib>
#include <string>

#include <lcm/lcm-cpp.hpp>
#include <pmg_lcm/controller_state_t.hpp>

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: pmg_test_state_log OUT.lcmlog EVENTS JOINTS\n");
    return 2;
  }
  const std::string path = argv[1];
  const int events = std::atoi(argv[2]), joints = std::atoi(argv[3]);
  if (events < 1 || joints < 1) {
    std::fprintf(stderr, "pmg_test_state_log: EVENTS and JOINTS must be >= 1\n");
    return 2;
  }
  lcm::LogFile log(path, "w");
  if (!log.good()) {
    std::fprintf(stderr, "pmg_test_state_log: %s: cannot write\n", path.c_str());
    return 1;
  }
  pmg_lcm::controller_state_t m{};
  m.num_joints = joints;
  for (auto* v : {&m.q, &m.qd, &m.tau, &m.q_ref, &m.qd_ref}) v->assign(static_cast<std::size_t>(joints), 0.0);
  m.mode = 2;  // active
  m.base_quat[0] = 1.0;
  std::string buffer;
  for (int k = 0; k < events; ++k) {
    m.utime = 10000LL * k;  // 100 Hz
    m.tick = k;
    m.phase = 0.01 * (k % 100);
    for (int j = 0; j < joints; ++j) {
      m.q[static_cast<std::size_t>(j)] = 0.001 * (j + k);
      m.q_ref[static_cast<std::size_t>(j)] = 0.001 * (j + k) + 0.0005;
    }
    buffer.resize(static_cast<std::size_t>(m.getEncodedSize()));
    m.encode(buffer.data(), 0, static_cast<int>(buffer.size()));
    lcm::LogEvent ev;
    ev.eventnum = k;
    ev.timestamp = m.utime;
    ev.channel = "PMG_STATE";
    ev.datalen = static_cast<int32_t>(buffer.size());
    ev.data = buffer.data();
    if (log.writeEvent(&ev) != 0) {
      std::fprintf(stderr, "pmg_test_state_log: %s: write failed\n", path.c_str());
      return 1;
    }
  }
  return 0;
}
