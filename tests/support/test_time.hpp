// How much longer a test waits for work to finish where everything runs slower: TEXWARP_TEST_TIME_SCALE (a positive
// number; scripts/sanitize.sh sets 4 under ASan, 10 under TSan), 1 when unset. Scaled: waits for work, and bounds that
// tell a fix from a pathology by a wide factor (milliseconds against 30 s), where both slow down alike.
#pragma once

#include <cstdlib>

namespace texwarp::testing {

inline double test_time_scale() {
  const char* text = std::getenv("TEXWARP_TEST_TIME_SCALE");
  const double scale = text ? std::strtod(text, nullptr) : 1.0;
  return scale > 0.0 ? scale : 1.0;
}

// `seconds` of waiting, scaled.
inline double wait_seconds(double seconds) { return seconds * test_time_scale(); }

}  // namespace texwarp::testing
