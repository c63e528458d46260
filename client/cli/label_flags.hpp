// The `--label KEY=VALUE` flags of `texwarp submit` and `texwarp list`: parsed and checked with the wire format's own
// label check, so that a bad label is refused here, naming the flag, before anything is sent.
#pragma once

#include <string>
#include <vector>

#include "texwarp/proto/job_labels.hpp"

namespace texwarp::cli {

// Each "KEY=VALUE" (split at the first '='; the value may hold '=' and be empty). InputError at --label for a
// flag without '=', a key given twice, more than proto::kMaxJobLabels labels, or a key or value the wire format
// refuses.
proto::JobLabels parse_label_flags(const std::vector<std::string>& flags);

}  // namespace texwarp::cli
