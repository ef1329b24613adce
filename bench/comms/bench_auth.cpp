// Added latency per message of the authenticated command channels (issue 13): signing
// (MessageSigner::sign, the commander side), verifying (MessageVerifier::verify) and the whole
// receive path with and without a key (LcmCommandDecoder::decode) for the velocity command
// (52-byte payload + 60-byte trailer) and the VR pose (281-byte payload). Google Benchmark:
//
//   build/bin/bench_auth --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <algorithm>
#include <cstdint>
#include <memory>
#include <vector>

#include <benchmark/benchmark.h>
#include <pmg_lcm/velocity_command_t.hpp>
#include <pmg_lcm/vr_pose_t.hpp>

#include "pmg/comms/auth.hpp"
#include "pmg/controller/lcm_command_source.hpp"

namespace {

using pmg::comms::AuthKey;

constexpr std::int64_t kNowUs = 1'700'000'000'000'000;
constexpr std::size_t kBatch = 1 << 14;  // pre-signed messages with increasing seq

template <class T>
std::vector<std::uint8_t> encode(const T& m) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(m.getEncodedSize()));
  m.encode(b.data(), 0, static_cast<int>(b.size()));
  return b;
}

std::vector<std::uint8_t> velocity() {
  pmg_lcm::velocity_command_t m;
  m.utime = kNowUs;
  m.vx = 0.4;
  m.vy = 0.1;
  m.wz = -0.2;
  m.source = "gamepad";
  return encode(m);
}

std::vector<std::uint8_t> vrPose() {
  pmg_lcm::vr_pose_t m{};
  m.utime = kNowUs;
  m.head_quat[0] = 1.0;
  m.hand_valid[0] = m.hand_valid[1] = 1;
  for (int k = 0; k < 2; ++k) {
    m.hand_quat[k][0] = 1.0;
    m.hand_position[k][0] = 0.3;
    m.grip[k] = 0.5;
  }
  m.head_position[2] = 1.6;
  m.source = "vr";
  return encode(m);
}

AuthKey benchKey() {
  std::array<std::uint8_t, pmg::comms::kAuthKeyBytes> b{};
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(i * 13 + 1);
  return AuthKey(b);
}

std::int64_t fixedClock(const void*) noexcept { return kNowUs; }

const char* channelOf(int which) { return which == 0 ? pmg::kVelocityChannel : pmg::kVrPoseChannel; }
std::vector<std::uint8_t> payloadOf(int which) { return which == 0 ? velocity() : vrPose(); }

std::vector<std::vector<std::uint8_t>> signedBatch(int which) {
  pmg::comms::MessageSigner signer(benchKey(), 7, 1);
  std::vector<std::vector<std::uint8_t>> batch(kBatch, payloadOf(which));
  for (auto& m : batch) signer.sign(channelOf(which), m, kNowUs);
  return batch;
}

void BM_Sign(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const std::vector<std::uint8_t> payload = payloadOf(which);
  std::vector<std::uint8_t> m;
  m.reserve(payload.size() + pmg::comms::kAuthTrailerBytes);
  pmg::comms::MessageSigner signer(benchKey(), 7, 1);
  for (auto _ : state) {
    m.assign(payload.begin(), payload.end());
    signer.sign(channelOf(which), m, kNowUs);
    benchmark::DoNotOptimize(m.data());
  }
  state.SetLabel(std::string(channelOf(which)) + ", " + std::to_string(payload.size()) + " B payload");
}

void BM_Verify(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const auto batch = signedBatch(which);
  auto verifier = std::make_unique<pmg::comms::MessageVerifier>(benchKey(), pmg::comms::VerifierOptions{}, &fixedClock);
  std::size_t i = 0, bad = 0, n = 0;
  for (auto _ : state) {
    if (i == batch.size()) {  // seq would repeat: a fresh verifier (not timed)
      state.PauseTiming();
      verifier = std::make_unique<pmg::comms::MessageVerifier>(benchKey(), pmg::comms::VerifierOptions{}, &fixedClock);
      i = 0;
      state.ResumeTiming();
    }
    const auto& m = batch[i++];
    bad += verifier->verify(channelOf(which), m.data(), m.size(), n) != pmg::comms::VerifyResult::kOk;
  }
  state.counters["rejected"] = static_cast<double>(bad);
  state.SetLabel(std::string(channelOf(which)) + ", " + std::to_string(batch[0].size()) + " B signed");
}

/// The controller's receive path per packet: plain (range(1) = 0) or authenticated (1).
void BM_Decode(benchmark::State& state) {
  const int which = static_cast<int>(state.range(0));
  const bool keyed = state.range(1) != 0;
  const std::vector<std::vector<std::uint8_t>> batch =
      keyed ? signedBatch(which) : std::vector<std::vector<std::uint8_t>>(kBatch, payloadOf(which));
  auto decoder = std::make_unique<pmg::LcmCommandDecoder>();
  const auto setup = [&] {
    decoder = std::make_unique<pmg::LcmCommandDecoder>();
    if (keyed) decoder->requireAuthentication(benchKey(), pmg::comms::VerifierOptions{}, &fixedClock);
  };
  setup();
  pmg::CommandSample sample;
  std::size_t i = 0, bad = 0;
  for (auto _ : state) {
    if (i == batch.size()) {
      state.PauseTiming();
      setup();
      i = 0;
      state.ResumeTiming();
    }
    const auto& m = batch[i++];
    bad += decoder->decode(channelOf(which), m.data(), m.size(), 1.0, sample) != pmg::DecodeResult::kAccepted;
  }
  state.counters["rejected"] = static_cast<double>(bad);
  state.SetLabel(std::string(channelOf(which)) + (keyed ? ", authenticated" : ", plain"));
}

// "min" next to mean/median/stddev: the least disturbed repetition on a shared machine.
double minOf(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }

}  // namespace

BENCHMARK(BM_Sign)->Arg(0)->Arg(1)->ComputeStatistics("min", minOf);
BENCHMARK(BM_Verify)->Arg(0)->Arg(1)->ComputeStatistics("min", minOf);
BENCHMARK(BM_Decode)->Args({0, 0})->Args({0, 1})->Args({1, 0})->Args({1, 1})->ComputeStatistics("min", minOf);
BENCHMARK_MAIN();
