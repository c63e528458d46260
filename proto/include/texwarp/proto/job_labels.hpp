// Job labels: key/value pairs a farm tags its jobs with (the job body's "labels", the list filter ?label=k=v), their
// limits, and the one check of a key and a value that both the body's decoder and the query's parser use. JSON codec:
// job_labels_codec.hpp.
#pragma once

#include <cstddef>
#include <map>
#include <string>

#include "texwarp/proto/export.hpp"
#include "texwarp/proto/input_location.hpp"

namespace texwarp::proto {

using JobLabels = std::map<std::string, std::string>;

inline constexpr std::size_t kMaxJobLabels = 32;
inline constexpr std::size_t kMaxLabelKeyLength = 63;     // bytes of [A-Za-z0-9_.\-/]
inline constexpr std::size_t kMaxLabelValueLength = 256;  // bytes of UTF-8

// InputError at `key_at` for a key that is empty, longer than kMaxLabelKeyLength or has a character outside
// [A-Za-z0-9_.-/]; at `value_at` for a value longer than kMaxLabelValueLength bytes or not UTF-8.
TEXWARP_API void check_job_label(const std::string& key, const std::string& value, const InputLocation& key_at,
                                 const InputLocation& value_at);

}  // namespace texwarp::proto
