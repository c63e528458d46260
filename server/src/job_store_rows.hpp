// What both job stores write the same way: labels as a JSON object of strings, the state names, and the problem a
// job gets when its leases ran out too often. Private to the store implementations.
#pragma once

#include <string>

#include "texwarp/server/job_store.hpp"

namespace texwarp::server::store_rows {

// {"k": "v", ...}; "{}" when empty.
std::string encode_labels(const Labels& labels);
// The inverse; throws std::runtime_error naming `where` (the column and job) when the text is not such an object.
Labels decode_labels(const std::string& json, const std::string& where);

// A state column's value; throws std::runtime_error naming `where` when it is not a state.
proto::JobState decode_state(const std::string& text, const std::string& where);
proto::JobKind decode_kind(const std::string& text, const std::string& where);

// The failed job's error after `max_attempts` leases ended without an outcome (kAttemptsExhausted problem JSON).
std::string attempts_exhausted_error(int max_attempts);

// std::invalid_argument unless `state` is final (succeeded, failed, canceled): what finish() may record.
void require_final_state(proto::JobState state);

}  // namespace texwarp::server::store_rows
