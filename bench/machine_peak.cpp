// Clock and FMA throughput of the machine: see machine_peak.hpp.
#include "machine_peak.hpp"

#include <algorithm>
#include <ctime>
#include <fstream>
#include <thread>
#include <vector>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace texwarp::bench {
namespace {

// CPU time of the calling thread: the clock and FMA figures must not see time the thread spent preempted by
// other processes on a shared machine.
double thread_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

#if defined(__x86_64__)
// One add per cycle on a dependent chain: cycles per second. The addend is a register: recent cores (Golden Cove,
// here) fold an immediate add into the register renamer, and a chain of `add $1` then ran at 8–12 adds per cycle
// (the benchmark reported a 7 GHz clock); register adds take their cycle, as a chain of 3-cycle imuls agreed
// (2.9 GHz on this 2.3 GHz-nominal machine).
double measure_clock_ghz() {
  long remaining = 400000000;
  long x = 0;
  const long one = 1;
  const double start = thread_seconds();
  asm volatile("1:\n\t"
               "add %2, %0\n\t"
               "add %2, %0\n\t"
               "add %2, %0\n\t"
               "add %2, %0\n\t"
               "sub $4, %1\n\t"
               "jnz 1b"
               : "+r"(x), "+r"(remaining)
               : "r"(one));
  return 400000000.0 / (thread_seconds() - start) / 1e9;
}

// 16 independent chains of 512-bit FMAs: enough in flight for 2 pipes of latency 4.
__attribute__((target("avx512f"))) float fma_chains(long iterations) {
  __m512 acc[16];
  for (int i = 0; i < 16; ++i) acc[i] = _mm512_set1_ps(1.0f + 1e-7f * static_cast<float>(i));
  const __m512 b = _mm512_set1_ps(0.9999999f);
  const __m512 c = _mm512_set1_ps(1e-7f);
  for (long k = 0; k < iterations; ++k) {
#pragma GCC unroll 16
    for (__m512& a : acc) a = _mm512_fmadd_ps(a, b, c);  // unrolled: accumulators in registers
  }
  __m512 sum = acc[0];
  for (int i = 1; i < 16; ++i) sum = _mm512_add_ps(sum, acc[i]);
  alignas(64) float lanes[16];
  _mm512_store_ps(lanes, sum);
  float total = 0.0f;
  for (const float x : lanes) total += x;
  return total;
}

// Every core running FMA chains at once; each thread's rate over its own CPU time, summed.
double measure_fma_gflops(int threads) {
  constexpr long kIterations = 50000000;
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads));
  std::vector<double> rate(static_cast<std::size_t>(threads));
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&rate, t] {
      const double start = thread_seconds();
      volatile float sink = fma_chains(kIterations);
      (void)sink;
      rate[static_cast<std::size_t>(t)] =
          2.0 * 16.0 * 16.0 * static_cast<double>(kIterations) / (thread_seconds() - start);
    });
  }
  for (auto& th : pool) th.join();
  double total = 0.0;
  for (const double r : rate) total += r;
  return total / 1e9;
}
#endif

}  // namespace

MachinePeak measure_machine_peak() {
  MachinePeak m;
  m.cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::ifstream cpuinfo("/proc/cpuinfo");
  std::string line;
  while (std::getline(cpuinfo, line)) {
    const auto colon = line.find(':');
    if (colon == std::string::npos) continue;
    const std::string key = line.substr(0, line.find_last_not_of(" \t", colon - 1) + 1);
    const std::string value = line.substr(colon + 2 <= line.size() ? colon + 2 : line.size());
    if (key == "model name" && m.cpu_model.empty()) m.cpu_model = value;
    if (key == "cpu MHz" && m.nominal_ghz == 0.0) m.nominal_ghz = std::stod(value) / 1000.0;
  }
  m.fma_units_note =
      "2 FMA units per core assumed (AVX-512 server cores with two 512-bit FMA pipes: Zen 5, Skylake-SP Gold/"
      "Platinum); the measured FMA throughput below checks it";
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx512f")) {
    m.measured_ghz = measure_clock_ghz();
    m.measured_fma_gflops = measure_fma_gflops(m.cores);
  }
#endif
  return m;
}

}  // namespace texwarp::bench
