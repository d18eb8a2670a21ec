// The NRRD `data file: <pattern> <min> <max> <step>` form (a pattern with %s once reached
// snprintf and crashed the server). The pattern is parsed, never used as a format: one %d or %i
// with optional flags and width, %% as a literal; everything else refused naming the pattern.
#include <gtest/gtest.h>

#include "core/volume_io.h"
#include "test_util.h"

using namespace peakcast;

namespace {

// Writes slices `names` of 2x2 uint8 each and a detached header using `pattern lo hi step`.
std::filesystem::path stack(const test::TempDir& d, const std::vector<std::string>& names, const std::string& spec) {
  for (size_t k = 0; k < names.size(); ++k) test::write_file(d / names[k], std::string(4, char(10 * (k + 1))));
  test::write_file(d / "h.nhdr", "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 " + std::to_string(names.size()) +
                                     "\nencoding: raw\ndata file: " + spec + " 2\n");
  return d / "h.nhdr";
}

std::string refusal(const std::filesystem::path& header) {
  try {
    load_volume(header);
  } catch (const VolumeError& e) {
    return e.what();
  }
  return "accepted";
}

TEST(NrrdPattern, AcceptsIntegerConversionsWithFlagsAndWidth) {
  struct Case {
    std::string spec;
    std::vector<std::string> files;
  } cases[] = {
      {"quarter.%d 1 3 1", {"quarter.1", "quarter.2", "quarter.3"}},
      {"slice%03d.raw 0 2 1", {"slice000.raw", "slice001.raw", "slice002.raw"}},
      {"s%i 8 10 1", {"s8", "s9", "s10"}},
      {"s%2d 3 1 -1", {"s 3", "s 2", "s 1"}},
      {"p%%_%d 0 1 1", {"p%_0", "p%_1"}},
      {"n%+d -1 1 1", {"n-1", "n+0", "n+1"}},
      {"l%-3d| 7 8 1", {"l7  |", "l8  |"}},
  };
  for (const auto& c : cases) {
    test::TempDir d;
    const auto h = stack(d, c.files, c.spec);
    Volume v = load_volume(h);
    EXPECT_EQ(v.dims()[2], int64_t(c.files.size())) << c.spec;
  }
}

TEST(NrrdPattern, RefusesAnythingButOneIntegerConversion) {
  for (std::string spec :
       {"q.%s 1 9 1", "q.%n 1 9 1", "q.%x 1 9 1", "q.%d%d 1 9 1", "q.%ld 1 9 1", "q.%.3d 1 9 1", "q.%*d 1 9 1",
        "q.%99d 1 9 1", "q.%p 1 9 1", "q.% 1 9 1", "q. 1 9 1", "q.%d% 1 9 1", "q.%lld 1 9 1", "q.%1$d 1 9 1"}) {
    test::TempDir d;
    test::write_file(d / "h.nhdr",
                     "NRRD0004\ntype: uint8\ndimension: 3\nsizes: 2 2 9\nencoding: raw\ndata file: " + spec + "\n");
    const std::string why = refusal(d / "h.nhdr");
    EXPECT_NE(why.find("data file pattern"), std::string::npos) << spec << ": " << why;
    EXPECT_NE(why.find("h.nhdr"), std::string::npos) << "names the file: " << why;
  }
}

}  // namespace
