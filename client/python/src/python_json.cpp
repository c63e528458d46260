// Python objects ↔ JSON: see python_json.hpp.
#include "python_json.hpp"

#include <string>

#include "python_failure.hpp"

namespace texwarp::python {

namespace py = pybind11;

nlohmann::json to_json(const py::handle& value) {
  const py::module_ json = py::module_::import("json");
  std::string text;
  try {
    text = json.attr("dumps")(value, py::arg("allow_nan") = false).cast<std::string>();
  } catch (const py::error_already_set& e) {
    Failure f = usage_failure("");
    f.kind = Failure::Kind::kInput;
    f.type = "urn:texwarp:problem:invalid-job";
    f.title = "Invalid job";
    f.path = "$";
    f.detail = std::string("the job is not JSON: ") + e.what();
    throw FailureError(f);
  }
  return nlohmann::json::parse(text);
}

py::object to_python(const nlohmann::json& value) { return py::module_::import("json").attr("loads")(value.dump()); }

}  // namespace texwarp::python
