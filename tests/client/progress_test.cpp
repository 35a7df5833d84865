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

// The last tasks still leased (to a worker that may have died): not 100% until they are done,
// and the leased ones are shown.
TEST(Progress, LeasedButUnfinishedTasksAreShownAndNotCountedAsDone) {
  JobProgress job;
  job.job_id = "job-7";
  job.state = "running";
  job.spp_budget = 128;
  job.passes_complete = 120;
  job.tiles_complete = 23;
  job.tiles_total = 24;
  job.tasks_complete = 383;
  job.tasks_total = 384;
  job.tasks_leased = 1;
  job.wall_seconds = 4;
  const std::string plain = format_progress(job_progress_state(job), false);
  EXPECT_NE(plain.find("383/384 tasks (99%)"), std::string::npos) << plain;
  EXPECT_NE(plain.find("leased 1"), std::string::npos) << plain;
  const std::string bar = format_progress(job_progress_state(job), true, 200, 10);
  EXPECT_EQ(bar.rfind("[#########-]  99%  383/384 tasks", 0), 0u) << bar;
  job.tasks_complete = 384;
  job.tasks_leased = 0;
  job.done = true;
  EXPECT_NE(format_progress(job_progress_state(job), false).find("(100%)"), std::string::npos);
}

TEST(Progress, FarmJobShowsTasksOrComputeSecondsWithSppTilesAndMrse) {
  JobProgress job;
  job.job_id = "job-4";
  job.state = "running";
  job.spp_budget = 16;
  job.passes_complete = 8;
  job.tiles_complete = 1;
  job.tiles_total = 4;
  job.tasks_complete = 10;
  job.tasks_total = 40;
  job.tasks_leased = 2;
  job.compute_seconds = 3;
  job.wall_seconds = 2;
  job.mrse = 0.0123;
  // 10 of 40 tasks in the job's 2 wall seconds: 5 tasks/s, 30 more take 6 s.
  EXPECT_EQ(format_progress(job_progress_state(job), false),
            "job-4: 10/40 tasks (25%), 5 tasks/s, ETA 6.0 s, 8 spp, 4 spp/s, tiles 1/4, leased 2, "
            "MRSE 0.0123, running");
  EXPECT_EQ(format_progress(job_progress_state(job), true, 200, 8),
            "[##------]  25%  10/40 tasks  5 tasks/s  ETA 6.0 s  8 spp, 4 spp/s, tiles 1/4, "
            "leased 2, MRSE 0.0123, running  job-4");

  // A seconds budget counts compute seconds, short of the budget until the job is done.
  JobProgress timed = job;
  timed.spp_budget = 0;
  timed.seconds_budget = 4;
  timed.compute_seconds = 5;  // spent, tasks still in flight
  timed.mrse.reset();
  timed.tasks_leased = 0;
  ProgressState state = job_progress_state(timed);
  EXPECT_EQ(state.unit, "compute s");
  EXPECT_DOUBLE_EQ(state.done, 0.99 * 4);
  EXPECT_EQ(state.extra, "8 spp, 4 spp/s, tiles 1/4, running");
  timed.done = true;
  timed.state = "done";
  EXPECT_EQ(format_progress(job_progress_state(timed), false),
            "job-4: 4/4 compute s (100%), 2 compute s/s, done in 2.0 s, 8 spp, 4 spp/s, tiles 1/4, "
            "done");
  // Queued: no total yet, no bar.
  JobProgress queued;
  queued.job_id = "job-5";
  queued.state = "queued";
  queued.spp_budget = 8;
  EXPECT_EQ(format_progress(job_progress_state(queued), false),
            "job-5: 0 tasks, 0 spp, tiles 0/0, queued");
}

TEST(Progress, RunningMrseListsAFewJobs) {
  EXPECT_EQ(running_mrse_text({}), "");
  EXPECT_EQ(running_mrse_text({{"sa", 0.0123}}), "MRSE sa 0.0123");
  EXPECT_EQ(running_mrse_text({{"a", 1}, {"b", 2}, {"c", 0.5}, {"d", 4}, {"e", 5}}),
            "MRSE a 1, b 2, c 0.5 (+2 more)");
}

}  // namespace
}  // namespace penumbra
