// The farm commands of `texwarp`: submit, status, list, wait, fetch, cancel, purge and nodes against a texwarpd
// (through libtexwarp_client, whose retries outlast a server restart: --retry-budget), and run (a job file run here,
// with no server). Shared options and exit codes: 0 success; 1 failure (the job failed, the server or the network
// failed); 2 invalid input (bad arguments, a job or request the server refused with a 4xx, a job in the wrong state
// for the command); 3 the job was canceled; 4 timed out (`wait --timeout`, or no answer).
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "cli_command.hpp"
#include "texwarp/client/client.hpp"
#include "texwarp/proto/input_error.hpp"

namespace texwarp::cli {

inline constexpr int kExitTimedOut = 4;

// Where the server is: --server (else TEXWARP_SERVER, else http://127.0.0.1:8080) and its token: --token-file
// (else TEXWARP_TOKEN); how long each request may keep retrying: --retry-budget (else TEXWARP_RETRY_BUDGET, else
// the library's 60 s).
struct ServerArgs {
  std::string server;
  std::string token_file;
  double request_timeout_s = 120.0;
  std::optional<double> retry_budget_s;
};

inline constexpr double kMaxRetryBudgetS = 7.0 * 24 * 3600;  // a week: beyond it a number is surely a mistake

// Seconds of retry budget from TEXWARP_RETRY_BUDGET (a number in [0, a week]); InputError naming it otherwise.
inline double retry_budget_from_env(const char* text) {
  char* end = nullptr;
  const double value = std::strtod(text, &end);
  if (end == text || *end != '\0' || !std::isfinite(value) || value < 0.0 || value > kMaxRetryBudgetS) {
    throw InputError(InputLocation::flag("TEXWARP_RETRY_BUDGET"),
                     std::string("expected seconds between 0 and ") +
                         std::to_string(static_cast<int>(kMaxRetryBudgetS)) + ", got \"" + text + "\"");
  }
  return value;
}

inline void add_server_options(CLI::App& command, ServerArgs& args) {
  command.add_option("--server", args.server,
                     "texwarpd base URL, http://HOST:PORT (default: $TEXWARP_SERVER, else http://127.0.0.1:8080)");
  command.add_option("--token-file", args.token_file, "file holding the bearer token (default: $TEXWARP_TOKEN)")
      ->check(CLI::ExistingFile);
  command.add_option("--request-timeout", args.request_timeout_s, "seconds for one HTTP exchange (default 120)")
      ->check(CLI::PositiveNumber);
  command
      .add_option("--retry-budget", args.retry_budget_s,
                  "seconds each request keeps retrying an unreachable or busy server, e.g. one restarting "
                  "(default: $TEXWARP_RETRY_BUDGET, else 60; 0: no retries)")
      ->check(CLI::Range(0.0, kMaxRetryBudgetS));
}

inline client::Client make_client(const ServerArgs& args) {
  client::ClientOptions options;
  if (!args.server.empty()) {
    options.server = args.server;
  } else if (const char* env = std::getenv("TEXWARP_SERVER"); env && *env) {
    options.server = env;
  }
  if (!args.token_file.empty()) {
    std::ifstream in(args.token_file);
    std::stringstream ss;
    ss << in.rdbuf();
    options.token = ss.str();
    while (!options.token.empty() && std::isspace(static_cast<unsigned char>(options.token.back())))
      options.token.pop_back();
  } else if (const char* env = std::getenv("TEXWARP_TOKEN"); env && *env) {
    options.token = env;
  }
  options.request_timeout = std::chrono::milliseconds(static_cast<long long>(args.request_timeout_s * 1000.0));
  if (args.retry_budget_s) {
    options.retry_budget = std::chrono::milliseconds(static_cast<long long>(*args.retry_budget_s * 1000.0));
  } else if (const char* env = std::getenv("TEXWARP_RETRY_BUDGET"); env && *env) {
    options.retry_budget = std::chrono::milliseconds(static_cast<long long>(retry_budget_from_env(env) * 1000.0));
  }
  return client::Client(options);
}

// Prints the error on stderr and returns the exit code for it.
inline int report_client_error(const client::ClientError& e) {
  std::fprintf(stderr, "texwarp: %s\n", e.message.c_str());
  if (e.problem && !e.problem->path.empty() && e.message.find(e.problem->path) == std::string::npos) {
    std::fprintf(stderr, "texwarp: at %s\n", e.problem->path.c_str());
  }
  switch (e.code) {
    case client::ErrorCode::kInvalidArgument:
    case client::ErrorCode::kWrongState:
      return kExitInvalidInput;
    case client::ErrorCode::kHttp:
      return (e.http_status >= 400 && e.http_status < 500 && e.http_status != 408 && e.http_status != 429)
                 ? kExitInvalidInput
                 : kExitFailure;
    case client::ErrorCode::kJobCanceled:
      return kExitCanceled;
    case client::ErrorCode::kTimeout:
      return kExitTimedOut;
    default:
      return kExitFailure;
  }
}

// Waits for the job (the library's long-poll), printing "texwarp: job ID STATE N%" lines on stderr (unless quiet)
// and the final status as JSON on stdout; returns the exit code: 0 succeeded, 1 failed, 3 canceled, 4 timed out
// (timeout_s 0: no limit). A server that goes away meanwhile is asked again within the client's retry budget.
int wait_for_job(client::Client& client, const std::string& id, double timeout_s, bool quiet);

void add_submit_command(CLI::App& root, Action& action);
void add_status_command(CLI::App& root, Action& action);
void add_wait_command(CLI::App& root, Action& action);
void add_fetch_command(CLI::App& root, Action& action);
void add_cancel_command(CLI::App& root, Action& action);
void add_list_command(CLI::App& root, Action& action);
void add_purge_command(CLI::App& root, Action& action);
void add_nodes_command(CLI::App& root, Action& action);
void add_run_command(CLI::App& root, Action& action);

}  // namespace texwarp::cli
