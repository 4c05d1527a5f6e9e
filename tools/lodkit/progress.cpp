#include "progress.h"

#include <unistd.h>

#include <cstdio>

namespace lod::cli {

ProgressBar::ProgressBar(std::string label)
    : label_(std::move(label)), start_(std::chrono::steady_clock::now()), enabled_(::isatty(2) == 1) {}

ProgressBar::~ProgressBar() {
  if (shown_) std::fprintf(stderr, "\r\033[2K");
}

void ProgressBar::update(double fraction) {
  if (!enabled_) return;
  if (!shown_ && seconds_since(start_) < 1.0) return;
  int percent = int(fraction * 100.0 + 0.5);
  if (percent == last_percent_) return;
  last_percent_ = percent;
  shown_ = true;
  constexpr int width = 30;
  int filled = percent * width / 100;
  std::string bar(size_t(filled), '#');
  bar.resize(width, '.');
  std::fprintf(stderr, "\r%s [%s] %3d%%", label_.c_str(), bar.c_str(), percent);
  std::fflush(stderr);
}

ReadOptions ProgressBar::read_options() {
  ReadOptions options;
  if (enabled_) options.progress = [this](double f) { update(f); };
  options.warning = [this](const std::string& message) { warn(message); };
  return options;
}

void ProgressBar::warn(const std::string& message) {
  if (shown_) std::fprintf(stderr, "\r\033[2K");
  std::fprintf(stderr, "lodkit: warning: %s\n", message.c_str());
  last_percent_ = -1;  // (the bar is drawn again at its next update)
}

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace lod::cli
