// Where an input error is, re-expressed in the job document: the runner's steps call core/mesh functions that
// name places in their own sub-document (or a file); at_path re-places them under the job's JSON path.
#pragma once

#include "texwarp/proto/input_error.hpp"

namespace texwarp::runner {

// Runs f, whose input is the part of the job at `base`; an InputError from it is re-placed in the job document
// (InputLocation::rebased: a file it names, the server's own layout, is dropped).
template <typename F>
auto at_path(const JsonPath& base, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const InputError& e) {
    throw InputError(e.where().rebased(base), e.detail());
  }
}

}  // namespace texwarp::runner
