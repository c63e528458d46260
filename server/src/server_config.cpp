// texwarpd configuration from flags and a config file: see server_config.hpp.
#include "texwarp/server/server_config.hpp"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include <CLI/CLI.hpp>

#include "texwarp/proto/input_error.hpp"
#include "texwarp/runner/backend_cache.hpp"
#include "texwarp/server/postgres_job_store.hpp"

namespace texwarp::server {
namespace {

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t\r\n");
  const auto e = s.find_last_not_of(" \t\r\n");
  return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
}

std::string read_token_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("--token-file: cannot read " + path);
  std::stringstream ss;
  ss << in.rdbuf();
  std::string token = trim(ss.str());
  if (token.empty()) throw std::invalid_argument("--token-file: " + path + " is empty");
  return token;
}

std::string short_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

bool has_prefix(const std::string& s, std::string_view prefix) { return s.rfind(prefix, 0) == 0; }

// "sqlite" or a PostgreSQL URI; std::invalid_argument (the password left out) otherwise.
std::string checked_store(const std::string& store) {
  if (store.empty() || store == "sqlite") return "sqlite";
  if (has_prefix(store, "postgresql://") || has_prefix(store, "postgres://")) return store;
  throw std::invalid_argument(
      R"(--store: expected "sqlite" or a PostgreSQL URI postgresql://USER@HOST:PORT/DB, got ")" +
      redacted_store(store).substr(0, 120) + "\"");
}

}  // namespace

std::string redacted_store(const std::string& store) {
  // One redaction for every URL (the store's, which reads a URL as libpq does); a word like "sqlite" has none.
  if (store.find("://") == std::string::npos) return store;
  return PostgresJobStore::redacted(store);
}

std::pair<std::string, unsigned short> parse_listen_address(const std::string& text) {
  const auto colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) {
    throw std::invalid_argument("--listen: expected HOST:PORT (e.g. 127.0.0.1:8080), got \"" + text + "\"");
  }
  std::string host = text.substr(0, colon);
  if (host.front() == '[' && host.back() == ']') host = host.substr(1, host.size() - 2);
  const std::string port_text = text.substr(colon + 1);
  char* end = nullptr;
  const long port = std::strtol(port_text.c_str(), &end, 10);
  if (*end != '\0' || port < 0 || port > 65535) {
    throw std::invalid_argument("--listen: the port must be a number from 0 to 65535, got \"" + port_text + "\"");
  }
  return {host, static_cast<unsigned short>(port)};
}

std::optional<ServerConfig> parse_server_config(int argc, char** argv, int* exit_code, const std::string& version) {
  ServerConfig c;
  CLI::App app("texwarpd: the texwarp HTTP/JSON batch service (jobs in, warped textures, UVs and reports out)");
  app.footer(
      "Environment: TEXWARPD_TOKEN (bearer token when --token-file is not given), POCL_CACHE_DIR (OpenCL compile "
      "cache).\nA config file holds the same long option names, e.g. `workers = 2` (TOML) or `workers=2` (INI).\n"
      "Exit codes: 0 clean shutdown (SIGTERM/SIGINT), 1 failure at run time, 2 bad configuration.");
  app.set_version_flag("--version", version, "print the version and the git commit texwarpd was built from, and exit");
  app.set_config("--config", "", "read options from this TOML/INI file (flags given on the command line win)");
  app.allow_config_extras(CLI::config_extras_mode::error);  // a misspelt key in the file is an error, not ignored
  std::string listen = "127.0.0.1:8080";
  std::string data_dir = c.data_dir.string();
  std::string port_file;
  std::string token_file;
  std::vector<std::string> roots;
  double max_image_megapixels = static_cast<double>(c.limits.image.max_pixels) / 1e6;
  double max_output_megapixels = static_cast<double>(c.limits.max_output_pixels) / 1e6;
  std::uint64_t max_job_body_mb = c.max_job_body_bytes >> 20;
  std::uint64_t max_blob_mb = c.max_blob_bytes >> 20;
  std::uint64_t max_mesh_mb = static_cast<std::uint64_t>(c.limits.max_mesh_bytes) >> 20;
  std::uint64_t max_job_memory_mb = 0;
  std::string device;
  app.add_option("--listen", listen, "address and port to listen on; 127.0.0.1 keeps it on this machine")
      ->capture_default_str();
  app.add_option("--data-dir", data_dir, "folder for the job database, blobs and results (created if missing)")
      ->capture_default_str();
  std::string cache_dir;
  app.add_option("--cache-dir", cache_dir,
                 "folder for compiled kernels, kept between starts (default: $TEXWARP_CACHE_DIR, else "
                 "$XDG_CACHE_HOME/texwarp or ~/.cache/texwarp, as `texwarp warm`)");
  app.add_option("--port-file", port_file, "write the bound port here once listening (useful with --listen HOST:0)");
  app.add_option("--io-threads", c.io_threads, "threads serving HTTP (they never run a warp)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  app.add_option("--workers", c.workers, "jobs run at the same time")->check(CLI::Range(1, 64))->capture_default_str();
  app.add_option("--threads-per-job", c.threads_per_job, "CPU threads of one job (0: all cores)")
      ->check(CLI::Range(0, 1024))
      ->capture_default_str();
  app.add_option("--device", device,
                 std::string("default device of jobs that name none: cpu, opencl or opencl:<name> (default: ") +
                     runner::default_device() + ")");
  app.add_option("--max-queue", c.max_queue, "queued jobs beyond which POST /v1/jobs answers 429 with Retry-After")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  app.add_option("--max-connections", c.max_connections, "open connections beyond which new ones get 503")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--max-connections-per-client", c.max_connections_per_client,
                 "open connections from one client address beyond which its new ones get 503")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--max-job-body-mb", max_job_body_mb, "largest POST /v1/jobs body, MiB (inline images count)")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app.add_option("--max-blob-mb", max_blob_mb, "largest POST /v1/blobs upload, MiB")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  app.add_option("--max-header-bytes", c.max_header_bytes, "largest request header block")
      ->check(CLI::Range(1024, 1 << 20))
      ->capture_default_str();
  app.add_option("--max-image-megapixels", max_image_megapixels, "largest input texture (checked from its header)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-image-side", c.limits.image.max_dimension, "largest input texture side, pixels")
      ->check(CLI::Range(1, 1 << 20))
      ->capture_default_str();
  app.add_option("--max-image-channels", c.limits.image.max_channels, "most channels of an input texture")
      ->check(CLI::Range(1, 4))
      ->capture_default_str();
  app.add_option("--max-output-megapixels", max_output_megapixels, "largest warped image")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--max-features", c.limits.max_features, "most features in a job (the method is O(n²))")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  app.add_option("--max-job-memory-mb", max_job_memory_mb,
                 "memory one job may allocate (pixels, output, lattice), MiB; 0: half the machine's memory shared "
                 "by --workers")
      ->check(CLI::Range(0, 1 << 24))
      ->capture_default_str();
  app.add_option("--max-mesh-mb", max_mesh_mb, "largest mesh file, MiB")
      ->check(CLI::Range(1, 65536))
      ->capture_default_str();
  app.add_option("--read-timeout", c.read_timeout_s, "seconds to receive a request's header, then its body")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--write-timeout", c.write_timeout_s, "seconds to send a response")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--idle-timeout", c.idle_timeout_s, "seconds a keep-alive connection may wait for its next request")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--shutdown-grace", c.shutdown_grace_s,
                 "seconds running jobs get to finish after SIGTERM before they are re-queued for the next start")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--max-attempts", c.max_attempts,
                 "a job found running after this many crashes is failed instead of re-run")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_option("--retention-hours", c.retention_hours,
                 "delete finished jobs and their files this long after they finish (0: keep them)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--input-root", roots,
                 "folder whose files jobs may name by path ({\"path\": ...}); repeatable; none by default")
      ->check(CLI::ExistingDirectory);
  app.add_option("--token-file", token_file,
                 "require `Authorization: Bearer <token>` with the token in this file (else TEXWARPD_TOKEN, if set)")
      ->check(CLI::ExistingFile);
  app.add_option("--store", c.store,
                 "the job store: sqlite (a file in --data-dir, one node) or a PostgreSQL URI postgresql://USER@HOST/DB "
                 "(any number of nodes sharing it and one --data-dir; the password from PGPASSWORD or ~/.pgpass)")
      ->capture_default_str();
  app.add_flag("--migrate", c.migrate, "create or upgrade the store's schema, print \"schema at version N\" and exit");
  app.add_option("--node-id", c.node_id, "this node's name in the store (default: HOSTNAME:PORT)");
  app.add_option("--lease-s", c.lease_s,
                 "seconds a node holds a claimed job without renewing it; another node takes over after that")
      ->check(CLI::Range(0.2, 86400.0))
      ->capture_default_str();
  app.add_option("--heartbeat-s", c.heartbeat_s,
                 "seconds between a node's heartbeats (leases, progress, cancel requests); less than --lease-s / 2")
      ->check(CLI::Range(0.05, 3600.0))
      ->capture_default_str();
  app.add_option("--poll-ms", c.poll_ms, "an idle worker looks for queued jobs this often, milliseconds")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  app.add_option("--log-level", c.log_level, "debug, info, warn or error")
      ->check(CLI::IsMember({"debug", "info", "warn", "error"}))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
    std::tie(c.host, c.port) = parse_listen_address(listen);
    c.store = checked_store(c.store);
    if (!(c.heartbeat_s < c.lease_s / 2.0)) {
      throw std::invalid_argument("--heartbeat-s " + short_number(c.heartbeat_s) + " must be less than half of " +
                                  "--lease-s " + short_number(c.lease_s) +
                                  " (a lease must survive a missed heartbeat)");
    }
    if (c.node_id.size() > 200 || c.node_id.find_first_of(" \t\r\n") != std::string::npos) {
      throw std::invalid_argument("--node-id: at most 200 characters without spaces");
    }
    c.data_dir = data_dir;
    c.cache_dir = cache_dir;
    c.port_file = port_file;
    c.max_job_body_bytes = max_job_body_mb << 20;
    c.max_blob_bytes = max_blob_mb << 20;
    c.limits.max_mesh_bytes = static_cast<long long>(max_mesh_mb) << 20;  // at most 65536 MiB (its Range)
    c.limits.max_job_memory_bytes =
        max_job_memory_mb > 0 ? max_job_memory_mb << 20 : runner::default_job_memory_bytes(c.workers);
    c.limits.image.max_pixels = static_cast<long long>(max_image_megapixels * 1e6);
    c.limits.max_output_pixels = static_cast<long long>(max_output_megapixels * 1e6);
    for (const auto& r : roots) c.input_roots.emplace_back(std::filesystem::canonical(r));
    if (!token_file.empty()) {
      c.token = read_token_file(token_file);
    } else if (const char* env = std::getenv("TEXWARPD_TOKEN"); env && *env) {
      c.token = trim(env);
    }
    const InputLocation device_flag = InputLocation::flag("--device");
    if (!device.empty()) c.device = proto::parse_device(device, device_flag);
    if (c.device && !c.device->name.empty()) {
      // A named device that does not exist refuses the start (the message lists the devices there are).
      try {
        runner::BackendCache(c.device).get(std::nullopt, device_flag);
      } catch (const InputError&) {
        throw;
      } catch (const std::exception&) {
        // Any other failure to open it leaves the server up, reporting the device as failing on GET /readyz.
      }
    }
  } catch (const CLI::ConfigError& e) {
    // CLI11 says "INI was not able to parse KEY" for a key no option has: name the file and what keys are.
    constexpr std::string_view kExtras = "INI was not able to parse ";
    const std::string what = e.what();
    std::cerr << "texwarpd: --config " << app.get_config_ptr()->as<std::string>() << ": "
              << (what.rfind(kExtras, 0) == 0 ? "unknown key \"" + what.substr(kExtras.size()) +
                                                    "\" (the keys are the long option names: texwarpd --help)"
                                              : what)
              << "\n";
    *exit_code = 2;
    return std::nullopt;
  } catch (const CLI::ParseError& e) {
    *exit_code = app.exit(e) == 0 ? 0 : 2;
    return std::nullopt;
  } catch (const std::exception& e) {
    std::cerr << "texwarpd: " << e.what() << "\n";
    *exit_code = 2;
    return std::nullopt;
  }
  return c;
}

}  // namespace texwarp::server
