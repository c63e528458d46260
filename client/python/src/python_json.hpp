// Python objects ↔ nlohmann::json through Python's own json module (a job dict in, a report dict out); the GIL
// must be held.
#pragma once

#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>

namespace texwarp::python {

// A dict / list / str / number / bool / None as JSON; texwarp.InputError at "$" when it is not JSON-serialisable.
nlohmann::json to_json(const pybind11::handle& value);
pybind11::object to_python(const nlohmann::json& value);

}  // namespace texwarp::python
