#pragma once
// Progress a person can follow while long commands run: on a terminal one line redrawn in place
// (a bar, what is done of what, the rate, the ETA); elsewhere (a pipe, a log file) plain lines,
// one at most every few seconds and one at the end, so logs stay readable. --quiet silences both.
//
// The formatting is pure (format_progress) so that tests check the text without a terminal.

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace penumbra {

struct ProgressState {
  std::string label;      // e.g. "render cornell-occluders"
  double done = 0;        // in `unit`s
  double total = 0;       // 0: unknown (no bar, no ETA)
  std::string unit;       // e.g. "spp", "s compute", "jobs"
  double elapsed = 0;     // wall seconds since the start
  double rate = 0;        // units per wall second (0: not known yet)
  std::string rate_unit;  // shown after the rate, e.g. "spp/s"; empty: "<unit>/s"
  std::string extra;      // appended as is, e.g. "MRSE 0.012"
};

// The line for `state`. On a terminal (`tty`) it starts with a bar of `bar_width` cells and is cut
// to `columns` characters; plain lines have no bar. Examples:
//   [##########----------]  50%  8/16 spp  12.5 spp/s  ETA 0.6 s  render box
//   render box: 8/16 spp (50%), 12.5 spp/s, ETA 0.6 s
std::string format_progress(const ProgressState& state, bool tty, int columns = 100,
                            int bar_width = 24);

// "0.6 s", "1 min 05 s", "2 h 03 min".
std::string format_duration(double seconds);

// A farm job's progress as `watch` and `submit --wait` show it: the fields of its status
// (penumbra.v1.JobStatus) it reads, copied so that this library needs no protobuf.
struct JobProgress {
  std::string job_id;
  std::string state;  // its name, e.g. "running"
  bool done = false;  // finished with its whole budget
  uint32_t spp_budget = 0;
  double seconds_budget = 0;
  uint32_t passes_complete = 0;
  uint32_t tiles_complete = 0, tiles_total = 0;
  uint64_t tasks_complete = 0, tasks_total = 0, tasks_leased = 0;
  double compute_seconds = 0, wall_seconds = 0;
  std::optional<double> mrse;  // against the job's reference, when it has one
};

// The state to show: tasks done of the total for an spp budget, compute seconds of the budget
// for a seconds one (short of it until the job is done: a spent budget still waits for the tasks
// in flight); the rate in those units per wall second of the job (so the ETA holds for a job
// that started before the watch); the spp, their rate, tiles, tasks leased, the MRSE and the
// state as extra, e.g. "8 spp, 4 spp/s, tiles 1/4, leased 2, MRSE 0.0123, running".
ProgressState job_progress_state(const JobProgress& job);

// The MRSE of the jobs running now (a batch's: label and MRSE so far), at most `shown` of them:
// "MRSE sa 0.0123, bsdf 0.0456 (+2 more)"; empty when there is none.
std::string running_mrse_text(const std::vector<std::pair<std::string, double>>& running,
                              size_t shown = 3);

enum class ProgressMode { Auto, Terminal, Plain, Quiet };

class ProgressReporter {
 public:
  // Auto: Terminal when `out` is a terminal, else Plain. `plain_interval` is the least wall time
  // between two plain lines.
  explicit ProgressReporter(std::string label, ProgressMode mode = ProgressMode::Auto,
                            std::FILE* out = stderr, double plain_interval = 2.0);
  ~ProgressReporter();

  // Reports `done` of `total` (0: unknown) units; the rate is measured from the calls (or given).
  // `elapsed`: the work's own wall seconds when it started before this reporter (else its age).
  void update(double done, double total, const std::string& unit, const std::string& extra = "",
              std::optional<double> rate = std::nullopt, const std::string& rate_unit = "",
              std::optional<double> elapsed = std::nullopt);
  // A message between progress lines (the bar is cleared first and redrawn by the next update).
  void note(const std::string& message);
  // Clears the bar on a terminal; prints the last state as a plain line once.
  void finish();

  bool terminal() const { return mode_ == ProgressMode::Terminal; }
  bool quiet() const { return mode_ == ProgressMode::Quiet; }
  double elapsed() const;

 private:
  void clear_line();

  std::string label_;
  ProgressMode mode_;
  std::FILE* out_;
  double plain_interval_;
  std::chrono::steady_clock::time_point start_;
  double last_draw_ = -1e9;
  bool drawn_ = false;  // a terminal line is on screen
  bool finished_ = false;
  std::string last_plain_;
  ProgressState last_;
  bool has_last_ = false;
};

}  // namespace penumbra
