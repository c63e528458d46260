// InputError: the one exception type for input from outside that is wrong (bad JSON, out-of-range values,
// colliding features...). Carries where (a typed InputLocation: JSON path, flag, file) and what.
#pragma once

#include <stdexcept>
#include <string>

#include "texwarp/proto/input_location.hpp"

namespace texwarp {

// Every layer throws InputError and names its place with these.
using proto::InputLocation;
using proto::JsonPath;

class InputError : public std::runtime_error {
 public:
  InputError(proto::InputLocation where, const std::string& detail)
      : std::runtime_error(with_place(where, detail)), where_(std::move(where)), detail_(detail) {}

  // The place in the input the error is about; empty when it is about the input as a whole.
  const proto::InputLocation& where() const noexcept { return where_; }
  // The message without the place.
  const std::string& detail() const noexcept { return detail_; }
  // "place: detail" with the location's file left out: what a server shows about a file it read itself.
  std::string message_without_file() const { return with_place(where_.without_file(), detail_); }

 private:
  static std::string with_place(const proto::InputLocation& where, const std::string& detail) {
    const std::string place = where.str();
    return place.empty() ? detail : place + ": " + detail;
  }

  proto::InputLocation where_;
  std::string detail_;
};

}  // namespace texwarp
