// A hand-made PNG whose header claims more pixels than its bytes hold: the header of a decompression bomb without
// the bomb, for tests of memory budgets and bounded decoding.
#pragma once

#include <string>

namespace texwarp::testing {

// The file's bytes: an IHDR of width×height RGBA (8 bits) and 1000 zero bytes of pixel data in one stored deflate
// block (about 1 KB in all).
std::string lying_png(int width, int height);

}  // namespace texwarp::testing
