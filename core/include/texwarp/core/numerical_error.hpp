// NumericalError: the method could not meet its own guarantees (step size collapse, a non-finite value):
// a bug or an input beyond what validation caught; never silently turned into an output.
#pragma once

#include <stdexcept>
#include <string>

namespace texwarp {

class NumericalError : public std::runtime_error {
 public:
  explicit NumericalError(const std::string& what) : std::runtime_error(what) {}
};

}  // namespace texwarp
