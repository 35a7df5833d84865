// Progress lines: the text (format_progress) and where it goes (ProgressReporter).

#include "client/progress.h"

#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace penumbra {

namespace {

// 3 significant digits, without exponent for the sizes progress shows.
std::string number(double value) {
  char text[32];
  double magnitude = std::abs(value);
  if (magnitude >= 100 || value == std::floor(value))
    std::snprintf(text, sizeof text, "%.0f", value);
  else if (magnitude >= 10)
    std::snprintf(text, sizeof text, "%.1f", value);
  else if (magnitude >= 1)
    std::snprintf(text, sizeof text, "%.2f", value);
  else
    std::snprintf(text, sizeof text, "%.3g", value);
  return text;
}

int terminal_columns(std::FILE* out) {
  winsize size{};
  if (ioctl(fileno(out), TIOCGWINSZ, &size) == 0 && size.ws_col > 20) return size.ws_col;
  return 100;
}

}  // namespace

std::string format_duration(double seconds) {
  char text[48];
  if (!std::isfinite(seconds) || seconds < 0) return "?";
  if (seconds < 60) {
    std::snprintf(text, sizeof text, "%.*f s", seconds < 10 ? 1 : 0, seconds);
  } else if (seconds < 3600) {
    long whole = std::lround(seconds);
    std::snprintf(text, sizeof text, "%ld min %02ld s", whole / 60, whole % 60);
  } else {
    long minutes = std::lround(seconds / 60);
    std::snprintf(text, sizeof text, "%ld h %02ld min", minutes / 60, minutes % 60);
  }
  return text;
}

std::string format_progress(const ProgressState& state, bool tty, int columns, int bar_width) {
  const bool bounded = state.total > 0;
  const double fraction = bounded ? std::clamp(state.done / state.total, 0.0, 1.0) : 0.0;
  std::string amount = number(state.done);
  if (bounded) amount.append("/").append(number(state.total));
  if (!state.unit.empty()) amount.append(" ").append(state.unit);
  std::string rate;
  if (state.rate > 0)
    rate = number(state.rate) + " " +
           (state.rate_unit.empty() ? (state.unit.empty() ? "/s" : state.unit + "/s")
                                    : state.rate_unit);
  std::string eta;
  if (bounded && state.rate > 0 && state.done < state.total)
    eta = "ETA " + format_duration((state.total - state.done) / state.rate);
  else if (bounded && state.done >= state.total)
    eta = "done in " + format_duration(state.elapsed);

  // Rounded down: 100% only once everything is done (a job with a last task still leased to a
  // dead worker is at 99%, not 100%).
  const double percent_value = std::floor(100 * fraction);
  char percent[16] = "";
  if (bounded) std::snprintf(percent, sizeof percent, "%3.0f%%", percent_value);
  std::string line;
  if (tty) {
    if (bounded) {
      int filled = int(std::floor(fraction * bar_width));
      line.append("[").append(size_t(filled), '#').append(size_t(bar_width - filled), '-');
      line.append("] ").append(percent).append("  ");
    }
    line += amount;
    for (const std::string* part : {&std::as_const(rate), &std::as_const(eta), &state.extra})
      if (!part->empty()) line += "  " + *part;
    if (!state.label.empty()) line += "  " + state.label;
    if (columns > 0 && int(line.size()) > columns) line.resize(size_t(columns));
    return line;
  }
  line = state.label.empty() ? amount : state.label + ": " + amount;
  if (bounded) {
    std::snprintf(percent, sizeof percent, "%.0f%%", percent_value);
    line += std::string(" (") + percent + ")";
  }
  for (const std::string* part : {&std::as_const(rate), &std::as_const(eta), &state.extra})
    if (!part->empty()) line += ", " + *part;
  return line;
}

ProgressState job_progress_state(const JobProgress& job) {
  ProgressState state;
  state.label = job.job_id;
  state.elapsed = job.wall_seconds;
  const double wall = job.wall_seconds;
  if (job.spp_budget > 0) {
    state.done = double(job.tasks_complete);
    state.total = double(job.tasks_total);
    state.unit = "tasks";
  } else {
    state.done =
        job.done ? job.seconds_budget : std::min(job.compute_seconds, 0.99 * job.seconds_budget);
    state.total = job.seconds_budget;
    state.unit = "compute s";
  }
  if (job.done) state.done = state.total;
  state.rate = wall > 0 ? state.done / wall : 0;
  state.rate_unit = job.spp_budget > 0 ? "tasks/s" : "compute s/s";
  std::string extra = std::to_string(job.passes_complete) + " spp";
  if (wall > 0) extra += ", " + number(job.passes_complete / wall) + " spp/s";
  extra += ", tiles " + std::to_string(job.tiles_complete) + "/" + std::to_string(job.tiles_total);
  if (job.tasks_leased > 0) extra += ", leased " + std::to_string(job.tasks_leased);
  if (job.mrse) {
    char text[32];
    std::snprintf(text, sizeof text, "%.4g", *job.mrse);
    extra += std::string(", MRSE ") + text;
  }
  state.extra = extra + ", " + job.state;
  return state;
}

std::string running_mrse_text(const std::vector<std::pair<std::string, double>>& running,
                              size_t shown) {
  if (running.empty()) return "";
  std::string text = "MRSE";
  for (size_t i = 0; i < running.size() && i < shown; ++i) {
    char value[32];
    std::snprintf(value, sizeof value, "%.4g", running[i].second);
    text += (i ? ", " : " ") + running[i].first + " " + value;
  }
  if (running.size() > shown) text += " (+" + std::to_string(running.size() - shown) + " more)";
  return text;
}

ProgressReporter::ProgressReporter(std::string label, ProgressMode mode, std::FILE* out,
                                   double plain_interval)
    : label_(std::move(label)),
      mode_(mode),
      out_(out),
      plain_interval_(plain_interval),
      start_(std::chrono::steady_clock::now()) {
  if (mode_ == ProgressMode::Auto)
    mode_ = isatty(fileno(out_)) ? ProgressMode::Terminal : ProgressMode::Plain;
}

ProgressReporter::~ProgressReporter() {
  if (drawn_) clear_line();
}

double ProgressReporter::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void ProgressReporter::update(double done, double total, const std::string& unit,
                              const std::string& extra, std::optional<double> rate,
                              const std::string& rate_unit, std::optional<double> elapsed) {
  if (mode_ == ProgressMode::Quiet) return;
  ProgressState state;
  state.label = label_;
  state.done = done;
  state.total = total;
  state.unit = unit;
  const double age = this->elapsed();
  state.elapsed = elapsed ? *elapsed : age;
  state.rate = rate ? *rate : (state.elapsed > 0 ? done / state.elapsed : 0);
  state.rate_unit = rate_unit;
  state.extra = extra;
  last_ = state;
  has_last_ = true;
  const bool complete = total > 0 && done >= total;
  if (mode_ == ProgressMode::Terminal) {
    // At most 10 redraws a second, and always the last one.
    if (age - last_draw_ < 0.1 && !complete) return;
    last_draw_ = age;
    std::fprintf(out_, "\r\033[K%s",
                 format_progress(state, true, terminal_columns(out_) - 1).c_str());
    std::fflush(out_);
    drawn_ = true;
    return;
  }
  if (age - last_draw_ < plain_interval_ && !complete) return;
  std::string line = format_progress(state, false);
  if (line == last_plain_) return;
  last_draw_ = age;
  last_plain_ = line;
  std::fprintf(out_, "%s\n", line.c_str());
  std::fflush(out_);
}

void ProgressReporter::note(const std::string& message) {
  if (mode_ == ProgressMode::Quiet) return;
  if (drawn_) clear_line();
  std::fprintf(out_, "%s\n", message.c_str());
  std::fflush(out_);
  last_draw_ = -1e9;  // redraw the bar at the next update
}

void ProgressReporter::finish() {
  if (finished_ || mode_ == ProgressMode::Quiet) return;
  finished_ = true;
  if (drawn_) clear_line();
  if (!has_last_) return;
  std::string line = format_progress(last_, false);
  if (mode_ == ProgressMode::Plain && line == last_plain_) return;
  std::fprintf(out_, "%s\n", line.c_str());
  std::fflush(out_);
}

void ProgressReporter::clear_line() {
  std::fprintf(out_, "\r\033[K");
  std::fflush(out_);
  drawn_ = false;
}

}  // namespace penumbra
