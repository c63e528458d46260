// Reading back what a glTF writer stored: an accessor's float components, whether its buffer view is tightly
// packed or strided (interleaved attributes), for tests that check written files through tinygltf.
#pragma once

#include <cstdint>
#include <cstring>
#include <vector>

#include "texwarp/mesh/tiny_gltf.hpp"

namespace texwarp::mesh::testing {

// Accessor `index` of `model` as floats, component by component (count × components values).
inline std::vector<float> accessor_floats(const tinygltf::Model& model, int index) {
  const tinygltf::Accessor& a = model.accessors.at(index);
  const tinygltf::BufferView& v = model.bufferViews.at(a.bufferView);
  const int n = tinygltf::GetNumComponentsInType(static_cast<std::uint32_t>(a.type));
  const std::size_t stride = v.byteStride != 0 ? v.byteStride : 4 * static_cast<std::size_t>(n);
  std::vector<float> out(a.count * static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < a.count; ++i) {
    std::memcpy(&out[i * n], model.buffers.at(v.buffer).data.data() + v.byteOffset + a.byteOffset + i * stride,
                4 * static_cast<std::size_t>(n));
  }
  return out;
}

}  // namespace texwarp::mesh::testing
