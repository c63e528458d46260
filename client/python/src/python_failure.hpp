// Failure: an error on its way from C++ to Python, made without the GIL (from a ClientError, an InputError or any
// exception of a local run) and raised as the texwarp module's exception (texwarp.errors) by one translator.
#pragma once

#include <pybind11/pybind11.h>

#include <exception>
#include <stdexcept>
#include <string>

#include "texwarp/client/client_error.hpp"

namespace texwarp::python {

struct Failure {
  // Which Python exception: texwarp.ProblemError, InputError, JobFailedError, JobCanceledError, TimeoutError,
  // texwarp.Error (a misuse of a Job, e.g. fetch before it finished).
  enum class Kind { kProblem, kInput, kJobFailed, kCanceled, kTimeout, kUsage };
  Kind kind = Kind::kProblem;
  std::string type;    // "urn:texwarp:problem:<slug>" (the server's), or "urn:texwarp:client:<code>"
  std::string path;    // JSON path of the offending value; "" when none
  std::string detail;  // what went wrong
  std::string title;
  int status = 0;  // HTTP status; 0 when no server answered
};

// Thrown by the module's C++ code; pybind11 turns it into the Python exception (register_failure_translator).
class FailureError : public std::runtime_error {
 public:
  explicit FailureError(Failure failure) : std::runtime_error(failure.detail), failure_(std::move(failure)) {}
  const Failure& failure() const { return failure_; }

 private:
  Failure failure_;
};

Failure failure_from(const client::ClientError& error);
// The exception in flight (call inside a catch block): InputError → kInput with its JSON path (or flag),
// NumericalError → "numerical-error", CanceledError → kCanceled, anything else → "internal".
Failure failure_from_current_exception();
Failure usage_failure(const std::string& detail);

// Runs `body` and turns any exception but a FailureError or a Python error in flight into a FailureError
// (failure_from_current_exception).
template <typename F>
auto guarded(F&& body) {
  try {
    return body();
  } catch (const FailureError&) {
    throw;
  } catch (const pybind11::error_already_set&) {
    throw;
  } catch (...) {
    throw FailureError(failure_from_current_exception());
  }
}

// Installs the translator of FailureError into texwarp.errors' classes (needs the module texwarp.errors).
void register_failure_translator();

}  // namespace texwarp::python
