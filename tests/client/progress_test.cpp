// Progress lines: the text on a terminal (a bar, cut to the width) and elsewhere (plain lines, no
// control characters), the ETA from the rate, and what the reporter writes in each mode.
#include "client/progress.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace penumbra {
namespace {

std::string read_back(std::FILE* file) {
  std::fflush(file);
  std::rewind(file);
  std::string text;
  char chunk[4096];
  for (size_t got; (got = std::fread(chunk, 1, sizeof chunk, file)) > 0;) text.append(chunk, got);
  return text;
}

ProgressState half_done() {
  ProgressState state;
  state.label = "render box";
  state.done = 8;
  state.total = 16;
  state.unit = "spp";
  state.elapsed = 0.64;
  state.rate = 12.5;
  state.rate_unit = "spp/s";
  state.extra = "3.2 Msamples/s";
  return state;
}

TEST(Progress, TerminalLineHasBarPercentRateAndEta) {
  // 8 more spp at 12.5 spp/s: 0.64 s.
  EXPECT_EQ(format_progress(half_done(), true, 200, 20),
            "[##########----------]  50%  8/16 spp  12.5 spp/s  ETA 0.6 s  3.2 Msamples/s  "
            "render box");
  // Cut to the terminal's width.
  EXPECT_EQ(format_progress(half_done(), true, 30, 20), "[##########----------]  50%  8");
}

TEST(Progress, PlainLineHasNoBarNorControlCharacters) {
  std::string line = format_progress(half_done(), false);
  EXPECT_EQ(line, "render box: 8/16 spp (50%), 12.5 spp/s, ETA 0.6 s, 3.2 Msamples/s");
  for (char c : line) EXPECT_GE(static_cast<unsigned char>(c), 0x20) << line;
}

TEST(Progress, DoneUnknownTotalAndDurations) {
  ProgressState state = half_done();
  state.done = 16;
  state.elapsed = 75;
  EXPECT_EQ(format_progress(state, false),
            "render box: 16/16 spp (100%), 12.5 spp/s, done in 1 min 15 s, 3.2 Msamples/s");
  state.total = 0;  // unknown: no percentage, no ETA
  state.extra.clear();
  EXPECT_EQ(format_progress(state, false), "render box: 16 spp, 12.5 spp/s");
  EXPECT_EQ(format_progress(state, true, 100), "16 spp  12.5 spp/s  render box");
  EXPECT_EQ(format_duration(0.25), "0.2 s");
  EXPECT_EQ(format_duration(42), "42 s");
  EXPECT_EQ(format_duration(3725), "1 h 02 min");
  EXPECT_EQ(format_duration(-1), "?");
}

TEST(Progress, PlainReporterWritesLinesAtMostEveryIntervalAndTheLast) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressReporter reporter("job", ProgressMode::Plain, file, 3600);
    for (int done = 1; done <= 10; ++done) reporter.update(done, 10, "passes", "", 2.0);
    reporter.finish();
  }
  // The first update and the completed one; finish does not repeat it.
  EXPECT_EQ(read_back(file),
            "job: 1/10 passes (10%), 2 passes/s, ETA 4.5 s\n"
            "job: 10/10 passes (100%), 2 passes/s, done in 0.0 s\n");
  std::fclose(file);
}

TEST(Progress, ElapsedOfWorkThatStartedEarlier) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressReporter reporter("batch-1", ProgressMode::Plain, file);
    reporter.update(3, 3, "jobs", "", 0.1, "jobs/s", 30.0);
  }
  EXPECT_EQ(read_back(file), "batch-1: 3/3 jobs (100%), 0.1 jobs/s, done in 30 s\n");
  std::fclose(file);
}

TEST(Progress, TerminalReporterRedrawsInPlaceAndClears) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressReporter reporter("job", ProgressMode::Terminal, file);
    reporter.update(5, 10, "passes", "", 2.0);
    reporter.note("a message");
    reporter.update(10, 10, "passes", "", 2.0);
    reporter.finish();
  }
  std::string text = read_back(file);
  EXPECT_EQ(text.rfind("\r\033[K[", 0), 0u) << text;
  EXPECT_NE(text.find(" 50%  5/10 passes  2 passes/s  ETA 2.5 s  job"), std::string::npos) << text;
  EXPECT_NE(text.find("\r\033[Ka message\n"), std::string::npos) << text;
  // finish: the bar is cleared and the last state stays as a plain line.
  EXPECT_NE(text.find("\r\033[Kjob: 10/10 passes (100%)"), std::string::npos) << text;
  std::fclose(file);
}

TEST(Progress, QuietWritesNothing) {
  std::FILE* file = std::tmpfile();
  ASSERT_NE(file, nullptr);
  {
    ProgressReporter reporter("job", ProgressMode::Quiet, file);
    reporter.update(5, 10, "passes");
    reporter.note("hidden");
    reporter.finish();
  }
  EXPECT_EQ(read_back(file), "");
  std::fclose(file);
}

}  // namespace
}  // namespace penumbra
