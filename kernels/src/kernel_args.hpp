// KernelArgs: a kernel's parameter list as one list of named, typed arguments; each one's index is its position in
// the list, so that adding an argument is one line; binds itself to a cl::Kernel and checks the kernel's own
// parameter list (count, names, buffer or value) against the list.
#pragma once

#include <CL/opencl.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <utility>

#include "opencl_calls.hpp"

namespace texwarp::kernels_detail {

// A kernel parameter's name as a template argument: Arg<"t_start", float>.
template <std::size_t N>
struct ArgName {
  char text[N]{};
  constexpr ArgName(const char (&name)[N]) { std::copy_n(name, N, text); }
  constexpr std::string_view view() const { return {text, N - 1}; }
};

template <ArgName Name, class T>
struct Arg {
  using Type = T;
  static constexpr std::string_view kName = Name.view();
  static constexpr bool kBuffer = std::is_same_v<T, cl::Buffer>;
  T value{};
};

// "" when the kernel's parameters match the expected names and kinds (a __global buffer or a value), else what
// differs. A kernel reported without names is checked by count only.
std::string parameter_mismatch(std::span<const std::string_view> names, std::span<const bool> buffers,
                               const KernelParameters& actual);

template <class... Args>
class KernelArgs {
 public:
  static constexpr std::size_t kCount = sizeof...(Args);
  static constexpr std::array<std::string_view, kCount> kNames = {Args::kName...};
  static constexpr std::array<bool, kCount> kBuffers = {Args::kBuffer...};

  // The position of the argument called Name (compile-time; an unknown name does not compile).
  template <ArgName Name>
  static constexpr std::size_t index() {
    constexpr auto kIndex =
        static_cast<std::size_t>(std::find(kNames.begin(), kNames.end(), Name.view()) - kNames.begin());
    static_assert(kIndex < kCount, "no kernel argument of this name");
    return kIndex;
  }

  template <ArgName Name>
  auto& get() {
    return std::get<index<Name>()>(args_).value;
  }

  // Every argument, in order.
  void bind(cl::Kernel& kernel) const { bind_all(kernel, std::index_sequence_for<Args...>{}); }
  // Sets one argument and binds it alone (per-launch arguments).
  template <ArgName Name, class V>
  void set(cl::Kernel& kernel, V&& value) {
    get<Name>() = std::forward<V>(value);
    kernel.setArg(static_cast<cl_uint>(index<Name>()), get<Name>());
  }

  // Throws OpenClError naming the kernel when its parameter list is not this one.
  static void check(const cl::Kernel& kernel, std::string_view kernel_name) {
    const std::string mismatch = parameter_mismatch(kNames, kBuffers, kernel_parameters(kernel));
    if (!mismatch.empty()) {
      throw OpenClError("kernel " + std::string(kernel_name) +
                        " does not take the arguments the host binds: " + mismatch);
    }
  }

 private:
  static constexpr bool unique_names() {
    for (std::size_t i = 0; i < kCount; ++i) {
      for (std::size_t j = i + 1; j < kCount; ++j) {
        if (kNames[i] == kNames[j]) return false;
      }
    }
    return true;
  }
  static_assert(unique_names(), "kernel argument names repeat");

  template <std::size_t... I>
  void bind_all(cl::Kernel& kernel, std::index_sequence<I...>) const {
    (kernel.setArg(static_cast<cl_uint>(I), std::get<I>(args_).value), ...);
  }

  std::tuple<Args...> args_;
};

}  // namespace texwarp::kernels_detail
