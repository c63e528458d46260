// libtexwarp_client as a package, used the way a plugin developer would: `cmake --install` into a fresh prefix, a
// separate CMake project (consumer/) that find_packages it, the same program built through pkg-config (each as C++17,
// the VFX Reference Platform's, and as C++20), every installed header compiled alone as C++17, the README's C++
// snippet compiled against it, a plugin .so whose exported symbols are counted, and a client-only configure (shared
// library, no OpenImageIO/Eigen/OpenCL/SQLite/PostgreSQL) installed and used. Jobs run on a real texwarpd.
#include <dlfcn.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "server_process.hpp"
#include "shell_command.hpp"
#include "test_jobs.hpp"

namespace texwarp::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

using Command = ShellOutput;

// Runs `command` through the shell, standard output and error captured.
Command run(const std::string& command) { return run_shell(command + " 2>&1"); }

std::string quoted(const fs::path& p) { return "'" + p.string() + "'"; }

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The compiler launcher of this build (ccache), so that the nested builds reuse its cache.
std::string launcher_flag() {
  // NOLINTNEXTLINE(readability-redundant-string-init): the macro is empty only in a build without a launcher
  const std::string launcher = TEXWARP_CXX_LAUNCHER;
  return launcher.empty() ? std::string() : " -DCMAKE_CXX_COMPILER_LAUNCHER=" + launcher;
}

const fs::path kConsumerSource = fs::path(TEXWARP_SOURCE_DIR) / "tests/package/consumer";

// The image job of the service tests, its texture as a PNG file next to it (so the consumer uploads it).
fs::path write_job(const fs::path& dir) {
  fs::create_directories(dir);
  std::ofstream(dir / "texture.png", std::ios::binary) << test_png(64);
  nlohmann::json job = image_job();
  job["image"] = {{"path", (dir / "texture.png").string()}};
  std::ofstream(dir / "job.json") << job.dump();
  return dir / "job.json";
}

// The value of __cplusplus for `-std=c++<standard>` (17 or 20).
long cplusplus_of(int standard) { return standard == 17 ? 201703L : 202002L; }

// Runs the consumer program (compiled as C++`standard`) against `server` and checks what it reports against the
// files it wrote: each file's size and SHA-256 (by sha256sum, not the server's code) as the result manifest says,
// the report's residual.
void check_consumer_run(const fs::path& program, int standard, const ServerProcess& server, const fs::path& dir) {
  const fs::path job = write_job(dir / "job");
  const fs::path out = dir / "out";
  const Command c = run(quoted(program) + " " + server.url() + " " + quoted(job) + " " + quoted(out));
  ASSERT_EQ(c.status, 0) << c.output;
  EXPECT_THAT(c.output, HasSubstr("cplusplus " + std::to_string(cplusplus_of(standard)) + "\n"));
  std::map<std::string, std::pair<std::uint64_t, std::string>> files;
  const std::regex file_line(R"(file (\S+) (\d+) ([0-9a-f]{64}))");
  for (std::sregex_iterator it(c.output.begin(), c.output.end(), file_line), end; it != end; ++it) {
    files[(*it)[1]] = {std::stoull((*it)[2]), (*it)[3]};
  }
  ASSERT_EQ(files.size(), 2u) << c.output;
  for (const auto& [name, expected] : files) {
    ASSERT_TRUE(fs::exists(out / name)) << name;
    EXPECT_EQ(fs::file_size(out / name), expected.first) << name;
    const Command sum = run("sha256sum " + quoted(out / name));
    EXPECT_EQ(sum.output.substr(0, 64), expected.second) << name;
  }
  EXPECT_TRUE(files.count("warped.png") && files.count("report.json"));
  std::smatch m;
  ASSERT_TRUE(std::regex_search(c.output, m, std::regex(R"(max_px (\S+))"))) << c.output;
  const double max_px = std::stod(m[1]);
  EXPECT_GE(max_px, 0.0);
  EXPECT_LT(max_px, 1e-6);  // the features land on their targets (as in the client suite)
  EXPECT_EQ(nlohmann::json::parse(read_file(out / "report.json"))["residuals"]["max_px"].get<double>(), max_px);
  EXPECT_THAT(c.output, HasSubstr("progress 100"));
  EXPECT_THAT(c.output, HasSubstr("bad_job_path $.warp.alpha"));
  EXPECT_THAT(c.output, HasSubstr("value_or 7"));
}

// Symbols a shared object exports (defined, dynamic symbol table), demangled, one per line.
std::vector<std::string> exported_symbols(const fs::path& so) {
  const Command c = run("nm -DC --defined-only " + quoted(so));
  std::vector<std::string> symbols;
  std::istringstream lines(c.output);
  for (std::string line; std::getline(lines, line);) {
    if (line.size() > 19) symbols.push_back(line.substr(19));  // "ADDRESS T name"
  }
  return symbols;
}

class Package : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test_folder("package"));
    prefix_ = new fs::path(*dir_ / "prefix");
    install_ =
        run("cmake --install " + quoted(TEXWARP_BINARY_DIR) + " --component client --prefix " + quoted(*prefix_));
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete prefix_;
  }
  void SetUp() override { ASSERT_EQ(install_.status, 0) << install_.output; }

  static fs::path* dir_;
  static fs::path* prefix_;
  static Command install_;
};
fs::path* Package::dir_ = nullptr;
fs::path* Package::prefix_ = nullptr;
Command Package::install_;

TEST_F(Package, InstallsHeadersLibraryConfigAndPkgConfig) {
  const fs::path p = *prefix_;
  EXPECT_TRUE(fs::exists(p / "include/texwarp/client/client.hpp"));
  EXPECT_TRUE(fs::exists(p / "include/texwarp/client/job_json.hpp"));
  EXPECT_TRUE(fs::exists(p / "include/texwarp/proto/job_spec.hpp"));
  EXPECT_FALSE(fs::exists(p / "include/texwarp/proto/job_spec_codec.hpp"));  // the codec stays inside
  EXPECT_TRUE(fs::exists(p / "lib/cmake/texwarp_client/texwarp_clientConfig.cmake"));
  EXPECT_TRUE(fs::exists(p / "lib/cmake/texwarp_client/texwarp_clientConfigVersion.cmake"));
  EXPECT_TRUE(fs::exists(p / "lib/pkgconfig/texwarp_client.pc"));
  EXPECT_TRUE(fs::exists(p / "lib/libtexwarp_client.a"));
  // No installed header names Boost or nlohmann-json, and none includes one: the whole public API, preprocessed,
  // opens no file of either.
  for (const auto& entry : fs::recursive_directory_iterator(p / "include")) {
    if (!entry.is_regular_file()) continue;
    const std::string text = read_file(entry.path());
    EXPECT_THAT(text, Not(HasSubstr("#include <nlohmann"))) << entry.path();
    EXPECT_THAT(text, Not(HasSubstr("#include <boost"))) << entry.path();
  }
  const Command trace =
      run("c++ -std=c++17 -fsyntax-only -H -I" + quoted(p / "include") + " " + quoted(kConsumerSource / "main.cpp"));
  ASSERT_EQ(trace.status, 0) << trace.output;
  EXPECT_THAT(trace.output, HasSubstr("texwarp/client/client.hpp"));
  EXPECT_THAT(trace.output, Not(HasSubstr("nlohmann")));
  EXPECT_THAT(trace.output, Not(HasSubstr("boost")));
  // The exported target states what its headers need, so that a consumer's compiler is asked for C++17 at least.
  const std::string targets = read_file(p / "lib/cmake/texwarp_client/texwarpClientTargets.cmake");
  EXPECT_THAT(targets, HasSubstr("INTERFACE_COMPILE_FEATURES \"cxx_std_17\""));
}

// Compiles each of `headers` (relative to `include`) alone, in a translation unit of its own in `units` (named for
// the header), as C++17 with the warnings plugin builds turn into errors; two compilers at a time. Status 0 when
// every one compiles.
Command compile_each_as_cxx17(const fs::path& include, const std::vector<std::string>& headers, const fs::path& units) {
  fs::create_directories(units);
  std::string list;
  for (const auto& h : headers) {
    std::string name = h;
    std::replace(name.begin(), name.end(), '/', '_');
    std::ofstream(units / (name + ".cpp")) << "#include <" << h << ">\n";
    list += (units / (name + ".cpp")).string() + "\n";
  }
  std::ofstream(units / "list.txt") << list;
  return run("xargs -P 2 -n 1 c++ -std=c++17 -Wall -Wextra -Wpedantic -Werror -fsyntax-only -I" + quoted(include) +
             " <" + quoted(units / "list.txt"));
}

// Plug-in hosts (Maya, Houdini, Nuke: the VFX Reference Platform) compile as C++17: each installed header, included
// alone, compiles as C++17.
TEST_F(Package, EveryInstalledHeaderCompilesAloneAsCxx17) {
  const fs::path include = *prefix_ / "include";
  std::vector<std::string> headers;
  for (const auto& entry : fs::recursive_directory_iterator(include)) {
    if (entry.is_regular_file()) headers.push_back(fs::relative(entry.path(), include).string());
  }
  std::sort(headers.begin(), headers.end());
  EXPECT_GT(headers.size(), 25u);  // the client's headers and proto's type headers
  EXPECT_NE(std::find(headers.begin(), headers.end(), "texwarp/client/client.hpp"), headers.end());
  const Command c = compile_each_as_cxx17(include, headers, *dir_ / "header-units");
  EXPECT_EQ(c.status, 0) << c.output;

  // The control: the same check refuses a header that only C++20 compiles (a defaulted comparison).
  fs::create_directories(*dir_ / "control/texwarp");
  std::ofstream(*dir_ / "control/texwarp/cxx20.hpp")
      << "#pragma once\nstruct P {\n  int x;\n  friend bool operator==(const P&, const P&) = default;\n};\n";
  const Command control = compile_each_as_cxx17(*dir_ / "control", {"texwarp/cxx20.hpp"}, *dir_ / "control-units");
  EXPECT_NE(control.status, 0) << control.output;
  EXPECT_THAT(control.output, HasSubstr("only available with"));
}

// The consumer project built twice, with CMAKE_CXX_STANDARD 17 and 20; the plugin checked in its C++17 build.
TEST_F(Package, FindPackageConsumerRunsAJobAndItsPluginExportsNothingOfTheLibrary) {
  ServerProcess server(*dir_ / "data-cmake");
  for (const int standard : {17, 20}) {
    SCOPED_TRACE("CMAKE_CXX_STANDARD " + std::to_string(standard));
    const fs::path build = *dir_ / ("consumer-build-" + std::to_string(standard));
    const Command configure =
        run("cmake -S " + quoted(kConsumerSource) + " -B " + quoted(build) +
            " -G Ninja -DCMAKE_BUILD_TYPE=Release -DCMAKE_CXX_STANDARD=" + std::to_string(standard) +
            " -DCMAKE_PREFIX_PATH=" + quoted(*prefix_) + launcher_flag());
    ASSERT_EQ(configure.status, 0) << configure.output;
    const Command built = run("cmake --build " + quoted(build));
    ASSERT_EQ(built.status, 0) << built.output;
    check_consumer_run(build / "texwarp_consumer", standard, server, *dir_ / ("cmake-run-" + std::to_string(standard)));
  }

  // The plugin: only its own entry point and what its own code instantiates; nothing of Boost, nlohmann-json or
  // the library's internals (1,792 symbols, 1,205 of them Boost's, before hidden visibility).
  const fs::path plugin = *dir_ / "consumer-build-17" / "texwarp_plugin.so";
  const auto symbols = exported_symbols(plugin);
  EXPECT_THAT(symbols, ::testing::Contains("texwarp_plugin_run"));
  EXPECT_LT(symbols.size(), 20u) << ::testing::PrintToString(symbols);
  for (const auto& s : symbols) {
    EXPECT_THAT(s, Not(HasSubstr("boost"))) << s;
    EXPECT_THAT(s, Not(HasSubstr("nlohmann"))) << s;
    EXPECT_THAT(s, Not(HasSubstr("texwarp::client::Client::"))) << s;
  }
  // And it works, loaded as a DCC loads a plugin.
  void* handle = ::dlopen(plugin.c_str(), RTLD_NOW | RTLD_LOCAL);
  ASSERT_NE(handle, nullptr) << ::dlerror();
  using PluginRun = int (*)(const char*, const char*, const char*);
  const auto plugin_run = reinterpret_cast<PluginRun>(::dlsym(handle, "texwarp_plugin_run"));
  ASSERT_NE(plugin_run, nullptr);
  const std::string job = image_job().dump();
  EXPECT_EQ(plugin_run(server.url().c_str(), job.c_str(), (*dir_ / "plugin-out").c_str()), 2);  // 2 files fetched
  EXPECT_TRUE(fs::exists(*dir_ / "plugin-out" / "warped.png"));
  ::dlclose(handle);
}

// The same program compiled by hand with pkg-config's flags, as C++17 and as C++20.
TEST_F(Package, PkgConfigConsumerRunsAJob) {
  const std::string env = "PKG_CONFIG_PATH=" + quoted(*prefix_ / "lib/pkgconfig") + " ";
  const Command flags = run(env + "pkg-config --cflags --libs texwarp_client");
  ASSERT_EQ(flags.status, 0) << flags.output;
  EXPECT_THAT(flags.output, HasSubstr("-ltexwarp_client"));
  EXPECT_THAT(flags.output, Not(HasSubstr("-std=")));  // the consumer's standard is the consumer's to choose
  ServerProcess server(*dir_ / "data-pc");
  for (const int standard : {17, 20}) {
    SCOPED_TRACE("-std=c++" + std::to_string(standard));
    const fs::path program = *dir_ / ("pkg-config-consumer-" + std::to_string(standard));
    const Command built =
        run("c++ -std=c++" + std::to_string(standard) + " -O1 " + quoted(kConsumerSource / "main.cpp") + " -o " +
            quoted(program) + " $(" + env + "pkg-config --cflags --libs texwarp_client)");
    ASSERT_EQ(built.status, 0) << built.output;
    check_consumer_run(program, standard, server, *dir_ / ("pc-run-" + std::to_string(standard)));
  }
}

// The C++ client snippet of docs/dcc.md (the first ```cpp block after "## The C++ client library") is a complete
// program: it compiles and links against the installed package as it stands in the docs.
TEST_F(Package, DocsSnippetCompiles) {
  const std::string readme = read_file(fs::path(TEXWARP_SOURCE_DIR) / "docs" / "dcc.md");
  const auto section = readme.find("## The C++ client library");
  ASSERT_NE(section, std::string::npos);
  const auto open = readme.find("```cpp\n", section);
  ASSERT_NE(open, std::string::npos);
  const auto close = readme.find("```\n", open + 7);
  ASSERT_NE(close, std::string::npos);
  const std::string snippet = readme.substr(open + 7, close - open - 7);
  EXPECT_THAT(snippet, HasSubstr("int main("));
  std::ofstream(*dir_ / "readme_snippet.cpp") << snippet;
  const std::string env = "PKG_CONFIG_PATH=" + quoted(*prefix_ / "lib/pkgconfig") + " ";
  const Command built =
      run("c++ -std=c++20 -Wall -Werror " + quoted(*dir_ / "readme_snippet.cpp") + " -o " +
          quoted(*dir_ / "readme_snippet") + " $(" + env + "pkg-config --cflags --libs texwarp_client)");
  EXPECT_EQ(built.status, 0) << built.output << "\nsnippet:\n" << snippet;
}

// A configure of the repository that can see none of the packages the server and the method need: with the client
// only it succeeds (and looked none of them up), without it fails. The client-only build is the shared variant:
// its SONAME is versioned, it exports texwarp's symbols only, and the consumer project builds against it and runs.
TEST(ClientOnly, ConfiguresBuildsAndInstallsASharedLibraryWithoutTheServersPackages) {
  const fs::path dir = test_folder("client-only");
  // Every package a full configure looks up beyond the compiler, Threads, Boost and nlohmann-json (PostgreSQL's
  // libpqxx through PkgConfig).
  const std::vector<std::string> packages = {"OpenImageIO", "Eigen3", "OpenCL", "SQLite3",       "OpenSSL",
                                             "PkgConfig",   "CLI11",  "GTest",  "tinyobjloader", "benchmark"};
  std::string hidden_packages;
  for (const auto& p : packages) hidden_packages += " -DCMAKE_DISABLE_FIND_PACKAGE_" + p + "=ON";
  const std::string source = " -S " + quoted(TEXWARP_SOURCE_DIR) + " -G Ninja -DCMAKE_BUILD_TYPE=Release";

  // The control: the full configure needs what is hidden.
  const Command full = run("cmake" + source + " -B " + quoted(dir / "full") + hidden_packages);
  EXPECT_NE(full.status, 0) << full.output;
  EXPECT_THAT(full.output, HasSubstr("CMAKE_DISABLE_FIND_PACKAGE_"));

  const fs::path build = dir / "build";
  const Command configure = run("cmake" + source + " -B " + quoted(build) + hidden_packages +
                                " -DTEXWARP_CLIENT_ONLY=ON -DTEXWARP_CLIENT_SHARED=ON" + launcher_flag());
  ASSERT_EQ(configure.status, 0) << configure.output;
  // None of them was even looked up: CMake lists each switch as unused, and the cache holds none of their paths.
  const auto unused = configure.output.find("Manually-specified variables were not used by the project");
  ASSERT_NE(unused, std::string::npos) << configure.output;
  for (const auto& p : packages) {
    EXPECT_THAT(configure.output.substr(unused), HasSubstr("CMAKE_DISABLE_FIND_PACKAGE_" + p + "\n"));
  }
  const std::string cache = read_file(build / "CMakeCache.txt");
  for (const char* path : {"OpenImageIO_DIR", "Eigen3_DIR", "OpenCL_LIBRARY", "SQLite3_LIBRARY", "CLI11_DIR"}) {
    EXPECT_THAT(cache, Not(HasSubstr(path)));
  }
  const Command built = run("cmake --build " + quoted(build) + " --target texwarp_client");  // what is installed
  ASSERT_EQ(built.status, 0) << built.output;
  const fs::path prefix = dir / "prefix";
  const Command installed = run("cmake --install " + quoted(build) + " --prefix " + quoted(prefix));
  ASSERT_EQ(installed.status, 0) << installed.output;

  const Command soname = run("readelf -d " + quoted(prefix / "lib/libtexwarp_client.so"));
  EXPECT_THAT(soname.output, HasSubstr("Library soname: [libtexwarp_client.so.0.1]"));
  EXPECT_TRUE(fs::exists(prefix / "lib/libtexwarp_client.so.0.1"));
  EXPECT_TRUE(fs::exists(prefix / "lib/libtexwarp_client.so.0.1.0"));
  EXPECT_FALSE(fs::exists(prefix / "lib/libtexwarp_proto.a"));  // inside the shared library
  const auto symbols = exported_symbols(prefix / "lib/libtexwarp_client.so.0.1.0");
  EXPECT_GT(symbols.size(), 20u);                                             // the API is there ...
  for (const auto& s : symbols) EXPECT_EQ(s.rfind("texwarp::", 0), 0u) << s;  // ... and nothing else
  EXPECT_THAT(symbols, ::testing::Contains(HasSubstr("texwarp::client::Client::wait(")));
  EXPECT_THAT(symbols, ::testing::Contains(HasSubstr("texwarp::client::parse_job(")));
  EXPECT_THAT(symbols, ::testing::Contains(HasSubstr("texwarp::proto::JsonPath::str")));

  const fs::path consumer = dir / "consumer-build";
  const Command consumer_configure = run("cmake -S " + quoted(kConsumerSource) + " -B " + quoted(consumer) +
                                         " -G Ninja -DCMAKE_PREFIX_PATH=" + quoted(prefix) + launcher_flag());
  ASSERT_EQ(consumer_configure.status, 0) << consumer_configure.output;
  const Command consumer_built = run("cmake --build " + quoted(consumer));
  ASSERT_EQ(consumer_built.status, 0) << consumer_built.output;
  const Command needed = run("readelf -d " + quoted(consumer / "texwarp_consumer"));
  EXPECT_THAT(needed.output, HasSubstr("Shared library: [libtexwarp_client.so.0.1]"));
  ServerProcess server(dir / "data");
  check_consumer_run(consumer / "texwarp_consumer", 17, server, dir / "run");  // the project's default: C++17
  fs::remove_all(dir);
}

}  // namespace
}  // namespace texwarp::testing
