// Program binaries kept between processes (program_binary_cache.hpp, build_program): a new process (here: the
// program table forgotten) builds from the stored binary and its kernel maps bit for bit as the source-built one;
// a truncated file, a flipped byte and another key under the same name are ignored and rewritten; a folder that
// cannot be written, or a process that keeps no binaries, still builds; writers racing leave one whole file.
#include <gtest/gtest.h>

#include <atomic>
#include <bit>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "kernel_test_support.hpp"
#include "opencl_device.hpp"
#include "pathline_kernel_args.hpp"
#include "pathline_program.hpp"
#include "program_binary_cache.hpp"
#include "test_folder.hpp"
#include "texwarp/kernels/opencl_backend.hpp"
#include "texwarp/kernels/opencl_warp_backend.hpp"

namespace texwarp {
namespace {

namespace fs = std::filesystem;
using kernels_detail::forget_programs_for_tests;

std::string read_file(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_file(const fs::path& file, const std::string& bytes) {
  std::ofstream(file, std::ios::binary | std::ios::trunc)
      .write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// The program files in `folder` (temporary files start with '.').
std::vector<fs::path> program_files(const fs::path& folder) {
  std::vector<fs::path> files;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(folder, ec)) {
    if (e.path().filename().string().front() != '.') files.push_back(e.path());
  }
  return files;
}

class ProgramBinaryCache : public ::testing::Test {
 protected:
  void SetUp() override { keep_opencl_program_binaries(true); }
  void TearDown() override {
    keep_opencl_program_binaries(false);
    forget_programs_for_tests(std::nullopt);
  }

  // A new process with its program binaries in `folder`: the inverse map of a small problem, and what it built.
  struct Run {
    std::vector<Point> map;
    std::size_t built = 0;
    std::size_t from_binary = 0;
  };
  Run run_in_new_process(const fs::path& folder) {
    forget_programs_for_tests(folder);
    const OpenClActivity before = opencl_activity();
    OpenClWarpBackend opencl;
    Run r;
    r.map = opencl.inverse_map_grid(problem_, 24, 16, RunControl{});
    r.built = opencl_activity().programs_built - before.programs_built;
    r.from_binary = opencl_activity().programs_from_binary - before.programs_from_binary;
    return r;
  }

  static void expect_same_bits(const std::vector<Point>& a, const std::vector<Point>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(std::bit_cast<std::uint64_t>(a[i].real()), std::bit_cast<std::uint64_t>(b[i].real())) << i;
      EXPECT_EQ(std::bit_cast<std::uint64_t>(a[i].imag()), std::bit_cast<std::uint64_t>(b[i].imag())) << i;
    }
  }

  testing::TestFolder dir_{"binaries"};
  WarpProblem problem_ = testing::make_problem(testing::ProblemSpec{});
};

TEST_F(ProgramBinaryCache, ANewProcessBuildsFromTheStoredBinaryAndMapsBitForBitTheSame) {
  const fs::path folder = dir_ / "programs";
  const Run source = run_in_new_process(folder);
  EXPECT_EQ(source.built, 1u);
  EXPECT_EQ(source.from_binary, 0u);
  ASSERT_EQ(program_files(folder).size(), 1u);

  const Run binary = run_in_new_process(folder);
  EXPECT_EQ(binary.built, 1u);
  EXPECT_EQ(binary.from_binary, 1u);
  expect_same_bits(binary.map, source.map);
  EXPECT_EQ(program_files(folder).size(), 1u);
}

TEST_F(ProgramBinaryCache, AProgramFromTheBinaryKeepsItsKernelArgumentInfo) {
  const fs::path folder = dir_ / "programs";
  const kernels_detail::DeviceHandle device = kernels_detail::select_device(OpenClOptions{});
  const kernels_detail::KernelVariant variant{false, false};
  forget_programs_for_tests(folder);
  kernels_detail::pathline_program(device, variant);
  forget_programs_for_tests(folder);
  const std::size_t from_binary = opencl_activity().programs_from_binary;
  const cl::Program program = kernels_detail::pathline_program(device, variant);  // checks the names itself
  ASSERT_EQ(opencl_activity().programs_from_binary, from_binary + 1);
  const cl::Kernel kernel(program, kernels_detail::kPathlineKernelName.data());
  EXPECT_FALSE(kernel.getArgInfo<CL_KERNEL_ARG_NAME>(0).empty());
}

// Damage to the one stored file: the next process ignores it, builds from source, maps the same, and rewrites it
// whole (the process after that builds from it).
struct Damage {
  const char* name;
  std::string (*apply)(const std::string& file);
};

class ProgramBinaryDamage : public ProgramBinaryCache, public ::testing::WithParamInterface<Damage> {};

TEST_P(ProgramBinaryDamage, IsIgnoredAndTheFileRewritten) {
  const fs::path folder = dir_ / "programs";
  const Run source = run_in_new_process(folder);
  ASSERT_EQ(program_files(folder).size(), 1u);
  const fs::path file = program_files(folder).front();
  const std::string whole = read_file(file);
  const std::string damaged = GetParam().apply(whole);
  ASSERT_NE(damaged, whole);
  write_file(file, damaged);

  const Run ignored = run_in_new_process(folder);
  EXPECT_EQ(ignored.built, 1u);
  EXPECT_EQ(ignored.from_binary, 0u);
  expect_same_bits(ignored.map, source.map);
  ASSERT_EQ(program_files(folder).size(), 1u);
  EXPECT_TRUE(read_file(file) != damaged) << "not rewritten";

  const Run rewritten = run_in_new_process(folder);
  EXPECT_EQ(rewritten.from_binary, 1u);
  expect_same_bits(rewritten.map, source.map);
}

INSTANTIATE_TEST_SUITE_P(
    Files, ProgramBinaryDamage,
    ::testing::Values(Damage{"Truncated", [](const std::string& f) { return f.substr(0, f.size() - 1000); }},
                      // Deep in the binary: the checksum's to catch, the driver might take it.
                      Damage{"FlippedByteInTheBinary",
                             [](const std::string& file) {
                               std::string f = file;
                               f[f.size() - 5000] = static_cast<char>(f[f.size() - 5000] ^ 0x10);
                               return f;
                             }},
                      // Same name, lengths and checksum: only the byte-for-byte key comparison tells.
                      Damage{"AnotherKeyUnderItsName",
                             [](const std::string& file) {
                               std::string f = file;
                               const std::size_t at = f.find("options -cl-std");
                               if (at != std::string::npos) f[at + 1] = 'O';
                               return f;
                             }},
                      Damage{"Empty", [](const std::string&) { return std::string(); }}),
    [](const ::testing::TestParamInfo<Damage>& p) { return std::string(p.param.name); });

TEST_F(ProgramBinaryCache, AFolderThatCannotBeMadeStillBuilds) {
  write_file(dir_ / "file", "not a folder");
  const fs::path folder = dir_ / "file" / "programs";
  const Run first = run_in_new_process(folder);
  const Run second = run_in_new_process(folder);
  EXPECT_EQ(first.built, 1u);
  EXPECT_EQ(second.built, 1u);
  EXPECT_EQ(second.from_binary, 0u);
  expect_same_bits(second.map, first.map);
}

TEST_F(ProgramBinaryCache, NoFolderStillBuilds) {
  const Run first = run_in_new_process(fs::path());
  EXPECT_EQ(first.built, 1u);
  EXPECT_EQ(first.from_binary, 0u);
  EXPECT_TRUE(program_files(dir_.path()).empty());
}

TEST_F(ProgramBinaryCache, AProcessThatKeepsNoBinariesWritesNoneButBuildsFromThem) {
  const fs::path folder = dir_ / "programs";
  keep_opencl_program_binaries(false);
  run_in_new_process(folder);
  EXPECT_TRUE(program_files(folder).empty());
  keep_opencl_program_binaries(true);
  run_in_new_process(folder);
  ASSERT_EQ(program_files(folder).size(), 1u);
  keep_opencl_program_binaries(false);
  EXPECT_EQ(run_in_new_process(folder).from_binary, 1u);
}

// Writers racing (other processes: the file is written beside and renamed) leave one whole file, no temporary
// ones, and a reader between their writes always finds a whole file.
TEST_F(ProgramBinaryCache, WritersAtOnceLeaveOneWholeFileThatReadersAlwaysTake) {
  const fs::path folder = dir_ / "programs";
  const kernels_detail::DeviceHandle device = kernels_detail::select_device(OpenClOptions{});
  const std::string options = "-cl-std=CL1.2 -w";
  const std::string source = "kernel void twice(global float* x) { x[get_global_id(0)] *= 2.0f; }";
  cl::Program program(device.context, source);
  program.build(std::vector<cl::Device>{device.device}, options.c_str());
  const std::string key = kernels_detail::program_binary_key(device, source, options);
  ASSERT_TRUE(kernels_detail::store_program_binary(device, folder, key, program));
  std::atomic<int> stored{0};
  std::vector<std::thread> writers;
  writers.reserve(3);
  for (int w = 0; w < 3; ++w) {
    writers.emplace_back([&] {
      for (int i = 0; i < 10; ++i) stored += kernels_detail::store_program_binary(device, folder, key, program);
    });
  }
  int loaded = 0;
  for (int i = 0; i < 10; ++i) loaded += kernels_detail::load_program_binary(device, folder, key, options).has_value();
  for (std::thread& t : writers) t.join();
  EXPECT_EQ(stored, 30);
  EXPECT_EQ(loaded, 10);
  EXPECT_EQ(program_files(folder).size(), 1u);
  EXPECT_EQ(std::distance(fs::directory_iterator(folder), fs::directory_iterator()), 1);  // no temporary file
}

// A link to a whole, valid binary elsewhere is not taken (only regular files of this user's are).
TEST_F(ProgramBinaryCache, ALinkToAValidFileIsNotTaken) {
  const fs::path elsewhere = dir_ / "elsewhere";
  run_in_new_process(elsewhere);
  const std::vector<fs::path> files = program_files(elsewhere);
  ASSERT_EQ(files.size(), 1u);
  const fs::path folder = dir_ / "programs";
  fs::create_directories(folder);
  fs::create_symlink(files[0], folder / files[0].filename());
  keep_opencl_program_binaries(false);
  EXPECT_EQ(run_in_new_process(folder).from_binary, 0u);
  EXPECT_EQ(run_in_new_process(elsewhere).from_binary, 1u);  // the file itself is good
}

TEST(ProgramBinaryKey, NamesEverythingTheBinaryDependsOn) {
  const kernels_detail::DeviceHandle device = kernels_detail::select_device(OpenClOptions{});
  const std::string key = kernels_detail::program_binary_key(device, "kernel void k() {}", "-cl-std=CL1.2 -w");
  for (const std::string& part : {device.device.getInfo<CL_DEVICE_NAME>(), device.device.getInfo<CL_DEVICE_VERSION>(),
                                  device.device.getInfo<CL_DRIVER_VERSION>(), std::string("kernel void k() {}"),
                                  std::string("-cl-std=CL1.2 -w")}) {
    EXPECT_NE(key.find(part.substr(0, part.find('\0'))), std::string::npos) << part;  // without a driver's NUL
  }
  EXPECT_NE(key, kernels_detail::program_binary_key(device, "kernel void k() {}", "-cl-std=CL1.2"));
  EXPECT_NE(key, kernels_detail::program_binary_key(device, "kernel void j() {}", "-cl-std=CL1.2 -w"));
  // The driver's library as it is on disk (a package update keeps the version strings), and its code settings.
  if (device.platform_name.find("Portable Computing Language") != std::string::npos) {
    EXPECT_NE(key.find("libpocl"), std::string::npos);
  }
  ::setenv("POCL_WORK_GROUP_METHOD", "cbs", 1);
  const std::string with_method = kernels_detail::program_binary_key(device, "kernel void k() {}", "-cl-std=CL1.2 -w");
  ::unsetenv("POCL_WORK_GROUP_METHOD");
  EXPECT_NE(with_method, key);
  EXPECT_EQ(key, kernels_detail::program_binary_key(device, "kernel void k() {}", "-cl-std=CL1.2 -w"));
}

}  // namespace
}  // namespace texwarp
