// Progress of the long commands (progress.hpp).
#include "dyncal_host/common/progress.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>

namespace dyncal::host {
namespace {

ProgressSink& sink() {
  static ProgressSink s;
  return s;
}

}  // namespace

void set_progress_sink(ProgressSink s) {
  sink() = std::move(s);
}

ProgressSink terminal_progress(std::ostream& out) {
  using Clock = std::chrono::steady_clock;
  struct Line {
    std::string task;
    Clock::time_point start, last;
    size_t width = 0;
  };
  auto line = std::make_shared<Line>();
  return [&out, line](const ProgressUpdate& u) {
    const auto now = Clock::now();
    if (u.finished) {
      if (line->width > 0) out << "\r" << std::string(line->width, ' ') << "\r" << std::flush;
      *line = Line{};
      return;
    }
    if (u.task != line->task) {  // a new task: drawn once it has run a quarter of a second
      line->task = u.task;
      line->start = now;
      return;
    }
    if (now - line->start < std::chrono::milliseconds(250) || now - line->last < std::chrono::milliseconds(100)) return;
    line->last = now;
    const double f = u.total > 0 ? std::clamp(u.done / u.total, 0.0, 1.0) : 0.0;
    const int bar = 24, filled = static_cast<int>(std::lround(f * bar));
    char numbers[96];
    std::snprintf(numbers, sizeof numbers, " %3d%% %.0f/%.0f%s%s", static_cast<int>(std::lround(100 * f)), u.done,
                  u.total, u.unit.empty() ? "" : " ", u.unit.c_str());
    const std::string text = u.task + " [" + std::string(static_cast<size_t>(filled), '#') +
                             std::string(static_cast<size_t>(bar - filled), '.') + "]" + numbers;
    out << "\r" << text << (text.size() < line->width ? std::string(line->width - text.size(), ' ') : "") << std::flush;
    line->width = std::max(line->width, text.size());
  };
}

Progress::Progress(std::string task, double total, std::string unit) {
  state_.task = std::move(task);
  state_.unit = std::move(unit);
  state_.total = total;
  std::lock_guard<std::mutex> lock(mutex_);
  report(false);
}

Progress::~Progress() {
  std::lock_guard<std::mutex> lock(mutex_);
  report(true);
}

void Progress::advance(double n) {
  std::lock_guard<std::mutex> lock(mutex_);
  state_.done += n;
  report(false);
}

void Progress::update(double done) {
  std::lock_guard<std::mutex> lock(mutex_);
  state_.done = done;
  report(false);
}

void Progress::report(bool finished) {
  const ProgressSink& s = sink();
  if (!s) return;
  const double step = state_.total > 0 ? state_.total / 100.0 : 1.0;
  if (!finished && reported_ >= 0 && state_.done - reported_ < step) return;
  reported_ = state_.done;
  state_.finished = finished;
  s(state_);
}

}  // namespace dyncal::host
