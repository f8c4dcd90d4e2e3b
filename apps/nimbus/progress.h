// A progress bar on stderr (only when stderr is a terminal): percent, samples/s, ETA.
#pragma once

#include <chrono>
#include <cstdint>
#include <mutex>
#include <string>

namespace nimbus::cli {

class ProgressBar {
 public:
  explicit ProgressBar(std::string label, bool enabled);
  // Thread-safe; redraws at most ~10 times a second.
  void update(int64_t done, int64_t total, int64_t samples);
  // A line for a phase without a fraction (the integrator's set-up): the label, the text, the time.
  void stage(const std::string& text);
  // Ends the line (if anything was drawn).
  void finish();

 private:
  std::string label_;
  bool enabled_ = false, drawn_ = false;
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_, last_;
};

bool stderr_is_terminal();

}  // namespace nimbus::cli
