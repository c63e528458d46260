// Failure: see python_failure.hpp.
#include "python_failure.hpp"

#include <pybind11/pybind11.h>

#include "texwarp/core/numerical_error.hpp"
#include "texwarp/core/run_control.hpp"
#include "texwarp/proto/input_error.hpp"
#include "texwarp/proto/problem_details.hpp"

namespace texwarp::python {

namespace py = pybind11;

Failure failure_from(const client::ClientError& error) {
  Failure f;
  f.detail = error.message;
  f.status = error.http_status;
  f.type = std::string("urn:texwarp:client:") + client::to_string(error.code);
  if (error.problem) {
    f.type = error.problem->type;
    f.path = error.problem->path;
    f.title = error.problem->title;
    if (!error.problem->detail.empty()) f.detail = error.problem->detail;
    if (error.problem->status != 0) f.status = error.problem->status;
  }
  switch (error.code) {
    case client::ErrorCode::kJobFailed:
      f.kind = Failure::Kind::kJobFailed;
      break;
    case client::ErrorCode::kJobCanceled:
      f.kind = Failure::Kind::kCanceled;
      break;
    case client::ErrorCode::kTimeout:
      f.kind = Failure::Kind::kTimeout;
      break;
    default:
      f.kind = Failure::Kind::kProblem;
      break;
  }
  return f;
}

Failure failure_from_current_exception() {
  Failure f;
  try {
    throw;
  } catch (const FailureError& e) {
    return e.failure();
  } catch (const InputError& e) {
    f.kind = Failure::Kind::kInput;
    f.type = std::string(proto::kProblemTypePrefix) + "invalid-job";
    f.title = "Invalid job";
    const auto& where = e.where();
    f.path = where.json_path() ? where.json_path()->str() : where.flag_name();
    f.detail = e.detail();
  } catch (const CanceledError&) {
    f.kind = Failure::Kind::kCanceled;
    f.detail = "the job was canceled";
  } catch (const NumericalError& e) {
    f.kind = Failure::Kind::kJobFailed;
    f.type = std::string(proto::kProblemTypePrefix) + "numerical-error";
    f.title = "The method could not meet its guarantees";
    f.detail = e.what();
  } catch (const std::exception& e) {
    f.kind = Failure::Kind::kJobFailed;
    f.type = std::string(proto::kProblemTypePrefix) + "internal";
    f.title = "Internal error";
    f.detail = e.what();
  }
  return f;
}

Failure usage_failure(const std::string& detail) {
  Failure f;
  f.kind = Failure::Kind::kUsage;
  f.detail = detail;
  return f;
}

void register_failure_translator() {
  // By value: pybind11's translator type is void (*)(std::exception_ptr).
  py::register_exception_translator([](std::exception_ptr p) {  // NOLINT(performance-unnecessary-value-param)
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FailureError& e) {
      const Failure& f = e.failure();
      const py::module_ errors = py::module_::import("texwarp.errors");
      py::object exc;
      switch (f.kind) {
        case Failure::Kind::kInput:
          exc = errors.attr("InputError")(f.path, f.detail, f.type, f.status, f.title);
          break;
        case Failure::Kind::kJobFailed:
          exc = errors.attr("JobFailedError")(f.type, f.path, f.detail, f.status, f.title);
          break;
        case Failure::Kind::kCanceled:
          exc = errors.attr("JobCanceledError")(f.detail);
          break;
        case Failure::Kind::kTimeout:
          PyErr_SetString(PyExc_TimeoutError, f.detail.c_str());
          return;
        case Failure::Kind::kUsage:
          exc = errors.attr("Error")(f.detail);
          break;
        case Failure::Kind::kProblem:
          exc = errors.attr("ProblemError")(f.type, f.path, f.detail, f.status, f.title);
          break;
      }
      PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(exc.ptr())), exc.ptr());
    }
  });
}

}  // namespace texwarp::python
