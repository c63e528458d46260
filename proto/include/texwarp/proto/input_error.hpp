// InputError: the one exception type for input from outside that is wrong (bad JSON, out-of-range values,
// colliding features...). Carries where (a JSON path such as "$.features[3].source", or a file name) and what.
#pragma once

#include <stdexcept>
#include <string>

namespace texwarp {

class InputError : public std::runtime_error {
 public:
  InputError(std::string where, const std::string& what)
      : std::runtime_error(where.empty() ? what : where + ": " + what), where_(std::move(where)), what_(what) {}

  // The place in the input the error is about; empty when it is about the input as a whole.
  const std::string& where() const noexcept { return where_; }
  // The message without the place.
  const std::string& detail() const noexcept { return what_; }

 private:
  std::string where_;
  std::string what_;
};

}  // namespace texwarp
