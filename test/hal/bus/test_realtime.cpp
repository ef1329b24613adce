// Real-time helpers: the periodic runner counts cycles and overruns, records statistics, rejects
// bad options, and degrades gracefully when a privileged request is refused.
#include <gtest/gtest.h>
#include <unistd.h>

#include <thread>

#include "pmg/hal/realtime.hpp"

using namespace pmg::hal::rt;

TEST(PeriodicTask, RunsTheRequestedCyclesAndRecordsThem) {
  PeriodicOptions o;
  o.period_s = 0.001;
  int calls = 0;
  PeriodicTask t(o, [&calls] { ++calls; });
  t.runFor(40);
  EXPECT_EQ(calls, 40);
  EXPECT_EQ(t.timing().cycles(), 40);
  const pmg::TimingSummary s = t.timing().summary();
  // Paced by the clock, not run in a burst (a slow machine only makes periods longer).
  EXPECT_GE(s.period_p50, 0.5 * o.period_s);
  EXPECT_GT(s.runtime_max, 0.0);
}

TEST(PeriodicTask, CountsOverrunsAndReanchors) {
  PeriodicOptions o;
  o.period_s = 0.001;
  PeriodicTask t(o, [] { std::this_thread::sleep_for(std::chrono::microseconds(2500)); });
  t.runFor(6);
  // Every cycle takes longer than the period: each one overruns, none is run in a burst.
  EXPECT_EQ(t.overruns(), 6);
  EXPECT_GE(t.timing().summary().period_p50, 0.0025);
}

TEST(PeriodicTask, ThreadModeStartsAndStops) {
  PeriodicOptions o;
  o.period_s = 0.001;
  std::atomic<int> calls{0};
  PeriodicTask t(o, [&calls] { ++calls; });
  t.start();
  while (calls.load() < 5) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  t.stop();
  const int after = calls.load();
  std::this_thread::sleep_for(std::chrono::milliseconds(5));
  EXPECT_EQ(calls.load(), after) << "no cycles after stop()";
}

TEST(PeriodicTask, RefusedPrivilegesAreReportedNotFatal) {
  PeriodicOptions o;
  o.period_s = 0.001;
  o.fifo_priority = 10;
  o.cpu = 100000;  // no such CPU
  PeriodicTask t(o, [] {});
  const RtReport r = t.runFor(3);
  EXPECT_FALSE(r.affinity);
  EXPECT_NE(r.notes.find("cpu 100000"), std::string::npos) << r.notes;
  // SCHED_FIFO is granted with CAP_SYS_NICE / an RLIMIT_RTPRIO, refused otherwise: either way the
  // task ran and the report is consistent.
  EXPECT_EQ(r.fifo, r.notes.find("SCHED_FIFO") == std::string::npos) << r.notes;
  EXPECT_EQ(t.timing().cycles(), 3);
}

TEST(PeriodicTask, InvalidOptionsThrow) {
  PeriodicOptions o;
  o.period_s = 0.0;
  EXPECT_THROW(PeriodicTask(o, [] {}), std::invalid_argument);
  o = PeriodicOptions{};
  o.fifo_priority = 120;
  EXPECT_THROW(PeriodicTask(o, [] {}), std::invalid_argument);
  EXPECT_THROW(PeriodicTask(PeriodicOptions{}, std::function<void()>{}), std::invalid_argument);
}

TEST(Realtime, SleepUntilIsAbsolute) {
  const double t0 = now();
  sleepUntil(t0 + 0.003);
  EXPECT_GE(now(), t0 + 0.003);
  const double t1 = now();
  sleepUntil(t1 - 1.0);  // a deadline in the past returns at once
  EXPECT_LT(now() - t1, 0.5);
}
