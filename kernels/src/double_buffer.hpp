// DoubleBuffer: two slots, so that while the device runs one tile the host fills the next and takes the previous
// one's results. An in-order queue runs the tiles one after the other, so they may share everything else.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <utility>

#include "tile_plan.hpp"

namespace texwarp::kernels_detail {

template <class Slot>
class DoubleBuffer {
 public:
  // Both slots built from the same arguments.
  template <class... A>
  explicit DoubleBuffer(const A&... args) : slots_{Slot(args...), Slot(args...)} {}

  // Tile i goes through slot i mod 2: before(); submit(slot, tile 0); then for each tile i: before(),
  // submit(other slot, tile i + 1) when there is one, complete(slot, tile i). before() may throw to stop (nothing
  // is then left to complete that the caller needs); so may submit and complete.
  template <class Before, class Submit, class Complete>
  void run(std::span<const Tile> tiles, Before&& before, Submit&& submit, Complete&& complete) {
    if (tiles.empty()) return;
    before();
    submit(slots_[0], tiles[0]);
    for (std::size_t i = 0; i < tiles.size(); ++i) {
      before();
      if (i + 1 < tiles.size()) submit(slots_[(i + 1) % 2], tiles[i + 1]);
      complete(slots_[i % 2], tiles[i]);
    }
  }

 private:
  std::array<Slot, 2> slots_;
};

}  // namespace texwarp::kernels_detail
