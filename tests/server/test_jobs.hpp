// Jobs for the service tests, small enough for the CPU reference (64² textures, ≤ 10 features) unless a test needs
// a job that runs long enough to be caught running (slow_image_job).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

namespace texwarp::testing {

// PNG bytes of a size×size RGB test pattern (gradients and a checkerboard), made with core's image writer.
std::string test_png(int size = 64);

// An image job with the texture inline: 3 positional features and 1 gradient feature on a 64² texture.
// `output_side` > 0 sets the warped image's size.
nlohmann::json image_job(int output_side = 0);

// The features of image_job, with their targets (for checks of the warped result).
nlohmann::json image_job_features();

// 36 features on a grid of the 64² texture, warped pixel by pixel ("exact") into an output_side² image: about
// 3 s per 500² on one CPU thread here.
nlohmann::json slow_image_job(int output_side);

// A mesh job: a flat 6×6-quad grid inline, the 64² texture inline, 5 surface features at vertices.
nlohmann::json mesh_job();

}  // namespace texwarp::testing
