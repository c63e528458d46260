// What an InputError says, for the suites that check error messages.
#pragma once

#include <string>

#include "texwarp/proto/input_error.hpp"

namespace texwarp::testing {

// The message of the InputError that f() throws; "" when it throws none (any other exception propagates).
template <typename F>
std::string input_error_of(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace texwarp::testing
