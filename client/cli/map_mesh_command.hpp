// `texwarp map-mesh`: textures a region of a mesh so that texture features land on surface features
// (the paper's Section 3 pipeline, core/mesh). Registered by main() when the build has texwarp_mesh.
#pragma once

#include "cli_command.hpp"

namespace texwarp::cli {

void add_map_mesh_command(CLI::App& root, Action& action);

}  // namespace texwarp::cli
