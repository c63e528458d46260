// The host-kernel contract's prelude: every table entry is defined exactly once, its literal reads back to the
// table's value in the variant's precision, the kernel sources define none of the names and use them all, the
// Dormand–Prince tableau is core's (and is one), and the program builds with the prelude in every variant.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "kernel_contract.hpp"
#include "kernel_prelude.hpp"
#include "kernel_source.hpp"
#include "opencl_device.hpp"
#include "pathline_program.hpp"
#include "texwarp/core/dormand_prince.hpp"

namespace texwarp::kernels_detail {
namespace {

const KernelVariant kVariants[] = {{false, false}, {false, true}, {true, false}, {true, true}};

// name → literal of every "#define NAME literal" line; flags (no literal) map to "".
std::multimap<std::string, std::string> defines(const std::string& prelude) {
  std::multimap<std::string, std::string> out;
  std::istringstream in(prelude);
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("#define ", 0) != 0) continue;
    const std::string rest = line.substr(8);
    const std::size_t space = rest.find(' ');
    out.emplace(rest.substr(0, space), space == std::string::npos ? "" : rest.substr(space + 1));
  }
  return out;
}

// The reals of a literal: "(0.9f)", "{1.0, -2.5}", "{{0.0f}, {0.2f, 0.0f}}"; float literals end in f.
std::vector<double> parse_reals(std::string text, bool double_precision) {
  for (char& c : text) {
    if (c == '(' || c == ')' || c == '{' || c == '}' || c == ',') c = ' ';
  }
  std::istringstream in(text);
  std::vector<double> out;
  std::string token;
  while (in >> token) {
    EXPECT_EQ(token.back() == 'f', !double_precision) << token;
    if (token.back() == 'f') token.pop_back();
    EXPECT_NE(token.find_first_of(".e"), std::string::npos) << token << " is not a floating literal";
    out.push_back(double_precision ? std::strtod(token.c_str(), nullptr) : std::strtof(token.c_str(), nullptr));
  }
  return out;
}

TEST(KernelPrelude, EveryEntryIsDefinedExactlyOnceWithTheVariantsFlags) {
  std::set<std::string_view> names;
  for (const KernelConstant& c : kKernelConstants) EXPECT_TRUE(names.insert(c.name).second) << c.name;
  for (const KernelVariant v : kVariants) {
    const auto d = defines(kernel_prelude(v));
    for (const KernelConstant& c : kKernelConstants) EXPECT_EQ(d.count(std::string(c.name)), 1u) << c.name;
    EXPECT_EQ(d.count("TW_DOUBLE"), v.double_precision ? 1u : 0u);
    EXPECT_EQ(d.count("TW_JACOBIAN"), v.jacobian ? 1u : 0u);
    EXPECT_EQ(d.size(), kKernelConstants.size() + v.double_precision + v.jacobian);
  }
}

TEST(KernelPrelude, ValuesReadBackInTheVariantsPrecision) {
  for (const bool dp : {false, true}) {
    const auto d = defines(kernel_prelude({dp, false}));
    for (const KernelConstant& c : kKernelConstants) {
      const std::string literal = d.find(std::string(c.name))->second;
      const double value = dp ? c.double_value : c.float_value;
      switch (c.kind) {
        case KernelConstant::Kind::kInt:
          EXPECT_EQ(std::stoll(literal), static_cast<long long>(value)) << c.name;
          EXPECT_EQ(literal.find_first_not_of("0123456789"), std::string::npos) << c.name << " " << literal;
          break;
        case KernelConstant::Kind::kReal: {
          const std::vector<double> read = parse_reals(literal, dp);
          ASSERT_EQ(read.size(), 1u) << c.name;
          EXPECT_EQ(read[0], dp ? value : static_cast<double>(static_cast<float>(value))) << c.name << " " << literal;
          break;
        }
        case KernelConstant::Kind::kRealArray: {
          const std::vector<double> read = parse_reals(literal, dp);
          ASSERT_EQ(read.size(), c.values.size()) << c.name;
          for (std::size_t i = 0; i < read.size(); ++i) {
            const double want = dp ? c.values[i] : static_cast<double>(static_cast<float>(c.values[i]));
            EXPECT_EQ(read[i], want) << c.name << "[" << i << "]";
          }
          if (c.row != 0) {  // one inner brace per row
            const std::size_t rows = static_cast<std::size_t>(std::count(literal.begin(), literal.end(), '{')) - 1;
            EXPECT_EQ(rows * c.row, c.values.size()) << c.name;
          }
          break;
        }
      }
    }
  }
  // Precision-dependent entries differ where the table says so.
  EXPECT_NE(kernel_prelude({false, false}).find("#define TW_ZMAX (1e+15f)"), std::string::npos);
  EXPECT_NE(kernel_prelude({true, false}).find("#define TW_ZMAX (1e+150)"), std::string::npos);
  EXPECT_NE(kernel_prelude({true, false}).find("#define TW_MIN_STEP (1e-12)"), std::string::npos);
}

TEST(KernelPrelude, TheKernelSourcesUseEveryNameAndDefineNone) {
  const std::string source(pathline_program_source());
  for (const KernelConstant& c : kKernelConstants) {
    const std::regex use("\\b" + std::string(c.name) + "\\b");
    EXPECT_TRUE(std::regex_search(source, use)) << c.name << " is in the contract but no kernel uses it";
    const std::regex define("#\\s*define\\s+" + std::string(c.name) + "\\b");
    EXPECT_FALSE(std::regex_search(source, define)) << c.name << " is defined in kernels/cl again";
  }
}

TEST(KernelPrelude, TheDormandPrinceTableauIsCoresAndConsistent) {
  using namespace dormand_prince;
  const auto d = defines(kernel_prelude({true, false}));
  const std::vector<double> a = parse_reals(d.find("TW_DP_A")->second, true);
  const std::vector<double> c = parse_reals(d.find("TW_DP_C")->second, true);
  const std::vector<double> e = parse_reals(d.find("TW_DP_E")->second, true);
  ASSERT_EQ(a.size(), static_cast<std::size_t>(kStages * (kStages - 1)));
  ASSERT_EQ(c.size(), static_cast<std::size_t>(kStages));
  double e_sum = 0.0;
  for (int s = 0; s < kStages; ++s) {
    EXPECT_EQ(c[s], kC[s]);
    double row = 0.0;
    for (int j = 0; j < kStages - 1; ++j) {
      EXPECT_EQ(a[s * (kStages - 1) + j], kA[s][j]);
      row += a[s * (kStages - 1) + j];
    }
    EXPECT_NEAR(row, c[s], 1e-14) << "stage " << s << ": the row sums of A are the stage times";
    EXPECT_EQ(e[s], kE[s]);
    e_sum += e[s];
  }
  EXPECT_NEAR(e_sum, 0.0, 1e-15) << "both embedded solutions' weights sum to 1";
  EXPECT_EQ(std::stoi(d.find("TW_DP_STAGES")->second), kStages);
}

TEST(KernelPrelude, TheProgramBuildsWithItInEveryVariant) {
  const DeviceHandle device = select_device({});
  for (const KernelVariant v : kVariants) {
    if (v.double_precision && !device.has_fp64) continue;
    SCOPED_TRACE(std::string(v.double_precision ? "double" : "float") + (v.jacobian ? ", Jacobian" : ""));
    EXPECT_NO_THROW(pathline_program(device, v));
    EXPECT_EQ(pathline_program_text(v).rfind(kernel_prelude(v), 0), 0u);
  }
}

}  // namespace
}  // namespace texwarp::kernels_detail
