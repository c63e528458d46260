// ServerConfig: everything texwarpd can be told, from flags and an optional config file (TOML/INI, keys are the
// long flag names), with the documented defaults; `texwarpd --help` lists them all.
#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "texwarp/proto/device_spec.hpp"
#include "texwarp/runner/job_runner.hpp"

namespace texwarp::server {

struct ServerConfig {
  std::string host = "127.0.0.1";  // --listen HOST:PORT; loopback unless told otherwise
  unsigned short port = 8080;      // 0: any free port (see port_file)
  std::filesystem::path data_dir = "texwarpd-data";
  std::filesystem::path cache_dir;  // compiled kernels; empty: the user's (opencl_backend.hpp, as `texwarp warm`)
  std::filesystem::path port_file;  // written with the bound port once listening
  int io_threads = 2;
  int workers = 1;
  int threads_per_job = 0;                  // CPU threads of one job; 0: all cores
  std::optional<proto::DeviceSpec> device;  // default device of jobs that name none (none: opencl when built with it)
  std::size_t max_queue = 256;              // queued jobs beyond which POST /v1/jobs answers 429
  std::size_t max_connections = 512;
  std::size_t max_connections_per_client = 64;  // open connections from one client address (IP)
  std::uint64_t max_job_body_bytes = 32ULL << 20;
  std::uint64_t max_blob_bytes = 256ULL << 20;
  std::uint32_t max_header_bytes = 16U << 10;
  runner::JobLimits limits;
  double read_timeout_s = 30.0;                    // a request's header, then its body
  double write_timeout_s = 60.0;                   // a response
  double idle_timeout_s = 30.0;                    // a keep-alive connection between requests
  double shutdown_grace_s = 20.0;                  // SIGTERM: running jobs get this long before they are re-queued
  int max_attempts = 3;                            // a job running at this many crashes is failed, not re-run
  double retention_hours = 0.0;                    // finished jobs and their files are deleted after this long; 0: kept
  std::vector<std::filesystem::path> input_roots;  // server-side paths allowed in jobs (none by default)
  std::string token;                               // bearer token; empty: no authentication
  std::string log_level = "info";
  // The job store and this node's part in a farm (docs: farm_contract; flags --store, --node-id, --lease-s, ...).
  std::string store = "sqlite";  // "sqlite" (under data_dir) or a postgresql:// (postgres://) libpq URI
  bool migrate = false;          // create/upgrade the store's schema, print its version and exit
  std::string node_id;           // empty: HOST:PORT (the machine's host name and the bound port)
  double lease_s = 30.0;         // a claimed job's lease; renewed every heartbeat_s
  double heartbeat_s = 1.0;      // < lease_s / 2
  int poll_ms = 250;             // idle workers look for queued jobs this often (and at once for a local submit)

  bool sqlite_store() const { return store == "sqlite"; }
};

// `store` without the password of a postgresql:// URI (PostgresJobStore::redacted), for logs and messages.
std::string redacted_store(const std::string& store);

// Parses flags (and --config FILE). Returns nullopt after printing help, `version` (for --version) or an error to
// stdout/stderr; *exit_code is then what main should return (0 for --help and --version, 2 for a usage error).
std::optional<ServerConfig> parse_server_config(int argc, char** argv, int* exit_code, const std::string& version);

// "HOST:PORT" or "[V6]:PORT" → host, port; std::invalid_argument otherwise.
std::pair<std::string, unsigned short> parse_listen_address(const std::string& text);

}  // namespace texwarp::server
