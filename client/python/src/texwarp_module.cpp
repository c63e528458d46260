// The texwarp Python module (_texwarp, wrapped by the texwarp package): Client over libtexwarp_client, run_local /
// submit_local over the runner, Job for both. Jobs are dicts (the job JSON); results are dicts {job_id, state,
// files, report}. The GIL is released while C++ works; progress callbacks take it back.
#include <pybind11/functional.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "array_warp.hpp"
#include "job_handle.hpp"
#include "python_failure.hpp"
#include "python_json.hpp"
#include "texwarp/client/client.hpp"

namespace texwarp::python {
namespace {

namespace py = pybind11;
using namespace std::chrono_literals;

py::dict outcome_dict(const JobOutcome& outcome) {
  py::dict d;
  d["job_id"] = outcome.job_id;
  d["state"] = outcome.state;
  d["files"] = outcome.files;
  d["report"] = to_python(outcome.report);
  return d;
}

// Job.wait: waits with the GIL released, in slices of 100 ms, calling progress(fraction, state) (with the GIL)
// when either changed; Ctrl-C (a pending signal) cancels the job and raises KeyboardInterrupt; TimeoutError after
// `timeout` seconds; then the job's own failure if it did not succeed. Returns the final state.
std::string wait_job(JobHandle& job, std::optional<double> timeout_s, const py::object& progress) {
  const auto deadline = timeout_s ? std::optional(std::chrono::steady_clock::now() +
                                                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                                      std::chrono::duration<double>(*timeout_s)))
                                  : std::nullopt;
  std::string last_state;
  double last_progress = -1.0;
  for (;;) {
    bool done = false;
    {
      py::gil_scoped_release release;
      auto slice = std::chrono::milliseconds(100);
      if (deadline) {
        const auto left =
            std::chrono::duration_cast<std::chrono::milliseconds>(*deadline - std::chrono::steady_clock::now());
        slice = std::max(0ms, std::min(slice, left));
      }
      done = job.wait_for(slice);
    }
    const std::string state = job.state();
    const double fraction = job.progress();
    if (!progress.is_none() && (state != last_state || fraction != last_progress)) {
      progress(fraction, state);
      last_state = state;
      last_progress = fraction;
    }
    if (done) break;
    if (PyErr_CheckSignals() != 0) {
      job.cancel();
      throw py::error_already_set();
    }
    if (deadline && std::chrono::steady_clock::now() >= *deadline) {
      Failure f;
      f.kind = Failure::Kind::kTimeout;
      f.detail = "job " + job.id() + " still " + job.state() + " after " + std::to_string(*timeout_s) + " s";
      throw FailureError(f);
    }
  }
  if (auto failure = job.failure()) throw FailureError(*failure);
  return job.state();
}

py::dict failure_dict(const Failure& f) {
  py::dict d;
  d["type"] = f.type;
  d["path"] = f.path;
  d["detail"] = f.detail;
  d["title"] = f.title;
  d["status"] = f.status;
  return d;
}

struct PyClient {
  client::ClientOptions options;
  std::shared_ptr<std::mutex> mutex = std::make_shared<std::mutex>();
  std::shared_ptr<client::Client> client;
};

std::shared_ptr<JobHandle> submit_to(PyClient& self, const py::dict& job) {
  const std::string body = to_json(job).dump();
  py::gil_scoped_release release;
  return guarded([&] { return std::shared_ptr<JobHandle>(std::make_shared<ServerJob>(self.options, body)); });
}

std::shared_ptr<JobHandle> submit_here(const py::dict& job, const std::optional<std::string>& base_dir) {
  const nlohmann::json j = to_json(job);
  const std::filesystem::path base = base_dir ? std::filesystem::path(*base_dir) : std::filesystem::current_path();
  py::gil_scoped_release release;
  return guarded([&] { return std::shared_ptr<JobHandle>(std::make_shared<LocalJob>(j, base)); });
}

py::dict finish_job(JobHandle& job, const std::string& out_dir, std::optional<double> timeout_s,
                    const py::object& progress) {
  wait_job(job, timeout_s, progress);
  JobOutcome outcome;
  {
    py::gil_scoped_release release;
    outcome = guarded([&] { return job.fetch(out_dir); });
  }
  return outcome_dict(outcome);
}

}  // namespace
}  // namespace texwarp::python

PYBIND11_MODULE(_texwarp, m) {
  namespace py = pybind11;
  using namespace texwarp::python;
  namespace client = texwarp::client;

  m.doc() =
      "texwarp's C++ part: Client (libtexwarp_client), run_local / submit_local (the runner), Job; warp / map_points "
      "(arrays in memory)";
  m.attr("__version__") = TEXWARP_VERSION;
  register_failure_translator();
  register_array_functions(m);

  py::class_<JobHandle, std::shared_ptr<JobHandle>>(m, "Job",
                                                    "A submitted job (on a texwarpd or in this process). state, "
                                                    "progress, poll() and done never block.")
      .def_property_readonly("id", &JobHandle::id, "the server's job id ('local:…' for a local job)")
      .def_property_readonly("state", &JobHandle::state, "'queued', 'running', 'succeeded', 'failed' or 'canceled'")
      .def_property_readonly("progress", &JobHandle::progress, "0.0 … 1.0")
      .def_property_readonly("done", &JobHandle::done)
      .def_property_readonly(
          "error",
          [](const JobHandle& job) -> py::object {
            auto f = job.failure();
            return f ? py::object(failure_dict(*f)) : py::none();
          },
          "the problem (dict: type, path, detail, title, status) once the job failed; None otherwise")
      .def("poll", &JobHandle::done, "True once the job has ended (never blocks: for a DCC's main loop or timer)")
      .def("wait", &wait_job, py::arg("timeout") = py::none(), py::arg("progress") = py::none(),
           "Waits until the job ends (timeout in seconds: TimeoutError), calling progress(fraction, state) as it "
           "changes; returns 'succeeded', raises JobFailedError / JobCanceledError otherwise. Ctrl-C cancels.")
      .def(
          "cancel",
          [](JobHandle& job) {
            py::gil_scoped_release release;
            guarded([&] {
              job.cancel();
              return 0;
            });
          },
          "Asks the job to stop; wait() or poll() shows when it has (state 'canceled').")
      .def(
          "fetch",
          [](JobHandle& job, const std::string& out_dir) {
            JobOutcome outcome;
            {
              py::gil_scoped_release release;
              outcome = guarded([&] { return job.fetch(out_dir); });
            }
            return outcome_dict(outcome);
          },
          py::arg("out_dir"), "The finished job's files into out_dir: {job_id, state, files, report}.");

  py::class_<PyClient>(m, "Client", "A texwarpd client (libtexwarp_client): retries within retry_budget seconds.")
      .def(py::init([](const std::string& server_url, const std::string& token, double retry_budget_s,
                       double request_timeout_s) {
             PyClient c;
             c.options.server = server_url;
             c.options.token = token;
             c.options.retry_budget = std::chrono::milliseconds(static_cast<long long>(retry_budget_s * 1000));
             c.options.request_timeout = std::chrono::milliseconds(static_cast<long long>(request_timeout_s * 1000));
             c.options.user_agent = std::string("texwarp-python/") + TEXWARP_VERSION;
             c.client = std::make_shared<client::Client>(c.options);
             return c;
           }),
           py::arg("server_url") = "http://127.0.0.1:8080", py::arg("token") = "", py::arg("retry_budget") = 60.0,
           py::arg("request_timeout") = 60.0)
      .def_property_readonly("server_url", [](const PyClient& c) { return c.options.server; })
      .def("submit", &submit_to, py::arg("job"), "Submits a job (dict): a Job; ProblemError when refused.")
      .def(
          "run",
          [](PyClient& self, const py::dict& job, const std::string& out_dir, std::optional<double> timeout,
             const py::object& progress) {
            auto handle = submit_to(self, job);
            return finish_job(*handle, out_dir, timeout, progress);
          },
          py::arg("job"), py::arg("out_dir"), py::arg("timeout") = py::none(), py::arg("progress") = py::none(),
          "submit + wait + fetch: {job_id, state, files, report}")
      .def(
          "upload_file",
          [](PyClient& self, const std::string& path) {
            py::gil_scoped_release release;
            std::lock_guard lock(*self.mutex);
            auto blob = self.client->upload_file(path);
            if (!blob) throw FailureError(failure_from(blob.error()));
            return blob->id;
          },
          py::arg("path"), R"(Uploads a texture or mesh file: its blob id, for {"image": {"blob": id}})")
      .def(
          "status",
          [](PyClient& self, const std::string& job_id) {
            nlohmann::json status;
            {
              py::gil_scoped_release release;
              std::lock_guard lock(*self.mutex);
              auto s = self.client->status(job_id);
              if (!s) throw FailureError(failure_from(s.error()));
              status = {{"id", s->id}, {"state", texwarp::proto::to_string(s->state)}, {"progress", s->progress}};
            }
            return to_python(status);
          },
          py::arg("job_id"), "{id, state, progress (percent)} of a job")
      .def("ready", [](PyClient& self) {
        nlohmann::json doc;
        {
          py::gil_scoped_release release;
          std::lock_guard lock(*self.mutex);
          auto r = self.client->ready();
          if (!r) throw FailureError(failure_from(r.error()));
          doc = r.value();
        }
        return to_python(doc);
      });

  m.def("submit_local", &submit_here, py::arg("job"), py::arg("base_dir") = py::none(),
        "Starts a job in this process (no server): a Job. Paths in the job are relative to base_dir (default: the "
        "current folder). InputError (with .path) for a job that is wrong.");
  m.def(
      "run_local",
      [](const py::dict& job, const std::string& out_dir, const std::optional<std::string>& base_dir,
         std::optional<double> timeout, const py::object& progress) {
        auto handle = submit_here(job, base_dir);
        return finish_job(*handle, out_dir, timeout, progress);
      },
      py::arg("job"), py::arg("out_dir"), py::arg("base_dir") = py::none(), py::arg("timeout") = py::none(),
      py::arg("progress") = py::none(),
      "Runs a job in this process (the `texwarp run` path): {job_id, state, files, report}.");
}
