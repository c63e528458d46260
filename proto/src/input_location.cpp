// Input locations: see input_location.hpp.
#include "texwarp/proto/input_location.hpp"

namespace texwarp::proto {

InputLocation InputLocation::flag(std::string name) {
  InputLocation where;
  where.flag_ = std::move(name);
  return where;
}

InputLocation InputLocation::file(std::string name) {
  InputLocation where;
  where.file_ = std::move(name);
  return where;
}

InputLocation InputLocation::in_file(std::string name) const {
  InputLocation where = *this;
  if (where.file_.empty()) where.file_ = std::move(name);
  return where;
}

InputLocation InputLocation::rebased(const JsonPath& base) const { return path_ ? path_->rebased(base) : base; }

InputLocation InputLocation::without_file() const {
  InputLocation where = *this;
  where.file_.clear();
  return where;
}

std::string InputLocation::str() const {
  std::string place = path_ ? path_->str() : flag_;
  if (file_.empty()) return place;
  return place.empty() ? file_ : file_ + ": " + place;
}

}  // namespace texwarp::proto
