// A progress bar on stderr, shown only when stderr is a terminal and the work has already taken about
// a second, so quick runs and redirected output stay clean.
#pragma once

#include <chrono>
#include <string>

#include "lodkit/io.h"

namespace lod::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  void update(double fraction);
  // A ReadOptions whose progress callback drives this bar, and whose warnings go to stderr (warn).
  ReadOptions read_options();
  // Prints "lodkit: warning: MESSAGE" on a line of its own, below the bar.
  void warn(const std::string& message);

 private:
  std::string label_;
  std::chrono::steady_clock::time_point start_;
  bool enabled_ = false;
  bool shown_ = false;
  int last_percent_ = -1;
};

// Seconds elapsed since `start`.
double seconds_since(std::chrono::steady_clock::time_point start);

}  // namespace lod::cli
