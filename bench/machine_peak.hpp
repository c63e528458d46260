// The machine's FP32 FMA peak for the benchmark's "fraction of peak": from the nominal clock (/proc/cpuinfo) and,
// where the CPU has AVX-512, from a measured clock and a measured FMA throughput.
#pragma once

#include <string>

namespace texwarp::bench {

struct MachinePeak {
  std::string cpu_model;
  int cores = 1;      // hardware threads the benchmark may use
  int lanes = 16;     // FP32 lanes per vector (AVX-512)
  int fma_units = 2;  // FMA pipes per core (assumed, see fma_units_note)
  std::string fma_units_note;
  double nominal_ghz = 0.0;          // "cpu MHz" of /proc/cpuinfo
  double measured_ghz = 0.0;         // a dependent chain of register adds (1 per cycle); 0 when not measured
  double measured_fma_gflops = 0.0;  // 16 independent AVX-512 FMA chains on every core; 0 when not measured

  // lanes × FMA units × 2 flops × clock × cores, GFLOP/s.
  double peak_gflops(double ghz) const { return lanes * fma_units * 2.0 * ghz * cores; }
};

MachinePeak measure_machine_peak();

}  // namespace texwarp::bench
