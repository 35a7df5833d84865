// The table `penumbra batch run` prints: no header or label is cut, whatever the lengths of the
// region names and method labels, and every value sits under its header.
#include "client/batch_summary.h"

#include <gtest/gtest.h>

#include <sstream>
#include <string>
#include <vector>

namespace penumbra {
namespace {

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

TEST(BatchSummary, HeadersAndLabelsAreNeverCutAndValuesSitUnderThem) {
  const std::string long_label = "bsdf+line-sa:u+line-sa:v/smooth-with-a-long-label";
  nlohmann::json index = {
      {"regions", {{{"name", "penumbra"}}, {{"name", "red-wall-shadow-of-the-tall-box"}}}},
      {"methods",
       {{{"label", "sa"},
         {"budget_seconds", 2.0},
         {"runs",
          {{{"spp", 12},
            {"compute_seconds", 2.01},
            {"repeat", 0},
            {"equal_time", true},
            {"errors",
             {{{"region", "image"}, {"mrse", 0.0123}},
              {{"region", "penumbra"}, {"mrse", 0.25}},
              {{"region", "red-wall-shadow-of-the-tall-box"}, {"mrse", 1.5}}}}},
           {{"spp", 2},
            {"compute_seconds", 0.3},
            {"repeat", 0},
            {"equal_time", false},
            {"errors", nlohmann::json::array()}}}}},
        {{"label", long_label},
         {"runs",
          {{{"spp", 16},
            {"compute_seconds", 12.5},
            {"repeat", 1},
            {"errors",
             {{{"region", "image"}, {"mrse", 0.5}},
              {{"region", "penumbra"}, {"mrse", 123456.0}},
              {{"region", "red-wall-shadow-of-the-tall-box"}, {"mrse", 2e-7}}}}}}}},
        {{"label", "line-bd16:rand"}, {"error", "line-bd16 needs Lambert or Phong materials"}}}}};
  const std::vector<std::string> lines = lines_of(batch_summary_table(index));
  ASSERT_EQ(lines.size(), 4u) << "a header, two runs (not the calibration), the refusal";
  const std::string& header = lines[0];
  for (const std::string text : {"method", "spp", "compute s", "MRSE image", "MRSE penumbra",
                                 "MRSE red-wall-shadow-of-the-tall-box"})
    EXPECT_NE(header.find(text), std::string::npos) << text << " in " << header;
  // Right-aligned columns: each value ends where its header ends.
  auto column_end = [&](const std::string& text) { return header.find(text) + text.size(); };
  auto ends_at = [](const std::string& line, const std::string& value, size_t end) {
    const size_t at = line.find(value);
    return at != std::string::npos && at + value.size() == end;
  };
  EXPECT_TRUE(ends_at(lines[1], "0.0123", column_end("MRSE image"))) << lines[1];
  EXPECT_TRUE(ends_at(lines[1], "1.5", column_end("MRSE red-wall-shadow-of-the-tall-box")))
      << lines[1];
  EXPECT_TRUE(ends_at(lines[2], "1.235e+05", column_end("MRSE penumbra"))) << lines[2];
  EXPECT_TRUE(ends_at(lines[2], "12.50", column_end("compute s"))) << lines[2];
  // The long label whole, and the columns after it still aligned.
  EXPECT_EQ(lines[2].rfind(long_label + " ", 0), 0u) << lines[2];
  EXPECT_TRUE(ends_at(lines[2], "2e-07", column_end("MRSE red-wall-shadow-of-the-tall-box")))
      << lines[2];
  EXPECT_NE(lines[3].find("refused: line-bd16 needs Lambert"), std::string::npos) << lines[3];
}

}  // namespace
}  // namespace penumbra
