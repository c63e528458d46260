// JobStatus: what GET /v1/jobs/{id} says about a job (state, progress 0–100, attempts, priority, labels, the node
// that runs or ran it, timestamps, error), and JobPage: one page of GET /v1/jobs with the cursor of the next.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "texwarp/proto/enum_names.hpp"
#include "texwarp/proto/job_labels.hpp"
#include "texwarp/proto/job_spec.hpp"
#include "texwarp/proto/problem_details.hpp"

namespace texwarp::proto {

enum class JobState { kQueued, kRunning, kSucceeded, kFailed, kCanceled };

template <>
struct EnumNames<JobState> {
  static constexpr std::array<std::pair<JobState, const char*>, 5> kTable = {{{JobState::kQueued, "queued"},
                                                                              {JobState::kRunning, "running"},
                                                                              {JobState::kSucceeded, "succeeded"},
                                                                              {JobState::kFailed, "failed"},
                                                                              {JobState::kCanceled, "canceled"}}};
};

inline bool is_terminal(JobState state) {
  return state == JobState::kSucceeded || state == JobState::kFailed || state == JobState::kCanceled;
}

struct JobStatus {
  std::string id;
  std::string name;
  JobKind kind = JobKind::kImage;
  JobState state = JobState::kQueued;
  int progress = 0;  // percent, 0–100; never decreases while the job runs
  int attempts = 0;  // runs started (a restart re-runs a job that was running)
  bool cancel_requested = false;
  int priority = 0;
  JobLabels labels;
  std::string node;        // the node that holds (running) or last held the job; empty when it never ran
  std::string created_at;  // RFC 3339 UTC with milliseconds; started/finished empty until then
  std::string started_at;
  std::string finished_at;
  std::optional<ProblemDetails> error;  // when failed
};

struct JobPage {
  std::vector<JobStatus> jobs;  // newest first
  std::string next_cursor;      // empty on the last page
};

}  // namespace texwarp::proto
